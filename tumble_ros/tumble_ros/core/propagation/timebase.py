"""
Moved to :mod:`tumble_ros.core.model.timebase` (the scenario's time base is part of the model).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.model.timebase import *  # noqa: F401,F403
from tumble_ros.core.model.timebase import __all__  # noqa: F401

"""
Moved to :mod:`tumble_ros.core.model.lightcurve_settings` (inputs of the scenario).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.model.lightcurve_settings import *  # noqa: F401,F403
from tumble_ros.core.model.lightcurve_settings import __all__  # noqa: F401

"""
Moved to :mod:`tumble_ros.core.model.user_files` (reading the model's input files).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.model.user_files import *  # noqa: F401,F403
from tumble_ros.core.model.user_files import __all__  # noqa: F401

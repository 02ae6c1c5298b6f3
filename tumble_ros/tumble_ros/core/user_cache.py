"""
Moved to :mod:`tumble_ros.core.compiling.user_cache` (the compile machinery's own folder).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.compiling.user_cache import *  # noqa: F401,F403
from tumble_ros.core.compiling.user_cache import __all__  # noqa: F401

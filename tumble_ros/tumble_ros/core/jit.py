"""
Moved to :mod:`tumble_ros.core.compiling.jit` (the compile machinery's own folder).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.compiling.jit import *  # noqa: F401,F403
from tumble_ros.core.compiling.jit import __all__  # noqa: F401

"""
Moved to :mod:`tumble_ros.core.units` (constants and time units: the bottom of core's numerics).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.units import *  # noqa: F401,F403
from tumble_ros.core.units import __all__  # noqa: F401

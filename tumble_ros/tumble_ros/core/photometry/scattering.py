"""
Moved to :mod:`tumble_ros.core.model.scattering` (the surface's scattering laws: model inputs).

This module keeps the old import path working: it re-exports the public names.
"""
from tumble_ros.core.model.scattering import *  # noqa: F401,F403
from tumble_ros.core.model.scattering import __all__  # noqa: F401

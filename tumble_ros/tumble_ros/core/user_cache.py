"""The user's cache folder of this package (numba's compiled loops, the Dask engine's wrapper)."""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ['user_cache_dir']


def user_cache_dir() -> Path:
    """
    Return this package's folder in the user's cache (not created here).

    ``$XDG_CACHE_HOME/tumble_ros`` where that variable is set and not empty (the XDG base
    directory specification), else ``~/.cache/tumble_ros``. What is kept there can be deleted
    at any time: it is made again when needed.
    """
    return Path(os.environ.get('XDG_CACHE_HOME') or Path.home() / '.cache') / 'tumble_ros'

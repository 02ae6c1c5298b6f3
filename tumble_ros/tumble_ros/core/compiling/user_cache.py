"""The user's cache folder of this package (numba's compiled loops, the Dask engine's wrapper)."""
from __future__ import annotations

import os
from pathlib import Path
import tempfile

__all__ = ['user_cache_dir']


def user_cache_dir() -> Path:
    """
    Return this package's folder in the user's cache (absolute; not created here).

    ``$XDG_CACHE_HOME/tumble_ros`` where that variable holds an absolute path (the XDG base
    directory specification ignores a relative one), else ``~/.cache/tumble_ros``; where the
    home folder cannot be told either (no ``HOME``, no password entry), a folder of this user
    in the temporary folder. What is kept there can be deleted at any time: it is made again
    when needed.
    """
    xdg = os.environ.get('XDG_CACHE_HOME', '')
    if os.path.isabs(xdg):
        return Path(xdg) / 'tumble_ros'
    home = os.path.expanduser('~')
    if os.path.isabs(home):
        return Path(home) / '.cache' / 'tumble_ros'
    return Path(tempfile.gettempdir()) / f'tumble_ros-cache-{os.getuid()}'

"""numba's cache of the compiled sources, shared by the clones of them (core.compiling.jit)."""
from __future__ import annotations

import json
import os
from pathlib import Path
import shutil
import subprocess
import sys
import time

import pytest

from tumble_ros.core import kernels
from tumble_ros.core.compiling import jit
from tumble_ros.core.compiling.user_cache import user_cache_dir

needs_numba = pytest.mark.skipif(not jit.COMPILED, reason='numba not available')
PACKAGE = Path(jit.__file__).resolve().parents[2]

#: In a fresh process: numba's cache counters of a small compiled function of kernels/.
_CALL = """
import json
from tumble_ros.core.kernels import checks
checks.collapsed(1.0, 1.0, 1.0)
print(json.dumps({'hits': sum(checks.collapsed.stats.cache_hits.values()),
                  'misses': sum(checks.collapsed.stats.cache_misses.values()),
                  'folder': checks.collapsed.stats.cache_path}))
"""


def _clone(to: Path) -> Path:
    """Copy the package's sources (no caches) to ``to``; return the folder to import it from."""
    shutil.copytree(PACKAGE, to / 'tumble_ros', ignore=shutil.ignore_patterns('__pycache__'))
    return to


def _call(root: Path, cache: Path) -> dict:
    env = {**os.environ, 'PYTHONPATH': str(root), 'XDG_CACHE_HOME': str(cache),
           'PYTHONDONTWRITEBYTECODE': '1'}
    env.pop('NUMBA_CACHE_DIR', None)
    done = subprocess.run([sys.executable, '-c', _CALL], env=env, capture_output=True,
                          text=True, timeout=300, cwd=root)
    assert done.returncode == 0, done.stderr[-3000:]
    seen: dict = json.loads(done.stdout.strip().splitlines()[-1])
    return seen


@needs_numba
def test_a_second_clone_loads_what_the_first_compiled_and_an_edit_compiles_again(tmp_path):
    cache = tmp_path / 'cache'
    first, second, edited = (_clone(tmp_path / name) for name in ('a', 'b', 'c'))
    kernel = edited / 'tumble_ros' / 'core' / 'kernels' / 'rk4.py'
    kernel.write_text(kernel.read_text() + '\n# an edit of another kernel file\n')

    compiled = _call(first, cache)
    assert (compiled['hits'], compiled['misses']) == (0, 1), compiled
    assert Path(compiled['folder']).is_relative_to(cache / 'tumble_ros' / 'numba'), compiled
    assert Path(compiled['folder']).name == 'kernels', compiled

    loaded = _call(second, cache)          # another clone, the same sources: loaded
    assert (loaded['hits'], loaded['misses']) == (1, 0), loaded
    assert loaded['folder'] == compiled['folder']

    again = _call(edited, cache)           # rk4.py edited: every kernel compiles again
    assert (again['hits'], again['misses']) == (0, 1), again
    assert again['folder'] != compiled['folder']
    assert len(list((cache / 'tumble_ros' / 'numba').iterdir())) == 2
    assert not list(first.rglob('*.nbi')) and not list(second.rglob('*.nbi'))   # none in-tree


@needs_numba
def test_the_loops_are_cached_in_the_folder_of_their_sources_hash(monkeypatch):
    monkeypatch.delenv('NUMBA_CACHE_DIR', raising=False)
    advance = kernels.loops('rk4').advance
    locator = advance._cache._impl._locator        # numba's cache internals (checked here)
    folder = Path(locator.get_cache_path())
    try:                                  # where the user's cache cannot be written: in-tree
        jit.shared_cache_root().mkdir(parents=True, exist_ok=True)
        writable = os.access(jit.shared_cache_root(), os.W_OK)
    except OSError:
        writable = False
    if not writable:
        assert folder.name == '__pycache__', folder
        return
    assert folder == jit.shared_cache_root() / jit.compiled_sources_hash().hex()[:16] / 'kernels'
    assert folder == jit.shared_cache_folder(advance.py_func.__code__.co_filename)


@needs_numba
def test_an_unwritable_cache_falls_back_to_the_sources_folder(tmp_path):
    cache = tmp_path / 'cache'
    cache.write_text('a file where the cache folder would be')    # makedirs fails under it
    root = _clone(tmp_path / 'a')
    seen = _call(root, cache)
    assert (seen['hits'], seen['misses']) == (0, 1), seen
    assert Path(seen['folder']) == root / 'tumble_ros' / 'core' / 'kernels' / '__pycache__'


def test_old_versions_are_deleted_but_the_last_used_and_the_current(tmp_path, monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    root = jit.shared_cache_root()
    current = root / jit.compiled_sources_hash().hex()[:16]
    current.mkdir(parents=True)
    now = time.time()
    ages = {f'{k:016x}': k * 3600.0 for k in range(1, 7)}   # 1 to 6 hours unused
    for name, age in ages.items():
        (root / name / 'kernels').mkdir(parents=True)
        os.utime(root / name, (now - age, now - age))
    (root / 'not-a-version').mkdir()
    os.utime(current, (now - 86400, now - 86400))           # the oldest, but the current
    deleted = jit.prune_shared_cache(keep=3)
    kept = {name for name, age in ages.items() if age <= 3 * 3600.0}   # the 3 last used
    assert {p.name for p in root.iterdir()} == {current.name, 'not-a-version'} | kept
    assert {p.name for p in deleted} == set(ages) - kept
    assert current.stat().st_mtime > now - 60                # marked used


@pytest.mark.parametrize('xdg, home, expected', [
    ('/x/cache', '/h', '/x/cache/tumble_ros'),
    ('', '/h', '/h/.cache/tumble_ros'),
    ('relative/cache', '/h', '/h/.cache/tumble_ros'),     # ignored, as the XDG spec says
    ('', '~', None),                                      # no home known: the temporary folder
])
def test_the_users_cache_folder_is_absolute(monkeypatch, xdg, home, expected):
    import tempfile

    monkeypatch.setenv('XDG_CACHE_HOME', xdg)
    monkeypatch.setattr(os.path, 'expanduser', lambda path: path.replace('~', home, 1))
    if expected is None:
        expected = f'{tempfile.gettempdir()}/tumble_ros-cache-{os.getuid()}'
    assert user_cache_dir() == Path(expected)

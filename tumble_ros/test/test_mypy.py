"""
Type checking: mypy, with the repository's mypy.ini, over the whole package, without an error.

mypy.ini is strict on the numerical core (``tumble_ros.core``), the typed IO
(``tumble_ros.io``) and the run layer (``tumble_ros.runs``), ordinary elsewhere. The package is
checked in one run: a module's errors depend on the types of what it imports.

mypy's cache is the user's (``core.compiling.user_cache``), shared by the clones of the
repository: mypy takes a module's cached result only where the source's hash is the one it
checked (a clone has other paths and times, so it hashes each file), and checks again what
changed and what depends on it. A fresh clone's check then takes ~1 s instead of ~18 s
(benchmarks/HISTORY.md).
"""
from __future__ import annotations

from pathlib import Path
import re
import shutil
import subprocess
import sys
import tempfile

from tumble_ros.core.compiling.user_cache import user_cache_dir

ROOT = Path(__file__).resolve().parents[2]
#: mypy's incremental cache, shared by the clones (its own Python-version folders inside).
MYPY_CACHE = user_cache_dir() / 'mypy'


def run_mypy(*args: str, root: Path = ROOT) -> subprocess.CompletedProcess:
    """Run the venv's mypy on ``root`` as its mypy.ini says, with the shared cache."""
    return subprocess.run([sys.executable, '-m', 'mypy', '--config-file', str(root / 'mypy.ini'),
                           '--cache-dir', str(MYPY_CACHE), *args],
                          cwd=root, capture_output=True, text=True, timeout=900)


def test_the_whole_package_type_checks():
    proc = run_mypy()
    summary = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else proc.stderr
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]
    checked = re.match(r'^Success: no issues found in (\d+) source files$', summary)
    assert checked and int(checked[1]) > 90, summary   # the package, not an empty selection
    # (here, not in a test of its own: two tests on two workers would both check cold)
    check_another_clone_with_the_shared_cache()


def check_another_clone_with_the_shared_cache() -> None:
    """
    Check a copy of the package elsewhere, one module changed to a type error: mypy reports it.

    The cache holds that module as this checkout has it (the check just run; the same path
    inside the package, another folder, a newer time). The module changed is one nothing
    imports (``cli/warmup.py``): mypy drops the cache of a module with an error and of its
    importers, so the next check here redoes only it.
    """
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp)
        # (what mypy sees from the root: the package, and the interface package's folders)
        for folder in (Path('tumble_ros', 'tumble_ros'), Path('tumble_ros_interfaces')):
            shutil.copytree(ROOT / folder, copy / folder,
                            ignore=shutil.ignore_patterns('__pycache__'))
        shutil.copy(ROOT / 'mypy.ini', copy / 'mypy.ini')
        changed = copy / 'tumble_ros' / 'tumble_ros' / 'cli' / 'warmup.py'
        changed.write_text(changed.read_text() + "\n_NOT_AN_INT: int = 'a'\n")
        proc = run_mypy(root=copy)
    assert proc.returncode == 1, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert re.search(r'^tumble_ros/tumble_ros/cli/warmup\.py:\d+: error: Incompatible types',
                     proc.stdout, re.M), proc.stdout[-3000:]
    assert 'Found 1 error in 1 file' in proc.stdout, proc.stdout[-3000:]


def test_strict_modules_are_checked_strictly(tmp_path):
    """A core module with an unannotated function fails; the same in analysis/ passes."""
    config = (ROOT / 'mypy.ini').read_text()
    assert re.search(r'^\[mypy-tumble_ros\.core\.\*,tumble_ros\.io\.\*,tumble_ros\.runs\.\*\]$',
                     config, re.M)
    for folder, fails in (('core', True), ('io', True), ('runs', True), ('analysis', False)):
        module = tmp_path / 'tumble_ros' / folder / 'sample.py'
        module.parent.mkdir(parents=True, exist_ok=True)
        for init in (tmp_path / 'tumble_ros' / '__init__.py', module.parent / '__init__.py'):
            init.write_text('')
        module.write_text('def untyped(x):\n    return x\n')
        proc = subprocess.run([sys.executable, '-m', 'mypy', '--config-file',
                               str(ROOT / 'mypy.ini'), '-p', f'tumble_ros.{folder}.sample'],
                              cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert (proc.returncode != 0) == fails, (folder, proc.stdout)

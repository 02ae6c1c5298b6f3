"""
Type checking: mypy, with the repository's mypy.ini, over the whole package, without an error.

mypy.ini is strict on the numerical core (``tumble_ros.core``), the typed IO
(``tumble_ros.io``) and the run layer (``tumble_ros.runs``), ordinary elsewhere. The package is
checked in one run: a module's errors depend on the types of what it imports.
"""
from __future__ import annotations

from pathlib import Path
import re
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[2]


def run_mypy(*args: str) -> subprocess.CompletedProcess:
    """Run the venv's mypy as configured by mypy.ini (extra ``args`` appended)."""
    return subprocess.run([sys.executable, '-m', 'mypy', '--config-file', str(ROOT / 'mypy.ini'),
                           *args], cwd=ROOT, capture_output=True, text=True, timeout=900)


def test_the_whole_package_type_checks():
    proc = run_mypy()
    summary = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else proc.stderr
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]
    checked = re.match(r'^Success: no issues found in (\d+) source files$', summary)
    assert checked and int(checked[1]) > 90, summary   # the package, not an empty selection


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

"""
numba imported without coverage by the main job when none is measured (numba_without_coverage).

In a fresh process each: without ``coverage`` imported, numba's coverage support is imported
with it hidden (numba then reports no coverage, and does not import it), and a later
``import coverage`` works; with ``coverage`` imported (a measured run), numba's support sees
it as before. The main job calls it before its imports (tests/test_main_job.py runs the job),
and so does every executable's start (``run_executable``) but the recorder's, which imports no
numba.
"""
import os
from pathlib import Path
import subprocess
import sys

import pytest
from test_main_job import main_job_then


def _env():
    """Return this environment without pytest-cov's: no coverage started in the child."""
    return {key: value for key, value in os.environ.items() if not key.startswith('COV_CORE_')}


def _python(code):
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=300, env=_env(), cwd=Path(__file__).parent)


def test_numba_is_imported_without_coverage_when_none_is_measured():
    pytest.importorskip('coverage')                     # (installed with the test tools)
    done = _python('import sys\n'
                   'from tumble_ros.__main__ import numba_without_coverage\n'
                   'numba_without_coverage()\n'
                   'import numba.misc.coverage_support as support\n'
                   'print("coverage" in sys.modules, support.coverage_available)\n'
                   'import coverage\n'
                   'print(coverage.Coverage is not None)\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ['False', 'False', 'True']


def test_a_measured_coverage_is_left_as_it_was():
    pytest.importorskip('coverage')
    done = _python('import sys, coverage\n'
                   'from tumble_ros.__main__ import numba_without_coverage\n'
                   'numba_without_coverage()\n'
                   'import numba.misc.coverage_support as support\n'
                   'print(sys.modules["coverage"] is coverage, support.coverage_available)\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ['True', 'True']


def test_the_main_job_imports_numba_without_coverage(tmp_path):
    pytest.importorskip('coverage')
    done = main_job_then(tmp_path, 'import numba.misc.coverage_support as support\n'
                                   'print(code, "coverage" in sys.modules, '
                                   'support.coverage_available)\n', env=_env())
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-3:] == ['0', 'False', 'False']


@pytest.mark.parametrize('name', ['sim', 'comparator', 'recorder'])
def test_a_node_imports_numba_without_coverage_and_the_recorder_none(name):
    """run_executable imports a node with numba but without coverage; the recorder, no numba."""
    pytest.importorskip('coverage')
    done = _python('import sys\n'
                   'from tumble_ros.__main__ import _imported, EXECUTABLES, WITHOUT_NUMBA\n'
                   f'_imported({name!r}, EXECUTABLES[{name!r}].split(":")[0])\n'
                   f'print({name!r} in WITHOUT_NUMBA, "numba" in sys.modules, '
                   '"coverage" in sys.modules)\n')
    assert done.returncode == 0, done.stderr
    without = name == 'recorder'
    assert done.stdout.split() == [str(without), str(not without), 'False']

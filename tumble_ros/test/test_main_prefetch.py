"""
The main job's imports off its path (tumble_ros.__main__: Prefetch, numba_without_coverage).

Prefetch imports its modules in a thread from start() on, once; a failing import is left to
be raised where the module is used; nothing starts after join(). The main job starts it at the
recording's first block: the modules of PREFETCH are imported by that thread, and none of them
by the imports before the recording (scipy.special: the spin state imports it where it is
used). numba_without_coverage imports numba's coverage support without coverage when no
coverage is measured (a later `import coverage` works), and leaves it as it was when coverage
is imported.
"""
import os
from pathlib import Path
import subprocess
import sys
import threading

import pytest

from test_main_job import short_scenario
from tumble_ros import __main__ as entry
from tumble_ros.__main__ import main, PREFETCH, Prefetch

#: A module that records the thread importing it.
RECORDER = ('import threading\n'
            'THREAD = threading.current_thread().name\n')


def _module(tmp_path, monkeypatch, name, text):
    (tmp_path / f'{name}.py').write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, name, raising=False)
    return name


def test_the_modules_are_imported_by_the_thread_from_start_on(tmp_path, monkeypatch):
    name = _module(tmp_path, monkeypatch, 'prefetched_a', RECORDER)
    prefetch = Prefetch((name,))
    assert name not in sys.modules                      # nothing before start()
    prefetch.start()
    prefetch.start()                                    # once
    prefetch.join()
    assert sys.modules[name].THREAD == 'tumble_ros-prefetch'
    assert not [t for t in threading.enumerate() if t.name == 'tumble_ros-prefetch']


def test_a_failing_import_is_raised_where_the_module_is_used(tmp_path, monkeypatch):
    name = _module(tmp_path, monkeypatch, 'prefetched_bad', 'raise ValueError("broken module")\n')
    after = _module(tmp_path, monkeypatch, 'prefetched_after', RECORDER)
    prefetch = Prefetch((name, after))
    prefetch.start()
    prefetch.join()                                     # no error here
    assert name not in sys.modules and sys.modules[after].THREAD == 'tumble_ros-prefetch'
    with pytest.raises(ValueError, match='broken module'):
        __import__(name)


def test_nothing_starts_after_join(tmp_path, monkeypatch):
    name = _module(tmp_path, monkeypatch, 'prefetched_late', RECORDER)
    prefetch = Prefetch((name,))
    prefetch.join()
    prefetch.start()
    prefetch.join()
    assert name not in sys.modules


def test_the_main_job_prefetches_at_the_first_block(tmp_path, monkeypatch):
    name = _module(tmp_path, monkeypatch, 'prefetched_job', RECORDER)
    seen = []
    original = entry.gather_in_background if hasattr(entry, 'gather_in_background') else None
    assert original is None                             # imported by main_job, not at the top
    from tumble_ros import io
    gather_in_background = io.gather_in_background

    def gather(written, on_first_block=None):
        def first():
            seen.append(name in sys.modules)            # not imported before the first block
            on_first_block()
        return gather_in_background(written, on_first_block=first)

    monkeypatch.setattr(io, 'gather_in_background', gather)
    monkeypatch.setattr(entry, 'PREFETCH', (name,))
    scenario = short_scenario(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main([str(scenario)]) == 0
    assert seen == [False]
    assert sys.modules[name].THREAD == 'tumble_ros-prefetch'
    assert not [t for t in threading.enumerate() if t.name == 'tumble_ros-prefetch']


def _python(code):
    env = dict(os.environ)
    env.pop('COV_CORE_SOURCE', None)                    # no coverage started in the child
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=300, env=env, cwd=Path(__file__).parent)


def test_nothing_of_prefetch_is_imported_before_the_recording():
    done = _python('import sys\n'
                   'import tumble_ros.analysis.figure_pool, tumble_ros.analysis.cli\n'
                   'import tumble_ros.nodes.bringup, tumble_ros.io\n'
                   'from tumble_ros.__main__ import PREFETCH\n'
                   'print(sorted(n for n in PREFETCH if n in sys.modules))\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == '[]' and 'scipy.special' in PREFETCH


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

"""
The main job's end without the interpreter's teardown (tumble_ros.__main__.quick_exit).

In a fresh process each: the exit code is kept, what is buffered on stdout and stderr comes
out, the atexit handlers run (once), a closed stdout gives 141 as elsewhere, and with another
thread still running it returns (the usual exit joins the thread). `python -m tumble_ros` on a
short scenario ends with everything written and exit code 0; of the executables, the nodes take
this path too (a node's interpreter teardown took ~2.5 s of its stop at load 20), the others only
when a stop signal ended them (test_cli_interrupts.py).
"""
import os
from pathlib import Path
import subprocess
import sys

import pytest

from test_main_job import short_scenario
from tumble_ros.__main__ import BROKEN_PIPE_EXIT, ends_quickly, is_main_job

HANDLER = """
import atexit, sys
from tumble_ros.__main__ import quick_exit
atexit.register(lambda: open(sys.argv[1], 'a').write('handler ran\\n'))
sys.stdout.write('buffered out')     # no newline: still in the buffer
sys.stderr.write('buffered err')
"""


#: The children's environment: stdout and stderr buffered (not so under PYTHONUNBUFFERED).
ENV = {key: value for key, value in os.environ.items() if key != 'PYTHONUNBUFFERED'}


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-c', code, *args], capture_output=True, text=True,
                          timeout=120, env=ENV)


@pytest.mark.parametrize('code', [0, 3])
def test_the_code_the_buffers_and_the_atexit_handlers_are_kept(tmp_path, code):
    marker = tmp_path / 'atexit.txt'
    done = _python(HANDLER + f'quick_exit({code})\nprint("not reached")\n', str(marker))
    assert done.returncode == code
    assert done.stdout == 'buffered out' and done.stderr == 'buffered err'
    assert marker.read_text() == 'handler ran\n'             # once, not again at teardown


def test_a_closed_stdout_gives_the_broken_pipe_code(tmp_path):
    marker = tmp_path / 'atexit.txt'
    proc = subprocess.Popen([sys.executable, '-c', HANDLER + 'quick_exit(0)\n', str(marker)],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=ENV)
    proc.stdout.close()                                         # nobody reads
    assert proc.wait(timeout=120) == BROKEN_PIPE_EXIT
    assert marker.read_text() == 'handler ran\n'


def test_another_thread_running_leaves_the_usual_exit(tmp_path):
    code = ('import threading, time, sys\n'
            'from tumble_ros.__main__ import quick_exit\n'
            't = threading.Thread(target=lambda: (time.sleep(0.5), print("thread done")))\n'
            't.start()\n'
            'quick_exit(5)\n'
            'print("returned")\n'
            'sys.exit(7)\n')
    done = _python(code)
    assert done.returncode == 7
    assert done.stdout.splitlines() == ['returned', 'thread done']   # joined by the exit


def test_only_the_main_job_takes_it():
    assert is_main_job([]) and is_main_job(['fig9']) and is_main_job(['x.yaml', '--live'])
    assert not is_main_job(['bringup', '--offline']) and not is_main_job(['analyze', 'f.mcap'])
    assert not is_main_job(['--help']) and not is_main_job(['-h'])


def test_the_nodes_and_the_main_job_end_quickly_the_other_executables_not():
    assert ends_quickly([]) and ends_quickly(['fig9'])
    assert ends_quickly(['sim', '--ros-args']) and ends_quickly(['comparator'])
    assert ends_quickly(['recorder'])
    assert not ends_quickly(['bringup']) and not ends_quickly(['analyze', 'f.mcap'])
    assert not ends_quickly(['--help'])


#: A process that runs an installed script's entry (named ``sim`` or ``analyze``) with an
#: object whose __del__ marks the interpreter's teardown (module objects are freed there).
LATE = """
import sys, types
from pathlib import Path
marker, name = sys.argv.pop(1), sys.argv.pop(1)
class Late:
    def __del__(self, open=open):
        open(marker, 'a').write('teardown\\n')
late = types.ModuleType('late_marker')
late.obj = Late()
sys.modules['late_marker'] = late
sys.argv[0] = str(Path(sys.argv[0]).with_name(name))
from tumble_ros.__main__ import entry
sys.exit(entry())
"""


@pytest.mark.parametrize('name, teardown', [('sim', False), ('recorder', False),
                                            ('analyze', True)])
def test_a_node_script_ends_without_the_interpreters_teardown(tmp_path, name, teardown):
    """The console scripts' entry: a node's process skips the teardown, analyze's does not."""
    marker = tmp_path / 'teardown.txt'
    done = _python(LATE, str(marker), name, '--help')
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith('usage:')
    assert marker.exists() == teardown, marker.exists()


def test_the_main_job_ends_with_everything_written(tmp_path):
    scenario = short_scenario(tmp_path)
    done = subprocess.run([sys.executable, '-m', 'tumble_ros', str(scenario)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600, env=ENV)
    assert done.returncode == 0, done.stderr[-2000:]
    (recording,) = Path(tmp_path, 'recordings').glob('short_*.mcap')
    figures = recording.with_name(recording.stem + '_figures')
    # the figures' list, then the viewer's layout line (analysis/viewer_layouts.py)
    *_, last_figure, layout_line = done.stdout.rstrip().splitlines()
    assert last_figure.strip().endswith(str(Path('recordings') / figures.name /
                                            'spectrum_wx.png')), last_figure
    assert layout_line.startswith('viewer: ') and 'foxglove_layout.json' in layout_line
    assert all((figures / name).stat().st_size > 1000
               for name in ('omega.png', 'error.png', 'spectrum_wx.png'))

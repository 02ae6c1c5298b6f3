"""`python -m tumble_ros` (make run): bringup, then the analysis of the recording."""
from pathlib import Path
import subprocess
import sys

from tumble_ros import topics
from tumble_ros.__main__ import main
from tumble_ros.io import summarize


def short_scenario(tmp_path) -> Path:
    scenario = tmp_path / 'short.yaml'
    scenario.write_text(
        'sim:\n  ros__parameters:\n    duration: 0.2\n    output_interval: 0.002\n')
    return scenario


def main_job_then(tmp_path, probe: str, env=None) -> subprocess.CompletedProcess:
    """
    Run the main job on :func:`short_scenario` in a fresh interpreter (in ``tmp_path``).

    Then ``probe`` (Python source, with ``code`` the job's exit code and ``sys`` imported);
    its output is the last of the process's stdout.
    """
    source = ('import os, sys\n'
              f'os.chdir({str(tmp_path)!r})\n'
              'from tumble_ros.__main__ import main\n'
              f'code = main([{str(short_scenario(tmp_path))!r}])\n' + probe)
    return subprocess.run([sys.executable, '-c', source], capture_output=True, text=True,
                          timeout=300, env=env, cwd=Path(__file__).parent)


def test_main_job_records_and_analyses(tmp_path, monkeypatch, capsys):
    scenario = short_scenario(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main([str(scenario)]) == 0
    (recording,) = Path('recordings').glob('short_*.mcap')
    assert summarize(recording).topics['/' + topics.ERROR_NORM].message_count == 101
    figures = sorted(p.name
                     for p in recording.with_name(recording.stem + '_figures').glob('*.png'))
    assert 'omega.png' in figures and 'error.png' in figures
    captured = capsys.readouterr()
    assert ("comparator error (model 'paper'" in captured.out
            and f'101 samples of /{topics.ANGULAR_VELOCITY}' in captured.out)
    assert 'bringup (offline)' in captured.err    # written straight from the simulation


def test_main_job_runs_the_ros_graph_when_asked(tmp_path, monkeypatch, capsys):
    scenario = short_scenario(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main([str(scenario), '--live']) == 0
    assert 'bringup (offline)' not in capsys.readouterr().err
    (recording,) = Path('recordings').glob('short_*.mcap')
    assert summarize(recording).topics['/' + topics.ERROR_NORM].message_count == 101


def test_main_job_refuses_a_missing_scenario(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(['nowhere.yaml']) == 1
    assert 'ERROR' in capsys.readouterr().err


def test_executables_dispatch(capsys):
    assert main(['analyze', '/nonexistent.mcap']) == 1
    assert capsys.readouterr().err.startswith('ERROR')


def test_runs_started_in_the_same_second_get_their_own_files(tmp_path, monkeypatch):
    """The recording is named by the UTC second: a second run then gets _2, not a refusal."""
    from datetime import datetime

    from tumble_ros.nodes import recorder

    class Frozen(datetime):
        @classmethod
        def now(cls, tz=None):
            return datetime(2029, 4, 13, 21, 46, 0, tzinfo=tz)

    monkeypatch.setattr(recorder, 'datetime', Frozen)
    monkeypatch.chdir(tmp_path)
    first = recorder.default_output('same')
    assert str(first) == 'recordings/same_20290413T214600.mcap'
    assert first.read_bytes() == b''   # claimed: created empty, the directory too
    second = recorder.default_output('same')
    assert str(second) == 'recordings/same_20290413T214600_2.mcap'
    assert str(recorder.default_output('same')) == 'recordings/same_20290413T214600_3.mcap'


#: One main job in its own process, its clock frozen on a second (both runs of the test name
#: their recording in the same second), started when the test creates the file ``go``: the two
#: processes have imported everything by then, so they race on the name.
SAME_SECOND_RUN = """
import sys, time
from datetime import datetime
from pathlib import Path
from tumble_ros.nodes import recorder
from tumble_ros.__main__ import main
import tumble_ros.nodes.bringup  # noqa: F401  (imported before the start line)


class Frozen(datetime):
    @classmethod
    def now(cls, tz=None):
        return datetime(2029, 4, 13, 21, 46, 0, tzinfo=tz)


recorder.datetime = Frozen
Path(sys.argv[2]).touch()
while not Path('go').exists():
    time.sleep(0.001)
sys.exit(main([sys.argv[1]]))
"""


def test_two_main_jobs_in_the_same_second_both_record(tmp_path):
    """
    Two ``make run`` of one config started in the same second both record (process level).

    Each is ``python -m tumble_ros``'s main() in its own process, only the clock frozen.
    Before: one of them failed with ``ERROR: cannot record: [Errno 17] File exists`` (the name
    was checked with exists(), then created by the writer).
    """
    import os
    import subprocess
    import sys
    import time

    scenario = short_scenario(tmp_path)
    runs = []
    try:
        for k in (1, 2):
            log = open(tmp_path / f'run{k}.log', 'w')
            runs.append((subprocess.Popen(
                [sys.executable, '-c', SAME_SECOND_RUN, str(scenario), f'ready{k}'],
                cwd=tmp_path, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                start_new_session=True), log))
        deadline = time.monotonic() + 120
        while not all((tmp_path / f'ready{k}').exists() for k in (1, 2)):
            assert time.monotonic() < deadline and all(p.poll() is None for p, _ in runs), \
                [(tmp_path / f'run{k}.log').read_text() for k in (1, 2)]
            time.sleep(0.01)
        (tmp_path / 'go').touch()
        codes = [p.wait(timeout=300) for p, _ in runs]
    finally:
        for p, log in runs:
            if p.poll() is None:
                os.killpg(p.pid, 9)
                p.wait()
            log.close()
    outputs = [(tmp_path / f'run{k}.log').read_text() for k in (1, 2)]
    assert codes == [0, 0], outputs
    names = sorted(p.name for p in (tmp_path / 'recordings').glob('*.mcap'))
    assert names == ['short_20290413T214600.mcap', 'short_20290413T214600_2.mcap']
    for name in names:
        summary = summarize(tmp_path / 'recordings' / name)
        assert summary.finalised
        assert summary.topics['/' + topics.ANGULAR_VELOCITY].message_count == 101

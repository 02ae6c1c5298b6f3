"""`python -m tumble_ros` (make run): bringup, then the analysis of the recording."""
from pathlib import Path

from tumble_ros import topics
from tumble_ros.__main__ import main
from tumble_ros.io import summarize


def short_scenario(tmp_path) -> Path:
    scenario = tmp_path / 'short.yaml'
    scenario.write_text(
        'sim:\n  ros__parameters:\n    duration: 0.2\n    output_interval: 0.002\n')
    return scenario


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
    first.parent.mkdir()
    first.write_bytes(b'')
    second = recorder.default_output('same')
    assert str(second) == 'recordings/same_20290413T214600_2.mcap'
    second.write_bytes(b'')
    assert str(recorder.default_output('same')) == 'recordings/same_20290413T214600_3.mcap'

"""`python -m tumble_ros` (make run): bringup, then the analysis of the recording."""
from pathlib import Path

from tumble_ros import topics
from tumble_ros.__main__ import main
from tumble_ros.io import summarize


def test_main_job_records_and_analyses(tmp_path, monkeypatch, capsys):
    scenario = tmp_path / 'short.yaml'
    scenario.write_text(
        'sim:\n  ros__parameters:\n    duration: 0.2\n    output_interval: 0.002\n')
    monkeypatch.chdir(tmp_path)
    assert main([str(scenario)]) == 0
    (recording,) = Path('recordings').glob('short_*.mcap')
    assert summarize(recording).topics['/' + topics.ERROR_NORM].message_count == 101
    figures = sorted(p.name
                     for p in recording.with_name(recording.stem + '_figures').glob('*.png'))
    assert 'omega.png' in figures and 'error.png' in figures
    out = capsys.readouterr().out
    assert ("comparator error (model 'paper'" in out
            and f'101 samples of /{topics.ANGULAR_VELOCITY}' in out)


def test_main_job_refuses_a_missing_scenario(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(['nowhere.yaml']) == 1
    assert 'ERROR' in capsys.readouterr().err


def test_executables_dispatch(capsys):
    assert main(['analyze', '/nonexistent.mcap']) == 1
    assert capsys.readouterr().err.startswith('ERROR')

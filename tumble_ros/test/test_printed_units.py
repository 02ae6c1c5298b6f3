"""
What a person reads is in the field's units (issue 47).

The scenario's time_unit for times, rates and periods (periods in hours too), pole longitudes in
[0, 360) everywhere, a --help that is usage.
"""
import io
import math

import numpy as np
import pytest

from tumble_ros.core import parse_scenario

DAYS = ('sim:\n  ros__parameters:\n    time_unit: d\n    inertia: [1.0, 1.3, 1.8]\n'
        '    orbit_rate: 0.0\n    omega0: [0.5, 0.1, 3.0]\n    duration: 1190.0\n'
        '    output_interval: 0.25\n')
HOURS = ('/**/sim:\n  ros__parameters:\n    time_unit: h\n    inertia: [1.0, 1.3, 1.8]\n'
         '    orbit_rate: 0.0\n    omega0: [0.05, 0.01, 0.3]\n    duration: 24.0\n'
         '    output_interval: 0.05\n')


def test_python_m_tumble_ros_help_is_usage(capsys):
    from tumble_ros.__main__ import EXECUTABLES, main

    assert main(['--help']) == 0
    out = capsys.readouterr().out
    assert out.startswith('usage: python -m tumble_ros')
    for developer_note in ('quick_exit', ':class:', ':func:', '``', 'garbage collector'):
        assert developer_note not in out, developer_note
    assert all(name in out for name in EXECUTABLES)


def test_a_days_recording_is_summarised_in_days(tmp_path):
    from tumble_ros.analysis.recording import load_recording
    from tumble_ros.analysis.report import format_summary
    from tumble_ros.analysis.summary import analyze
    from tumble_ros.runs.offline import record_offline

    sc = parse_scenario(DAYS)
    record_offline(sc, tmp_path / 'days.mcap', markers=False)
    rec = load_recording(tmp_path / 'days.mcap')
    summary = analyze(rec)
    text = format_summary(summary)
    assert summary.units.time == 'd'
    assert 'rad/yr' not in text and ' yr' not in text.replace('seconds_per_year', ''), text
    assert 't = 0 .. 1190 d, duration 1190 d, dt = 0.25 d (uniform)' in text, text
    assert 'omega0 (0.5, 0.1, 3) rad/d' in text, text
    # periods: in days, and hours beside
    rotation = summary.spin.start.rotation_period
    assert summary.units.period_text(rotation) == (
        f'{rotation * 365.25:.4g} d ({rotation * 8766.0:.4g} h)')


@pytest.mark.parametrize('offline', [True, False], ids=['offline', 'live'])
def test_an_hours_run_shows_its_progress_in_hours(tmp_path, offline):
    from tumble_ros.nodes.bringup import run_bringup

    config = tmp_path / 'hours.yaml'
    config.write_text(HOURS)
    progress = io.StringIO()
    result = run_bringup(config, output=str(tmp_path / 'hours.mcap'), progress=progress,
                         offline=offline, markers=False)
    assert result.ok
    last = progress.getvalue().strip().split('\r')[-1]
    label = 'bringup (offline)' if offline else 'bringup'
    assert last.startswith(f'{label}: t = 24 / 24 h (100.0 %), 481 samples'), last
    assert ' yr' not in progress.getvalue()


def test_the_ensemble_prints_its_time_and_rates_in_the_scenario_unit(tmp_path, capsys):
    from tumble_ros.cli.ensemble import main

    config = tmp_path / 'hours.yaml'
    config.write_text(HOURS)
    assert main([str(config), '--bodies', '2', '--quiet']) == 0
    out = capsys.readouterr().out
    assert 'time: 24 h, 481 samples per body' in out, out
    assert 'final |w_perp| [rad/h]' in out and 'rad/yr' not in out, out


def test_a_pole_longitude_reads_0_to_360_in_the_text_and_the_ensemble_figure(
        tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from tumble_ros.analysis import ensemble
    from tumble_ros.analysis.display import display_units, longitude_degrees

    assert longitude_degrees(-math.pi / 2) == pytest.approx(270.0)
    assert display_units(1.0).direction_text(-math.pi / 2, 0.0).startswith('lon 270.00 deg')
    spin = {'omega': np.ones((3, 3)), 'rotation_period': np.ones(3),
            'pole_longitude': np.array([-math.pi / 2, 0.1, math.pi - 0.1]),
            'pole_latitude': np.zeros(3), 'time': 1.0, 'spin_body': np.arange(3)}

    class Store:
        status = type('Status', (), {'values': np.ones(3)})()
        sizes = {'body': 3}

    drawn = []
    monkeypatch.setattr(ensemble, 'final_spin', lambda *args: spin)
    monkeypatch.setattr(ensemble, 'ensemble_units', lambda ds: display_units(1.0))
    monkeypatch.setattr(Figure, 'savefig', lambda fig, path: drawn.append(fig))
    ensemble.plot_ensemble(Store(), tmp_path)
    (fig,) = drawn
    longitudes = fig.axes[3].collections[0].get_offsets()[:, 0]
    np.testing.assert_allclose(longitudes, [270.0, math.degrees(0.1), 180 - math.degrees(0.1)])

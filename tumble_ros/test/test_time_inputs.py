"""
Every time a person types is in the scenario's own time_unit, or carries its unit (issue 47).

A bare number is in the scenario's (or the recording's) ``time_unit``; ``12h``, ``3d``,
``30min``, ``90s``, ``2yr`` state their own (``core.units.parse_time``): the ensemble's
``--duration``, ``--output-interval``, ``--step``, ``--impact-duration`` (and its rates per
unit), ``analyze --at``. The node's ``real_time_factor`` and the impact service:
test_node_sim.py.
"""
import numpy as np
import pytest

from tumble_ros.core import parse_scenario
from tumble_ros.core.units import HOURS_PER_YEAR, parse_time, time_parts

HOURS = ('/**/sim:\n  ros__parameters:\n    time_unit: h\n    inertia: [1.0, 1.3, 1.8]\n'
         '    orbit_rate: 0.0\n    omega0: [0.05, 0.01, 0.3]\n    duration: 24.0\n'
         '    output_interval: 0.5\n')


@pytest.mark.parametrize('text, unit, hours', [
    ('12', 'h', 12.0), (12, 'h', 12.0), ('12h', 'yr', 12.0), ('0.5d', 'h', 12.0),
    ('720min', 's', 12.0), ('43200 s', 'yr', 12.0), ('1yr', 'h', HOURS_PER_YEAR),
    (' 1.2e1h ', 'd', 12.0), ('+12', 'h', 12.0), ('-3h', 'yr', -3.0),
])
def test_a_time_is_read_in_its_own_unit_or_the_scenarios(text, unit, hours):
    assert parse_time(text, unit) * HOURS_PER_YEAR == pytest.approx(hours, rel=1e-15)


@pytest.mark.parametrize('text, phrase', [
    ('12 hours', "--x: '12 hours' is not a time: a number in h (the scenario's time_unit) or a "
                 'number and its unit, one of yr, d, h, min, s: 12h, 3d, 30min, 90s, 2yr'),
    ('h', "--x: 'h' is not a time"), ('', "--x: '' is not a time"),
    ('nan', "--x: 'nan' is not a time"), ('1e999', "--x: must be a finite time, got '1e999'"),
    (float('inf'), '--x: must be a finite time, got inf'),
])
def test_what_is_not_a_time_is_refused_naming_the_input(text, phrase):
    with pytest.raises(ValueError) as err:
        parse_time(text, 'h', '--x')
    assert str(err.value).startswith(phrase), str(err.value)
    with pytest.raises(ValueError):
        time_parts(text, '--x')


def test_the_ensemble_reads_its_times_in_the_scenarios_unit(tmp_path, capsys):
    """An hours scenario: --duration 12 is 12 h (it was 12 yr), 0.5d and 720min too."""
    from tumble_ros.cli.ensemble import main

    config = tmp_path / 'hours.yaml'
    config.write_text(HOURS)
    t = {}
    for duration, interval in (('12', '1'), ('0.5d', '60min'), ('12h', '3600s')):
        out = tmp_path / f'{duration}.npz'
        assert main([str(config), '--bodies', '2', '--quiet', '--duration', duration,
                     '--output-interval', interval, '--method', 'rk4', '--step', '0.01h',
                     '--out', str(out)]) == 0, capsys.readouterr().err
        assert 'time: 12 h, 13 samples per body' in capsys.readouterr().out
        t[duration] = np.load(out)['t']
    np.testing.assert_allclose(t['12'] * HOURS_PER_YEAR, np.arange(13.0), rtol=1e-12, atol=0)
    np.testing.assert_array_equal(t['12'], t['0.5d'])
    np.testing.assert_array_equal(t['12'], t['12h'])
    assert main([str(config), '--bodies', '2', '--quiet', '--duration', '12 hours']) == 2
    assert "error: --duration: '12 hours' is not a time: a number in h" in \
        capsys.readouterr().err


def test_the_ensembles_impacts_are_per_unit_of_the_scenario(tmp_path, capsys):
    """
    --impact-rate per hour, --impact-duration in hours, --impact-torque in I rad/h^2.

    The command's bodies are the Python API's given the same impacts in years.
    """
    from tumble_ros.cli.ensemble import main
    from tumble_ros.core import RandomImpacts
    from tumble_ros.ensembles import run_ensemble

    config = tmp_path / 'hours.yaml'
    config.write_text(HOURS)
    out = tmp_path / 'kicked.npz'
    assert main([str(config), '--bodies', '3', '--quiet', '--impact-rate', '0.5',
                 '--impact-duration', '0.01', '--impact-torque', '2.0', '--omega-spread', '0',
                 '--out', str(out), '--seed', '3']) == 0, capsys.readouterr().err
    said = capsys.readouterr().out
    assert 'impacts: random, 0.5/h per body, seed 3' in said, said
    h = HOURS_PER_YEAR
    expected = run_ensemble(parse_scenario(HOURS), n_bodies=3, impacts=RandomImpacts(
        rate=0.5 * h, torque=2.0 * h * h, pulse=0.01 / h, frame='body', seed=3))
    np.testing.assert_array_equal(np.load(out)['omega'], expected.omega)
    quiet = run_ensemble(parse_scenario(HOURS), n_bodies=3)
    assert not np.array_equal(quiet.omega, expected.omega)     # the impacts did kick


def test_analyze_at_is_in_the_recordings_unit(tmp_path, capsys):
    """A 24-h recording: --at 12, 12h and 0.5d draw the same frame; 30 is past its end."""
    from tumble_ros.analysis.cli import command
    from tumble_ros.runs.offline import record_offline

    result = record_offline(parse_scenario(HOURS), tmp_path / 'hours.mcap')
    said = []
    for at in ('12', '12h', '0.5d'):
        out = tmp_path / f'still_{at}.png'
        assert command([str(result.output), '--still', str(out), '--at', at, '--quiet']) == 0
        said.append(capsys.readouterr().out.split(f'still: {out} ')[1].splitlines()[0].strip())
    assert said == ['(the /markers scene at t = 12 h)'] * 3, said
    assert command([str(result.output), '--still', str(tmp_path / 'x.png'), '--at', '30',
                    '--quiet']) == 1
    assert '--at 30 h: outside the run, [0, 24] h' in capsys.readouterr().err

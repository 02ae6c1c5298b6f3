"""
One output grid for every time_unit (issue 47).

The Python API, the sim node and the offline recording sample the same times, every
output_interval from 0 to the duration included.
"""
from fractions import Fraction
import itertools

import numpy as np
import pytest
from rclpy.parameter import Parameter

from tumble_ros.analysis.recording import load_recording
from tumble_ros.core import load_scenario, parse_scenario, Scenario, simulate
from tumble_ros.core.units import TIME_UNITS
from tumble_ros.runs.offline import record_offline

#: (duration, output_interval) in the scenario's unit, as a person writes them.
DURATIONS = ('1', '7', '24', '144', '1190', '1190.1', '3.3', '1000.5', '365.25')
INTERVALS = ('1', '0.25', '0.05', '0.1', '0.3', '0.125', '0.07')
SWEEP = [(d, i) for d, i in itertools.product(DURATIONS, INTERVALS)
         if Fraction(i) <= Fraction(d) and Fraction(d) / Fraction(i) <= 30_000]


def scenario_text(unit: str, duration: str, interval: str) -> str:
    """Return a free body's params file in ``unit`` (slow spin: any duration is valid)."""
    return ('sim:\n  ros__parameters:\n'
            f'    time_unit: {unit}\n    orbit_rate: 0.0\n    omega0: [0.0, 0.0, 1.0e-3]\n'
            f'    duration: {duration}\n    output_interval: {interval}\n')


def expected_count(duration: str, interval: str) -> int:
    """Return the samples at 0, interval, ... up to the duration, in exact decimal arithmetic."""
    return int(Fraction(duration) // Fraction(interval)) + 1


@pytest.mark.parametrize('unit', list(TIME_UNITS))
def test_the_grid_of_every_unit_ends_at_the_duration(unit):
    wrong = []
    for duration, interval in SWEEP:
        sc = parse_scenario(scenario_text(unit, duration, interval))
        t = sc.output_times
        n = expected_count(duration, interval)
        # in the unit: k * interval, to the float rounding of the conversion
        in_unit = np.arange(n) * float(Fraction(interval))
        if len(t) != n or not np.allclose(t / TIME_UNITS[unit], in_unit, rtol=1e-13, atol=0):
            wrong.append((duration, interval, len(t), n))
        elif Fraction(duration) % Fraction(interval) == 0 and t[-1] != sc.duration:
            wrong.append((duration, interval, 'last', t[-1], sc.duration))
    assert not wrong


def test_only_float_rounding_moves_a_duration_onto_its_stamp():
    assert Scenario(duration=1 / 3, output_interval=0.01).duration == 1 / 3   # between stamps
    days = Scenario(duration=1190 * TIME_UNITS['d'], output_interval=0.25 * TIME_UNITS['d'],
                    time_unit='d')
    assert days.duration == 1190 / 365.25 != 1190 * TIME_UNITS['d']   # an ulp apart
    assert days.output_times[-1] == days.duration


def test_the_issue_cases():
    """1190 d every 0.25 d: 4761 samples to 1190 d; Apophis: 2881 samples 0.05 h apart."""
    days = parse_scenario(scenario_text('d', '1190', '0.25'))
    assert len(days.output_times) == 4761
    assert days.output_times[-1] * 365.25 == pytest.approx(1190.0, rel=1e-15)
    apophis = load_scenario('tumble_ros/config/apophis_2029.yaml')
    t = apophis.output_times * 8766.0
    assert len(t) == 2881 and t[-1] == pytest.approx(144.0, rel=1e-15)
    np.testing.assert_allclose(np.diff(t), 0.05, rtol=1e-12)


@pytest.mark.parametrize('unit', list(TIME_UNITS))
def test_the_sim_node_publishes_the_grid_of_simulate(ros, unit):
    """The node's default seconds_per_year (0: one ROS second per unit) gives the same grid."""
    from tumble_ros.nodes.sim import SimNode

    for duration, interval in [('1190', '0.25'), ('7', '0.1'), ('1190.1', '0.3'), ('3.3', '0.07')]:
        sc = parse_scenario(scenario_text(unit, duration, interval))
        overrides = {'time_unit': unit, 'orbit_rate': 0.0, 'omega0': [0.0, 0.0, 1e-3],
                     'duration': float(duration), 'output_interval': float(interval),
                     'start_paused': True}
        sim = SimNode(context=ros.context, parameter_overrides=[
            Parameter(name, value=value) for name, value in overrides.items()])
        try:
            assert sim.scenario.duration == sc.duration
            assert sim.grid.times().tolist() == sc.output_times.tolist()
            assert sim.grid.count == expected_count(duration, interval)
        finally:
            sim.destroy_node()


@pytest.mark.parametrize('unit', list(TIME_UNITS))
def test_the_offline_recording_writes_the_grid_of_simulate(tmp_path, unit):
    for duration, interval in [('24', '0.25'), ('3.3', '0.3')]:
        sc = parse_scenario(scenario_text(unit, duration, interval))
        path = tmp_path / f'{unit}-{duration}.mcap'
        result = record_offline(sc, path, markers=False)
        rec = load_recording(path)
        run = simulate(sc)
        assert result.samples == len(run.t) == expected_count(duration, interval)
        assert rec.t.tolist() == run.t.tolist()
        assert rec.scenario == sc                 # the description keeps the unit
        np.testing.assert_array_equal(rec.omega, run.omega)

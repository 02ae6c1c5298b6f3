"""Scenario units at the boundary (core/units.py): hours, days, ... made years once."""
import math

import numpy as np
import pytest

from tumble_ros.core import parse_scenario, Scenario, ScenarioError, simulate
from tumble_ros.core.model.scenario import PARAMETER_DOCS
from tumble_ros.core.units import HOURS_PER_YEAR, TIME_POWERS, TIME_UNITS, to_years


def test_every_time_like_parameter_is_converted_with_its_power_of_time():
    """A new parameter in years, rad/yr or .../yr^2 must be listed in TIME_POWERS too."""
    for name, (unit, _) in PARAMETER_DOCS.items():
        if 'yr' not in unit:
            assert name not in TIME_POWERS, name
            continue
        power = -2 if unit.endswith('yr^2') else (-1 if '/yr' in unit else 1)
        assert TIME_POWERS.get(name) == power, (name, unit)


def test_a_scenario_in_hours_is_the_same_scenario_in_years():
    h = 1.0 / HOURS_PER_YEAR
    hours = parse_scenario(
        'sim:\n  ros__parameters:\n    time_unit: h\n    inertia: [1.0, 1.3, 1.8]\n'
        '    orbit_rate: 0.0\n'
        f'    duration: {0.5 * HOURS_PER_YEAR!r}\n    output_interval: {0.01 * HOURS_PER_YEAR!r}\n'
        f'    omega0: [{1.0 * h!r}, {-2.0 * h!r}, {20.0 * h!r}]\n'
        f'    integrator.method: rk4\n    integrator.step: {1e-4 * HOURS_PER_YEAR!r}\n'
        f'    impacts.start: [{0.2 * HOURS_PER_YEAR!r}]\n'
        f'    impacts.duration: [{1e-3 * HOURS_PER_YEAR!r}]\n'
        f'    impacts.torque: [{500.0 * h * h!r}, 0.0, 0.0]\n'
        f'    orbit.kind: kepler\n    orbit.gm: 1.3271244e11\n    orbit.a: 2.0e8\n'
        f'    orbit.e: 0.3\n    orbit.t_p: {0.1 * HOURS_PER_YEAR!r}\n')
    years = Scenario.from_parameters({
        'inertia': [1.0, 1.3, 1.8], 'orbit_rate': 0.0, 'duration': 0.5, 'output_interval': 0.01,
        'omega0': [1.0, -2.0, 20.0], 'integrator.method': 'rk4', 'integrator.step': 1e-4,
        'impacts.start': [0.2], 'impacts.duration': [1e-3], 'impacts.torque': [500.0, 0, 0],
        'orbit.kind': 'kepler', 'orbit.gm': 1.3271244e11, 'orbit.a': 2.0e8, 'orbit.e': 0.3,
        'orbit.t_p': 0.1})
    for field in ('duration', 'output_interval'):
        assert getattr(hours, field) == pytest.approx(getattr(years, field), rel=1e-14)
    np.testing.assert_allclose(hours.omega0, years.omega0, rtol=1e-14)
    assert hours.impacts[0].torque[0] == pytest.approx(500.0, rel=1e-14)
    assert hours.orbit.gm == years.orbit.gm == 1.3271244e11   # km^3/s^2 whatever time_unit
    assert hours.orbit.t_p == pytest.approx(0.1, rel=1e-14)
    np.testing.assert_allclose(simulate(hours).omega, simulate(years).omega, rtol=1e-9)
    # inside, and in every description the simulator publishes, the values are in years; the
    # scenario keeps its unit (its grid's, and what is printed)
    params = hours.to_parameters()
    assert (params['time_unit'], params['values_in_years']) == ('h', True)
    assert params['duration'] == hours.duration
    assert Scenario.from_parameters(params) == hours
    assert (hours.time_unit, years.time_unit) == ('h', 'yr')
    assert years.to_parameters()['values_in_years'] is False


def test_values_in_years_must_be_a_boolean():
    with pytest.raises(ScenarioError, match=r"^values_in_years: must be true or false, got 'y'"):
        Scenario.from_parameters({'time_unit': 'h', 'values_in_years': 'y'})


def test_a_time_unit_is_refused_naming_the_field_in_the_python_api():
    with pytest.raises(ScenarioError, match=r"^time_unit: must be one of \['d', 'h', 'min', "):
        Scenario(time_unit='hours')


def test_the_conversion_factors():
    assert TIME_UNITS['d'] * 365.25 == 1.0
    assert TIME_UNITS['h'] * HOURS_PER_YEAR == pytest.approx(1.0, rel=1e-15)
    assert to_years({'omega0': [2 * math.pi]}, 'd')['omega0'][0] == pytest.approx(
        2 * math.pi * 365.25)                          # one turn a day in rad/yr
    assert to_years({'duration': 'soon'}, 'h') == {'duration': 'soon'}   # left to validation


def test_an_unknown_unit_is_refused_naming_the_field():
    with pytest.raises(ScenarioError, match=r"^time_unit: must be one of \['d', 'h', 'min', "):
        Scenario.from_parameters({'time_unit': 'hour'})


def test_numbers_without_a_decimal_point_or_exponent_sign_are_numbers_as_in_ros():
    """YAML 1.1 (PyYAML) reads 1.3271244e11 and 4e5 as strings; rcl and YAML 1.2 as numbers."""
    sc = parse_scenario('sim:\n  ros__parameters:\n    orbit_rate: 0.0\n    orbit.kind: kepler\n'
                        '    orbit.gm: 1.3271244e11\n    orbit.a: 2e8\n    duration: 1E-1\n')
    assert (sc.orbit.gm, sc.orbit.a, sc.duration) == (1.3271244e11, 2e8, 0.1)

"""
The spin state as the literature gives it (core/model/observables.py, the ``spin.*`` block).

Both ways: a literature state through a params file or the API to omega0/euler0, simulated, and
back through :func:`observe` (what ``analyze``'s :func:`spin_state` reports) for SAMs and LAMs;
any (w, attitude) to a literature state and back; the Apophis-like config against Pravec et al.
2014's own E/E0; an independent scipy DOP853 integration measuring the periods and L; bad values
refused in one line naming the field.
"""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tumble_ros.core import (IntegratorSettings, load_scenario, parse_scenario, Scenario,
                             ScenarioError, simulate)
from tumble_ros.core.model.observables import observe, SpinObservables
from tumble_ros.core.model.rotation import euler_to_matrix, euler_to_quaternion
from tumble_ros.core.model.spinstate import omega_for_periods, spin_state
from tumble_ros.core.units import TIME_UNITS

CONFIG = Path(__file__).resolve().parents[1] / 'config'
HOUR = TIME_UNITS['h']
#: Pravec et al. 2014 (Icarus 233, 48): config/tumbling_from_observables.yaml.
PRAVEC = SpinObservables('SAM', 27.38 * HOUR, 263.0 * HOUR, (0.61, 0.965),
                         (math.radians(250.0), math.radians(-75.0)))

BLOCK = """
/**/sim:
  ros__parameters:
    time_unit: h
    orbit_rate: 0.0
    duration: 100.0
    output_interval: 0.5
    spin:
      mode: {mode}
      precession_period: {p_phi!r}
      rotation_period: {p_psi!r}
      inertia_ratios: [{r1!r}, {r2!r}]
      pole: [{lon!r}, {lat!r}]
      phases: [{phi!r}, {psi!r}]
      anti_aligned: {anti}
"""


def block(state: SpinObservables, unit: float = HOUR) -> str:
    """Return a params file's text stating ``state`` (periods in hours)."""
    return BLOCK.format(mode=state.mode, p_phi=state.precession_period / unit,
                        p_psi=state.rotation_period / unit, r1=state.inertia_ratios[0],
                        r2=state.inertia_ratios[1], lon=state.pole[0], lat=state.pole[1],
                        phi=state.phases[0], psi=state.phases[1],
                        anti=str(state.anti_aligned).lower())


def angle_gap(a: float, b: float) -> float:
    """Return |a - b| modulo 2 pi, in [0, pi]."""
    return abs(math.remainder(a - b, 2.0 * math.pi))


def random_state(rng: np.random.Generator, mode: str) -> SpinObservables:
    """
    Return a random literature state of ``mode``, away from the separatrix and pure spins.

    Its periods are those of a polhode point of a dynamical moment drawn inside the mode's range.
    """
    r1 = rng.uniform(0.45, 0.85)
    r2 = rng.uniform(r1 + 0.03, 0.97)
    low, high = (r2, 1.0) if mode == 'SAM' else (r1, r2)
    d = low + rng.uniform(0.1, 0.9) * (high - low)
    e2 = 1.0 / d                                  # 2E for L = 1
    w = np.array([math.sqrt((1.0 - e2) / (r1 * (r1 - 1.0))), 0.0,
                  math.sqrt((1.0 - e2 * r1) / (1.0 - r1))])
    unit = spin_state(w, (r1, r2, 1.0))
    assert unit.mode == mode
    scale = rng.uniform(0.5, 2.0) * 1e-3 / unit.precession_period     # P_phi ~ 1e-3 yr
    return SpinObservables(mode, unit.precession_period * scale, unit.rotation_period * scale,
                           (r1, r2), (rng.uniform(0, 2 * math.pi), rng.uniform(-1.5, 1.5)),
                           (rng.uniform(0, 2 * math.pi), rng.uniform(0, 2 * math.pi)),
                           bool(rng.integers(2)))


def assert_same_state(found: SpinObservables, expected: SpinObservables, rel: float,
                      phases: bool = True) -> None:
    """Assert two literature states agree: mode, periods, ratios, pole (and the phases)."""
    assert found.mode == expected.mode
    assert found.precession_period == pytest.approx(expected.precession_period, rel=rel)
    assert found.rotation_period == pytest.approx(expected.rotation_period, rel=rel)
    np.testing.assert_allclose(found.inertia_ratios, expected.inertia_ratios, rtol=1e-12)
    pole = [math.cos(found.pole[1]) * math.cos(found.pole[0]),
            math.cos(found.pole[1]) * math.sin(found.pole[0]), math.sin(found.pole[1])]
    want = [math.cos(expected.pole[1]) * math.cos(expected.pole[0]),
            math.cos(expected.pole[1]) * math.sin(expected.pole[0]), math.sin(expected.pole[1])]
    np.testing.assert_allclose(pole, want, atol=rel)
    if phases:
        assert angle_gap(found.phases[0], expected.phases[0]) < 1e-9
        assert angle_gap(found.phases[1], expected.phases[1]) < 1e-9
        assert found.anti_aligned == expected.anti_aligned


@pytest.mark.parametrize('mode', ['SAM', 'LAM'])
def test_a_params_file_block_states_the_spin_state_it_gives(mode):
    """The block, in hours, loads to an omega0/euler0 whose state at t = 0 is the block's."""
    rng = np.random.default_rng(47 if mode == 'SAM' else 48)
    for _ in range(3):
        state = random_state(rng, mode)
        scenario = parse_scenario(block(state))
        assert scenario.inertia == (*state.inertia_ratios, 1.0)
        back = observe(scenario.omega0, scenario.inertia, euler_to_quaternion(*scenario.euler0))
        assert_same_state(back, state, rel=1e-11)
        # the API: the same fields
        fields = state.scenario_fields()
        assert (fields['omega0'], fields['euler0']) == (scenario.omega0, scenario.euler0)


@pytest.mark.parametrize('mode', ['SAM', 'LAM'])
def test_the_state_survives_a_simulation_as_analyze_reports_it(mode):
    """Literature state -> scenario -> torque-free run of a few P_psi -> spin_state at its end."""
    rng = np.random.default_rng(2014 if mode == 'SAM' else 2022)
    for _ in range(3):
        state = random_state(rng, mode)
        span = 3.0 * max(state.rotation_period, state.precession_period)
        scenario = Scenario(**state.scenario_fields(), orbit_rate=0.0, duration=span,
                            output_interval=span / 10, allow_unphysical_inertia=True,
                            integrator=IntegratorSettings(method='dop853', rtol=1e-12,
                                                          atol=1e-12))
        run = simulate(scenario)
        reported = spin_state(run.omega[-1], scenario.inertia, run.quaternion[-1])
        assert reported.mode == mode
        assert reported.precession_period == pytest.approx(state.precession_period, rel=1e-8)
        assert reported.rotation_period == pytest.approx(state.rotation_period, rel=1e-8)
        found = observe(run.omega[-1], scenario.inertia, run.quaternion[-1])
        assert_same_state(found, state, rel=1e-8, phases=False)


@pytest.mark.parametrize('seed', range(6))
def test_any_tumbling_state_goes_to_the_literature_and_back(seed):
    """(w, attitude) -> observe -> scenario_fields gives the same w and attitude."""
    rng = np.random.default_rng(seed)
    inertia = rng.permutation([rng.uniform(0.5, 0.7), rng.uniform(0.75, 0.95), 1.0]) * 3.0
    omega = rng.normal(size=3) * 100.0
    euler = (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(0.1, 3.0))
    state = observe(omega, inertia, euler_to_quaternion(*euler))
    fields = state.scenario_fields(inertia)
    assert fields['inertia'] == tuple(inertia)
    np.testing.assert_allclose(fields['omega0'], omega, rtol=1e-9, atol=1e-9 * 100)
    np.testing.assert_allclose(euler_to_matrix(*fields['euler0']), euler_to_matrix(*euler),
                               atol=1e-9)


def test_omega_for_periods_builds_long_axis_modes():
    w = omega_for_periods((0.61, 0.965, 1.0), 27.38, 60.0, 'LAM')
    state = spin_state(w, (0.61, 0.965, 1.0))
    assert state.mode == 'LAM'
    assert state.precession_period == pytest.approx(27.38, rel=1e-12)
    assert state.rotation_period == pytest.approx(60.0, rel=1e-12)


def test_the_apophis_like_config_is_pravec_et_al_2014():
    """The shipped file states Pravec et al.'s solution; its E/E0 is theirs (1.024 +- 0.013)."""
    scenario = load_scenario(CONFIG / 'tumbling_from_observables.yaml')
    assert scenario.inertia == (0.61, 0.965, 1.0)
    state = observe(scenario.omega0, scenario.inertia, euler_to_quaternion(*scenario.euler0))
    assert_same_state(state, PRAVEC, rel=1e-11)
    # an independent check of the conversion: E/E0 = I3 / D (E0 = L^2 / 2 I3), a number the
    # paper derives from the same solution
    dynamic = spin_state(scenario.omega0, scenario.inertia).dynamic_inertia
    assert abs(1.0 / dynamic - 1.024) <= 0.013


def _euler_poinsot(t, y, inertia):
    """Euler's equations and the rotation matrix C (body -> inertial): dC/dt = C [w]x."""
    w, c = y[:3], y[3:].reshape(3, 3)
    dw = np.array([(inertia[1] - inertia[2]) * w[1] * w[2],
                   (inertia[2] - inertia[0]) * w[2] * w[0],
                   (inertia[0] - inertia[1]) * w[0] * w[1]]) / inertia
    cross = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    return np.concatenate([dw, (c @ cross).ravel()])


def test_an_independent_integration_measures_the_stated_periods_and_pole():
    """
    The config's state through scipy's DOP853 on Euler's equations (not the project's code).

    P_psi: the time between upward zero crossings of w2; P_phi: the mean rate of the I3 axis'
    azimuth about L over the run; L's direction in the inertial frame: (250 deg, -75 deg).
    """
    scenario = load_scenario(CONFIG / 'tumbling_from_observables.yaml')
    inertia = np.array(scenario.inertia)
    c0 = euler_to_matrix(*scenario.euler0).T
    span = 6.0 * PRAVEC.rotation_period
    t = np.linspace(0.0, span, 60001)
    sol = solve_ivp(_euler_poinsot, (0.0, span), np.concatenate([scenario.omega0, c0.ravel()]),
                    method='DOP853', t_eval=t, rtol=1e-12, atol=1e-12, args=(inertia,))
    assert sol.success
    w, c = sol.y[:3].T, sol.y[3:].T.reshape(-1, 3, 3)
    momentum = c[0] @ (inertia * w[0])
    pole = momentum / np.linalg.norm(momentum)
    lon, lat = PRAVEC.pole
    np.testing.assert_allclose(pole, [math.cos(lat) * math.cos(lon),
                                      math.cos(lat) * math.sin(lon), math.sin(lat)], atol=1e-12)
    w2 = w[:, 1]
    up = np.flatnonzero((w2[:-1] < 0) & (w2[1:] >= 0))
    crossings = t[up] - w2[up] * (t[up + 1] - t[up]) / (w2[up + 1] - w2[up])
    assert len(crossings) >= 5
    p_psi = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert p_psi == pytest.approx(PRAVEC.rotation_period, rel=1e-6)
    # the I3 axis about L, over whole rotation periods (its rate varies within one)
    e1 = np.cross(pole, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(pole, e1)
    axis = c[:, :, 2]
    azimuth = np.unwrap(np.arctan2(axis @ e2, axis @ e1))
    k0, k1 = up[0], up[-1]
    p_phi = 2.0 * math.pi * (t[k1] - t[k0]) / abs(azimuth[k1] - azimuth[k0])
    assert p_phi == pytest.approx(PRAVEC.precession_period, rel=1e-4)


GOOD = {'mode': 'SAM', 'precession_period': 27.38 * HOUR, 'rotation_period': 263.0 * HOUR,
        'inertia_ratios': (0.61, 0.965), 'pole': (4.36, -1.31)}


@pytest.mark.parametrize('change, field', [
    # (a SAM of these ratios has P_psi / P_phi > 7.5, a LAM > 1.6)
    ({'rotation_period': 1.0 * HOUR}, 'spin.rotation_period: impossible'),
    ({'mode': 'LAM', 'rotation_period': 10.0 * HOUR}, 'spin.rotation_period: impossible'),
    ({'pole': (4.36, -1.6)}, 'spin.pole: the latitude'),
    ({'inertia_ratios': (0.965, 0.61)}, 'spin.inertia_ratios: must be'),
    ({'inertia_ratios': (0.61, 1.2)}, 'spin.inertia_ratios: must be'),
    ({'inertia_ratios': (0.61, 0.61)}, 'spin.inertia_ratios: must be'),
    ({'mode': 'NPA'}, 'spin.mode: must be one of'),
    ({'precession_period': -1.0}, 'spin.precession_period: must be'),
    ({'rotation_period': math.nan}, 'spin.rotation_period: must be'),
    ({'pole': (math.inf, 0.0)}, 'spin.pole: must be'),
    ({'phases': (0.0,)}, 'spin.phases: must be'),
])
def test_bad_values_are_refused_in_one_line_naming_the_field(change, field):
    with pytest.raises(ScenarioError) as err:
        SpinObservables(**{**GOOD, **change})
    assert str(err.value).startswith(field)
    assert '\n' not in str(err.value) and 'got' in str(err.value)


@pytest.mark.parametrize('old, new, field', [
    ('    spin:\n', '    omega0: [1.0, 2.0, 3.0]\n    spin:\n',
     'omega0: give the spin state once'),
    ('    spin:\n', '    euler0: [0.1, 0.2, 0.3]\n    spin:\n',
     'euler0: give the spin state once'),
    ('    spin:\n', '    inertia: [0.6, 0.965, 1.0]\n    spin:\n',
     'spin.inertia_ratios: disagree'),
    ('rotation_period: 263.0', 'rotation_period: 1.0', 'spin.rotation_period: impossible'),
    ('pole: [', 'pole: [1.0, ', 'spin.pole: must be a list of 2'),
])
def test_a_params_file_states_the_spin_once_and_right(old, new, field):
    text = block(PRAVEC)
    assert old in text
    with pytest.raises(ScenarioError) as err:
        parse_scenario(text.replace(old, new, 1))
    assert str(err.value).startswith(field) and '\n' not in str(err.value)


def test_a_stated_inertia_with_the_ratios_keeps_its_axes():
    """An inertia [2, 1.22, 1.93] (I3 along x) with the block: the ratios agree, axes kept."""
    text = block(PRAVEC).replace('    spin:\n', '    inertia: [2.0, 1.22, 1.93]\n    spin:\n')
    scenario = parse_scenario(text)
    assert scenario.inertia == (2.0, 1.22, 1.93)
    state = observe(scenario.omega0, scenario.inertia, euler_to_quaternion(*scenario.euler0))
    assert_same_state(state, PRAVEC, rel=1e-11)


def test_spin_fields_without_a_mode_are_refused():
    text = '/**/sim:\n  ros__parameters:\n    spin:\n      pole: [1.0, 0.5]\n'
    with pytest.raises(ScenarioError, match=r'^spin\.pole: is used only with spin\.mode'):
        parse_scenario(text)


def test_observe_refuses_a_principal_rotation():
    with pytest.raises(ScenarioError, match='^spin.mode: the state has no SAM/LAM'):
        observe((0.0, 0.0, 5.0), (0.6, 0.9, 1.0), (1.0, 0.0, 0.0, 0.0))


def test_the_block_round_trips_through_its_parameters():
    """to_parameters (periods in years) read back as the same state."""
    from tumble_ros.core.model.observables import spin_from_parameters
    assert spin_from_parameters(PRAVEC.to_parameters()) == PRAVEC


def test_analyze_reports_the_state_as_the_block_it_was_given(tmp_path):
    """A recording of the shipped file: analyze's start state is Pravec et al.'s block again."""
    from test_analysis_support import write_recording

    from tumble_ros.analysis import analyze, format_summary, load_recording, summary_to_dict

    scenario = load_scenario(CONFIG / 'tumbling_from_observables.yaml').replace(
        duration=10 * HOUR, output_interval=HOUR)
    run = simulate(scenario)
    path = write_recording(tmp_path / 'tumbler.mcap', run.t, run.omega,
                           quaternion=run.quaternion, scenario=scenario)
    summary = analyze(load_recording(path))
    assert summary.spin is not None and summary.spin.start_block is not None
    assert_same_state(summary.spin.start_block, PRAVEC, rel=1e-11)
    assert summary.spin.end_block is not None
    assert_same_state(summary.spin.end_block, PRAVEC, rel=1e-9, phases=False)
    assert 'as spin.*: inertia_ratios [0.61, 0.965], phases (phi0, psi0) = (0, 0) deg' \
        in format_summary(summary)
    assert summary_to_dict(summary)['spin']['start_block']['mode'] == 'SAM'

"""
A torque defined outside core, integrated by every integrator (reference and compiled paths).

The proof that torques are components (issue 11): the torque below lives in this file, not in
core; no integrator knows it. Each method must integrate it, together with the built-in
gravity gradient and an impact pulse, to its accuracy against an independent solution: scipy's
DOP853 at rtol 1e-13 on a right-hand side written out here (Euler's equations, the tidal torque
of eq 12 from its components, the quaternion kinematics), which shares no code with core but
the torque function itself.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tumble_ros.core import (Impact, INTEGRATORS, IntegratorSettings, kernels, Propagator,
                             Scenario, simulate, simulate_ensemble, torque_function,
                             TorqueComponent)
from tumble_ros.core.model.rotation import euler_to_quaternion


@torque_function
def dipole_in_turning_field(par, t, q0, q1, q2, q3):
    """
    Return m x B: a body-fixed dipole m in a field B fixed to a frame turning about Z'.

    par = (B0x, B0y, B0z, rate, mx, my, mz): B(t) = R_z(rate t) B0 in the orbital frame.
    """
    c = math.cos(par[3] * t)
    s = math.sin(par[3] * t)
    bx = c * par[0] - s * par[1]
    by = s * par[0] + c * par[1]
    bz = par[2]
    n = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    # body components C^T B of the orbital-frame field (C: body -> orbital, unit quaternion)
    ux = ((q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3) * bx + 2.0 * (q1 * q2 + q0 * q3) * by
          + 2.0 * (q1 * q3 - q0 * q2) * bz) / n
    uy = (2.0 * (q1 * q2 - q0 * q3) * bx + (q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3) * by
          + 2.0 * (q2 * q3 + q0 * q1) * bz) / n
    uz = (2.0 * (q1 * q3 + q0 * q2) * bx + 2.0 * (q2 * q3 - q0 * q1) * by
          + (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3) * bz) / n
    mx, my, mz = par[4], par[5], par[6]
    return my * uz - mz * uy, mz * ux - mx * uz, mx * uy - my * ux


@torque_function
def constant_body_torque(par, t, q0, q1, q2, q3):
    """Return the constant body-axis torque (par[0], par[1], par[2])."""
    return par[0], par[1], par[2]


@torque_function
def tidal_torque_written_here(par, t, q0, q1, q2, q3):
    """Return eq 12's torque, written out here: par = (ws, Ix, Iy, Iz)."""
    ws = par[0]
    sx, sy = math.sin(ws * t), math.cos(ws * t)
    n = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    ux = ((q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3) * sx + 2.0 * (q1 * q2 + q0 * q3) * sy) / n
    uy = (2.0 * (q1 * q2 - q0 * q3) * sx + (q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3) * sy) / n
    uz = (2.0 * (q1 * q3 + q0 * q2) * sx + 2.0 * (q2 * q3 - q0 * q1) * sy) / n
    k = 3.0 * ws * ws
    return (k * (par[3] - par[2]) * uy * uz, k * (par[1] - par[3]) * ux * uz,
            k * (par[2] - par[1]) * ux * uy)


DIPOLE = TorqueComponent('dipole', dipole_in_turning_field,
                         (300.0, -200.0, 500.0, 7.0, 0.3, -0.2, 0.4))
INERTIA = (1.0, 1.3, 1.8)
WS = 2.0
BASE = Scenario(inertia=INERTIA, orbit_rate=WS, omega0=(2.0, -3.0, 25.0), euler0=(0.4, 0.3, 0.7),
                duration=0.4, output_interval=0.05,
                impacts=(Impact(start=0.2, duration=1e-3, torque=(800.0, 0.0, -500.0)),),
                torques=(DIPOLE,))
#: Settings per method: each meets the issue's standard, 1e-8 relative (|omega| ~ 25 rad/yr),
#: on this run with a margin (measured 2e-12 .. 8e-8 rad/yr, 2026-12-01).
SETTINGS = {
    'rk4': {'step': 1e-4},
    'rk45': {'rtol': 1e-12, 'atol': 1e-12},
    'dop853': {'rtol': 1e-12, 'atol': 1e-12},
    'radau': {'rtol': 1e-12, 'atol': 1e-12},
    'bdf': {'rtol': 1e-12, 'atol': 1e-12},
    'lsoda': {'rtol': 1e-12, 'atol': 1e-12},
    'adams': {'rtol': 1e-12, 'atol': 1e-12},
    'splitting': {'step': 1e-5},
    'splitting4': {'step': 1e-4},
    'splitting6': {'step': 2e-4},
}
TOLERANCE = 1e-8 * 25.0  # rad/yr


def reference_solution(scenario, times):
    """Return omega at ``times`` from scipy DOP853 (rtol 1e-13) on a RHS written out here."""
    inertia = np.array(scenario.inertia)
    ws = scenario.orbit_rate
    tidal = TorqueComponent('tidal', tidal_torque_written_here, (ws, *scenario.inertia))
    components = (tidal, *scenario.torques)

    def rhs(t, y, pulse):
        w, q = y[:3], y[3:]
        torque = pulse + sum(c.torque(t, q) for c in components)
        dw = (np.cross(inertia * w, w) + torque) / inertia
        q0, q1, q2, q3 = q
        dq = 0.5 * np.array([-q1 * w[0] - q2 * w[1] - q3 * w[2],
                             q0 * w[0] + q2 * w[2] - q3 * w[1],
                             q0 * w[1] - q1 * w[2] + q3 * w[0],
                             q0 * w[2] + q1 * w[1] - q2 * w[0]])
        return np.concatenate([dw, dq])

    pulse_edges = [e for i in scenario.impacts for e in (i.start, i.end)]
    edges = sorted({0.0, scenario.duration, *pulse_edges})
    y = np.concatenate([scenario.omega0, euler_to_quaternion(*scenario.euler0)])
    out = np.empty((len(times), 3))
    for t0, t1 in zip(edges[:-1], edges[1:]):
        pulse = np.zeros(3)
        for i in scenario.impacts:
            if i.start <= t0 < i.end:
                pulse = np.array(i.torque)
        inside = [k for k, t in enumerate(times) if t0 <= t <= t1]
        sol = solve_ivp(rhs, (t0, t1), y, method='DOP853', rtol=1e-13, atol=1e-13,
                        t_eval=[times[k] for k in inside], args=(pulse,))
        assert sol.success
        out[inside] = sol.y[:3].T
        y = solve_ivp(rhs, (t0, t1), y, method='DOP853', rtol=1e-13, atol=1e-13,
                      args=(pulse,)).y[:, -1]
    return out


@pytest.fixture(scope='module')
def reference():
    return reference_solution(BASE, BASE.output_times)


def _paths(method):
    compiled = INTEGRATORS[method].kernel is not None and kernels.COMPILED
    return [False, True] if compiled else [False]


CASES = [(m, fast) for m in sorted(INTEGRATORS) for fast in _paths(m)]
#: End [yr] of the runs of the compiled loops' pure-Python twins: past the pulse (0.2-0.201 yr).
REFERENCE_PREFIX = 0.25


@pytest.mark.parametrize('method, fast', CASES,
                         ids=[f"{m}-{'compiled' if f else 'reference'}" for m, f in CASES])
def test_every_integrator_integrates_a_torque_defined_outside_core(method, fast, reference):
    """
    Every method to its accuracy; a compiled loop's pure-Python twin over the pulse only.

    The twin steps 40,000 times in Python at the splitting's 1e-5 yr (7.5 s of CPU over the
    whole run): it runs to REFERENCE_PREFIX, past the pulse, and its compiled loop over the
    whole run (the two agree to 1e-12: ``test_core_fast.py``).
    """
    sc = BASE.replace(integrator=IntegratorSettings(method=method, **SETTINGS[method]))
    if not fast and _paths(method) == [False, True]:
        sc = sc.replace(duration=REFERENCE_PREFIX)
    result = simulate(sc, fast=fast)
    assert result.success, result.message
    np.testing.assert_array_equal(result.t, BASE.output_times[:len(result.t)])
    assert result.t[-1] > BASE.impacts[0].end
    error = np.max(np.abs(result.omega - reference[:len(result.t)]))
    assert error < TOLERANCE, f'{method}: max |omega error| {error:.3g} rad/yr'


def test_the_extra_torque_matters_far_beyond_the_tolerance(reference):
    """Without it the run is off by ~14 rad/yr: an integrator that ignored it would fail."""
    sc = BASE.replace(torques=(), integrator=IntegratorSettings(method='dop853', rtol=1e-12,
                                                                atol=1e-12))
    assert np.max(np.abs(simulate(sc).omega - reference)) > 1e6 * TOLERANCE


@pytest.mark.parametrize('method', ['dop853', 'lsoda', 'rk45'])
def test_the_euler_attitude_integrates_it_too(method, reference):
    sc = BASE.replace(attitude='euler',
                      integrator=IntegratorSettings(method=method, **SETTINGS[method]))
    result = simulate(sc)
    assert result.success, result.message
    assert np.max(np.abs(result.omega - reference)) < TOLERANCE


@pytest.mark.parametrize('method, fast', CASES,
                         ids=[f"{m}-{'compiled' if f else 'reference'}" for m, f in CASES])
def test_a_constant_torque_on_a_sphere_gives_the_closed_form(method, fast):
    """
    I dw/dt = M on a sphere (w x I w = 0): w(t) = w0 + M t / I.

    Linear in t: exact for every method (splitting: exact kick, exact free flow), any step.
    """
    torque = np.array([3.0, -4.0, 1.5])
    sc = Scenario(inertia=(2.0, 2.0, 2.0), orbit_rate=0.0, omega0=(0.5, 1.0, 10.0),
                  duration=0.5, output_interval=0.125,
                  torques=(TorqueComponent('constant', constant_body_torque, tuple(torque)),),
                  integrator=IntegratorSettings(method=method, step=0.01))
    result = simulate(sc, fast=fast)
    expected = np.array(sc.omega0) + np.outer(sc.output_times, torque) / 2.0
    np.testing.assert_allclose(result.omega, expected, rtol=0, atol=1e-10)


@pytest.mark.skipif(not kernels.COMPILED, reason='numba not available')
def test_one_to_eight_extra_torques_share_one_compiled_variant():
    """The kernels' ``extra`` is typed by its tuple's length: padded, 1 to 8 are one type."""
    import numba

    from tumble_ros.core.torques import extra_torque_arrays

    def extra(n):
        return extra_torque_arrays([TorqueComponent(f'c{j}', constant_body_torque, (j, 0, 0))
                                    for j in range(n)])
    types = {n: numba.typeof(extra(n)) for n in (1, 2, 3, 8, 9, 16)}
    assert types[1] == types[2] == types[3] == types[8] != types[9] == types[16]
    functions, parameters = extra(3)
    assert len(functions) == 8 and parameters.shape == (3, 3)   # the rows say what is called


@pytest.mark.parametrize('method, fast', [c for c in CASES if c[0] in ('dop853', 'splitting')])
def test_three_extra_torques_through_the_padded_tuple_add_up(method, fast):
    """Three constant torques on a sphere: w0 + (M1 + M2 + M3) t / I (the padding adds nothing)."""
    parts = np.array([[3.0, 0.0, 1.0], [0.0, -4.0, 0.0], [0.0, 0.0, 0.5]])
    sc = Scenario(inertia=(2.0, 2.0, 2.0), orbit_rate=0.0, omega0=(0.5, 1.0, 10.0),
                  duration=0.5, output_interval=0.125,
                  torques=tuple(TorqueComponent(f'part{j}', constant_body_torque, tuple(p))
                                for j, p in enumerate(parts)),
                  integrator=IntegratorSettings(method=method, step=0.01))
    result = simulate(sc, fast=fast)
    expected = np.array(sc.omega0) + np.outer(sc.output_times, parts.sum(axis=0)) / 2.0
    np.testing.assert_allclose(result.omega, expected, rtol=0, atol=1e-10)


@pytest.mark.parametrize('method, fast',
                         [c for c in CASES if c[0] in ('dop853', 'splitting6', 'rk4')])
def test_a_plug_in_copy_of_the_tidal_torque_equals_the_built_in_one(method, fast):
    """Same time argument, same quaternion convention: the two paths into the torque agree."""
    settings = SETTINGS[method]
    built_in = BASE.replace(torques=(), impacts=(), duration=0.1,
                            integrator=IntegratorSettings(method=method, **settings))
    plugged = built_in.replace(orbit_rate=0.0, torques=(
        TorqueComponent('tidal', tidal_torque_written_here, (WS, *INERTIA)),))
    a = simulate(built_in, fast=fast)
    b = simulate(plugged, fast=fast)
    np.testing.assert_allclose(b.omega, a.omega, rtol=0, atol=1e-9)
    assert np.max(np.abs(a.omega - simulate(built_in.replace(orbit_rate=0.0)).omega)) > 1e-3


@pytest.mark.parametrize('fast', [False, True] if kernels.COMPILED else [False])
def test_ensembles_run_the_extra_torque(fast):
    sc = BASE.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-12, atol=1e-12))
    ens = simulate_ensemble(sc, n_bodies=2, omega0=[sc.omega0, (1.0, 2.0, 20.0)], fast=fast)
    assert ens.success.all()
    single = simulate(sc.replace(omega0=(1.0, 2.0, 20.0)), fast=fast)
    np.testing.assert_allclose(ens.omega[1], single.omega, rtol=0, atol=1e-10)
    np.testing.assert_allclose(ens.omega[0], simulate(sc, fast=fast).omega, rtol=0, atol=1e-10)


def test_the_propagator_hands_the_torque_to_each_segment():
    prop = Propagator(BASE.replace(integrator=IntegratorSettings(method='rk4', step=1e-4)))
    assert prop._stepper.problem.extra_torques == (DIPOLE,)


def test_a_plain_python_function_is_refused_with_the_reason():
    if not kernels.COMPILED:
        pytest.skip('without numba a plain function is a torque function')

    def plain(par, t, q0, q1, q2, q3):
        return 0.0, 0.0, 0.0

    with pytest.raises(ValueError, match='torque_function'):
        TorqueComponent('plain', plain)


@pytest.mark.parametrize('parameters, match', [((math.nan,), 'finite'), (('x',), 'numbers')])
def test_bad_parameters_are_refused_naming_the_component(parameters, match):
    with pytest.raises(ValueError, match=rf'torques\[constant\].parameters: .*{match}'):
        TorqueComponent('constant', constant_body_torque, parameters)


def test_a_scenario_refuses_what_is_not_a_component():
    with pytest.raises(ValueError, match=r'torques\[0\]'):
        Scenario(torques=(constant_body_torque,))

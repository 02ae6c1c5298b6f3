"""
The Lie-Poisson splitting integrators (splitting, splitting4, splitting6).

Registry and capability checks, order of convergence, exact invariants of the free flow,
bounded Jacobi error over the 2000-year Fig 9 run, exact pulses.
"""
from pathlib import Path

import numpy as np
import pytest

from tumble_ros.core import (angular_momentum_orbital, Impact, INTEGRATORS, IntegratorSettings,
                             kernels, load_scenario, METHODS, Propagator, Scenario, ScenarioError,
                             SegmentProblem, simulate, SPLITTING_METHODS)
from tumble_ros.core.integrators import FINISHED
from tumble_ros.core.model.rotation import quaternion_to_matrix

CONFIG = Path(__file__).resolve().parents[1] / 'config'
ORDERS = {'splitting': 2, 'splitting4': 4, 'splitting6': 6}
ASYMMETRIC = Scenario(inertia=(1.0, 1.6, 2.2), omega0=(0.5, 1.0, 10.0), euler0=(0.5, 0.2, 0.5),
                      orbit_rate=5.0, duration=1.0, output_interval=1.0)


def fig9(**changes):
    return load_scenario(CONFIG / 'fig9.yaml').replace(**changes)


def test_registry_and_capability_flags():
    assert set(SPLITTING_METHODS) == set(ORDERS)
    assert INTEGRATORS == {**METHODS, **SPLITTING_METHODS}
    assert not set(METHODS) & set(SPLITTING_METHODS)
    for name, cls in SPLITTING_METHODS.items():
        assert cls.name == name and cls.symplectic and not cls.adaptive and cls.needs_problem
        assert cls.order == ORDERS[name] and cls.attitudes == {'quaternion'}
    assert all(not cls.needs_problem and cls.attitudes == {'quaternion', 'euler'}
               for cls in METHODS.values())


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_euler_attitude_is_refused_at_validation_with_the_reason(method):
    with pytest.raises(
            ScenarioError,
            match=r"integrator\.method: .*cannot integrate attitude 'euler'.*quaternion"):
        Scenario(attitude='euler', integrator=IntegratorSettings(method=method))
    Scenario(attitude='quaternion', integrator=IntegratorSettings(method=method))  # accepted


def test_splitting_needs_the_problem_structure():
    settings = IntegratorSettings(method='splitting', step=1e-3)
    with pytest.raises(ValueError, match='rigid-body problem'):
        SPLITTING_METHODS['splitting'](lambda t, y: -y, 0.0, [1.0, 0.0], 1.0, settings)
    sc = Scenario(integrator=settings, impacts=(Impact(0.5, 1e-3, (1.0, 0.0, 0.0)),))
    with pytest.raises(ValueError, match='split_impacts=False'):
        Propagator(sc, split_impacts=False)


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_order_of_convergence(method):
    """
    Halving the step divides the error by 2^p.

    Asymmetric body (the free flow is split too) in a strong tidal field.
    """
    order = ORDERS[method]
    ref = simulate(
        ASYMMETRIC.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-14)))
    steps = {2: (4e-3, 2e-3, 1e-3), 4: (1e-2, 5e-3, 2.5e-3), 6: (2e-2, 1e-2, 5e-3)}[order]
    errors = []
    for h in steps:
        r = simulate(ASYMMETRIC.replace(integrator=IntegratorSettings(method=method, step=h)))
        errors.append(np.linalg.norm(r.omega[-1] - ref.omega[-1])
                      + np.linalg.norm(r.quaternion[-1] - ref.quaternion[-1]))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(np.log2(ratios) - order) < 0.25), (errors, ratios)


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_dense_output_has_the_order_of_the_method(method):
    """Inside a step the state is a partial step of the method: as accurate as the nodes."""
    order = ORDERS[method]
    sc = ASYMMETRIC.replace(integrator=IntegratorSettings(method=method,
                                                          step={2: 2e-3, 4: 5e-3, 6: 1e-2}[order]))
    t_mid = np.linspace(0.0, 1.0, 7)[1:-1] + 0.37 * sc.integrator.step  # never on a step boundary
    ref = simulate(sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-13,
                                                            atol=1e-14)), t_mid)
    r = simulate(sc, t_mid)
    nodes = simulate(sc, [1.0])
    err_mid = np.max(np.abs(r.omega - ref.omega))
    err_end = np.max(np.abs(nodes.omega[-1] - simulate(sc.replace(
        integrator=IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-14)), [1.0]).omega[-1]))
    assert err_mid < 3.0 * err_end + 1e-11, (err_mid, err_end)


def test_symmetric_free_top_is_integrated_exactly():
    """Ix = Iy and no torque: the split free flow is the exact flow, whatever the step."""
    inertia, omega0 = (1.0, 1.0, 1.5), (0.3, 1.0, 30.0)
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.2, 0.7),
                  duration=2.0, output_interval=0.1,
                  integrator=IntegratorSettings(method='splitting', step=0.05))
    r = simulate(sc)
    lam = (inertia[2] - inertia[0]) / inertia[0] * omega0[2]
    c, s = np.cos(lam * r.t), np.sin(lam * r.t)
    expected = np.stack([omega0[0] * c - omega0[1] * s, omega0[0] * s + omega0[1] * c,
                         np.full_like(r.t, omega0[2])], -1)
    np.testing.assert_allclose(r.omega, expected, atol=1e-12 * np.linalg.norm(omega0))


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_angular_momentum_is_kept_to_rounding_without_torque(method):
    """
    Without torque, |L| and the inertial L vector are kept to rounding.

    Asymmetric free body, 100 spin periods: |L| and the inertial L vector move only by
    rounding (every sub-flow is a rotation), while DOP853 at rtol 1e-10 drifts visibly.
    """
    inertia, omega0 = (1.0, 1.6, 2.2), (3.0, 0.5, 10.0)
    duration = 100 * 2 * np.pi / 10.0
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.2, 0.7),
                  duration=duration, output_interval=duration / 500,
                  integrator=IntegratorSettings(method=method, step=2e-3))
    r = simulate(sc)
    assert np.ptp(r.omega[:, 0]) > 1.0  # it tumbles
    c = np.array([quaternion_to_matrix(q) for q in r.quaternion])
    momentum = angular_momentum_orbital(r.omega, c, inertia)
    body = np.linalg.norm(r.omega * np.array(inertia), axis=1)
    scale = body[0]
    assert np.max(np.abs(body - scale)) / scale < 2e-13          # measured 1e-14 .. 5e-14
    assert np.max(np.linalg.norm(momentum - momentum[0], axis=1)) / scale < 5e-13  # 2e-14 .. 9e-14
    dop = simulate(sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-10,
                                                            atol=1e-12)))
    assert (np.max(np.abs(np.linalg.norm(dop.omega * np.array(inertia), axis=1) - scale)) / scale
            > 2e-12)  # 1e-11


def test_jacobi_error_is_bounded_over_2000_years():
    """
    The splitting method's Jacobi error stays bounded over 2000 years, DOP853's does not.

    The paper's Fig 9 case over its 2000 years: the splitting method's Jacobi error
    oscillates at a constant level (no secular trend), DOP853's grows linearly.
    """
    duration = 2000.0 if kernels.COMPILED else 50.0  # the reference path takes ~1 min per 100 yr
    sc = fig9(duration=duration, output_interval=duration / 4000)
    r = simulate(sc.replace(integrator=IntegratorSettings(method='splitting', step=2e-3)))
    assert r.success
    err = np.abs(r.jacobi - r.jacobi[0]) / abs(r.jacobi[0])
    tenth = len(err) // 10
    first, last = err[:tenth].max(), err[-tenth:].max()
    assert 1e-9 < err.max() < 1e-7          # order 2, step 2e-3: ~3e-8
    assert last < 1.3 * first and first < 1.3 * last, (first, last)
    slope = np.polyfit(r.t, err, 1)[0]
    assert abs(slope) * duration < 0.05 * err.max(), (slope, err.max())
    dop = simulate(sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-8,
                                                            atol=1e-10)))
    derr = np.abs(dop.jacobi - dop.jacobi[0]) / abs(dop.jacobi[0])
    assert derr[-tenth:].max() > 5 * derr[:tenth].max()  # secular drift of a non-symplectic method


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_transverse_body_pulse_is_exact(method):
    """
    A transverse body pulse is exact with the splitting methods.

    test_core_impacts' closed form, for the splitting methods: a 3e-7-yr body pulse on a
    symmetric top changes w by I^-1 M dt plus the free motion during the pulse.
    """
    inertia, omega0, t1, dt = (1.0, 1.0, 1.5), (0.2, 1.0, 30.0), 0.3, 3e-7
    torque = (3.0e6, -1.5e6, 0.0)
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.0, 0.5),
                  duration=0.5, output_interval=0.1, impacts=(Impact(t1, dt, torque),),
                  integrator=IntegratorSettings(method=method, step=1e-3))
    r = simulate(sc, t_eval=[t1, t1 + dt, 0.5])
    lam = (inertia[2] - inertia[0]) / inertia[0] * omega0[2]
    w1 = np.exp(1j * lam * t1) * (omega0[0] + 1j * omega0[1])
    e = np.exp(1j * lam * dt)
    m = (torque[0] + 1j * torque[1]) / inertia[0]
    w2 = e * w1 + m * (e - 1) / (1j * lam)
    impulse = np.linalg.norm(np.array(torque) * dt / np.array(inertia))
    np.testing.assert_allclose(r.omega[0, :2], [w1.real, w1.imag], atol=1e-12 * 30)
    assert np.linalg.norm(r.omega[1, :2] - [w2.real, w2.imag]) <= 1e-9 * impulse
    w3 = np.exp(1j * lam * (0.5 - t1 - dt)) * w2
    np.testing.assert_allclose(r.omega[2, :2], [w3.real, w3.imag], atol=1e-9)


@pytest.mark.parametrize('method', sorted(SPLITTING_METHODS))
def test_pulses_in_the_tidal_field_match_a_tight_reference(method):
    """
    Pulses in the tidal field match a tight reference.

    Fig 9 body, one body pulse and one orbital-frame pulse: the splitting method lands on
    every pulse edge and integrates each pulse with its own torque.
    """
    impacts = (Impact(0.3, 3e-7, (3e6, -1e6, 5e5)),
               Impact(0.61, 2e-3, (0.0, 2e3, 1e3), frame='orbital'))
    sc = fig9(duration=1.0, output_interval=0.1, impacts=impacts)
    t_eval = [0.3, 0.3 + 3e-7, 0.61, 0.612, 1.0]
    ref = simulate(sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-13,
                                                            atol=1e-13)), t_eval)
    # the orbital pulse turns with the body (~120 rad/yr): order 2 needs the smaller step
    r = simulate(sc.replace(integrator=IntegratorSettings(
        method=method, step=1e-4 if method == 'splitting' else 1e-3)), t_eval)
    dw_ref = ref.omega[1] - ref.omega[0]
    dw = r.omega[1] - r.omega[0]
    # Strang: local O(dt^3) error
    assert np.linalg.norm(dw - dw_ref) <= 1e-8 * np.linalg.norm(dw_ref)
    assert np.max(np.abs(r.omega - ref.omega)) < 1e-5 * 30


def test_stepper_lands_on_t_bound_with_equal_steps():
    problem = SegmentProblem((1.0, 1.2, 1.5), 1.0)
    settings = IntegratorSettings(method='splitting4', step=1e-2)
    y0 = np.array([0.1, 0.2, 3.0, 1.0, 0.0, 0.0, 0.0])
    st = SPLITTING_METHODS['splitting4'](None, 0.25, y0, 0.5, settings, problem=problem)
    times = []
    while st.status != FINISHED:
        st.step()
        times.append(st.t)
    assert st.t == 0.5 and len(times) == 25
    np.testing.assert_allclose(np.diff([0.25] + times), 0.01, rtol=1e-12)
    assert np.linalg.norm(st.y[3:]) == pytest.approx(1.0, abs=1e-14)

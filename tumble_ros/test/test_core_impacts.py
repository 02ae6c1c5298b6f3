"""Impacts (paper Fig. 10): exact pulses for every integrator, thanks to splitting."""
import numpy as np
import pytest

from tumble_ros.core import Impact, IntegratorSettings, METHODS, Propagator, Scenario, simulate

INERTIA = (1.0, 1.0, 1.5)
OMEGA0 = (0.2, 1.0, 30.0)
T1, DT = 0.3, 3e-7  # the paper's pulse length


def free_transverse(w, t, lam, m=0j):
    """
    Return w = wx + i wy of a symmetric top under a constant transverse body torque.

    dw/dt = i lam w + m, so w(t) = e^{i lam t} w0 + m (e^{i lam t} - 1) / (i lam).
    """
    e = np.exp(1j * lam * t)
    return e * w + (m * (e - 1) / (1j * lam) if m else 0)


def scenario(method, impacts, attitude='quaternion'):
    return Scenario(inertia=INERTIA, orbit_rate=0.0, omega0=OMEGA0, euler0=(0.5, 0.0, 0.5),
                    attitude=attitude, duration=0.5, output_interval=0.1, impacts=tuple(impacts),
                    integrator=IntegratorSettings(method=method, rtol=1e-11, atol=1e-12,
                                                  step=1e-4))


@pytest.mark.parametrize('method', sorted(METHODS))
def test_transverse_body_pulse_changes_omega_by_its_impulse(method):
    torque = (3.0e6, -1.5e6, 0.0)  # |dw| ~ 1 rad/yr over 3e-7 yr
    sc = scenario(method, [Impact(T1, DT, torque)])
    r = simulate(sc, t_eval=[0.0, T1, T1 + DT])
    assert r.success, r.message
    lam = (INERTIA[2] - INERTIA[0]) / INERTIA[0] * OMEGA0[2]
    w1 = free_transverse(OMEGA0[0] + 1j * OMEGA0[1], T1, lam)
    w2 = free_transverse(w1, DT, lam, (torque[0] + 1j * torque[1]) / INERTIA[0])
    impulse = np.array(torque) * DT / np.array(INERTIA)  # I^-1 M dt
    measured = r.omega[2] - r.omega[1]
    expected = np.array([w2.real - w1.real, w2.imag - w1.imag, 0.0])  # impulse + free motion
    # the free part is small...
    assert np.linalg.norm(expected - impulse) < 1e-4 * np.linalg.norm(impulse)
    # ...but accounted for
    assert np.linalg.norm(measured - expected) <= 1e-5 * np.linalg.norm(impulse)
    np.testing.assert_allclose(r.omega[1, :2], [w1.real, w1.imag], atol=1e-6)


@pytest.mark.parametrize('method', sorted(METHODS))
def test_axial_orbital_frame_pulse_spins_up_exactly(method):
    """A pulse about Z' on a body spinning about Z' = body z changes wz by Mz dt / Iz."""
    impact = Impact(T1, DT, (0.0, 0.0, 2.0e6), frame='orbital')
    sc = scenario(method, [impact]).replace(omega0=(0.0, 0.0, 30.0), euler0=(0.5, 0.0, 0.0))
    r = simulate(sc, t_eval=[T1, T1 + DT, 0.5])
    assert r.success, r.message
    dwz = 2.0e6 * DT / INERTIA[2]
    assert r.omega[1, 2] - r.omega[0, 2] == pytest.approx(dwz, rel=1e-5)
    assert r.omega[2, 2] == pytest.approx(30.0 + dwz, rel=1e-9)


def test_unsplit_adaptive_integration_steps_over_the_pulse():
    """Without tstops, dop853 never samples inside a 3e-7 yr pulse (paper Fig. 10, 'ode')."""
    torque = (3.0e6, 0.0, 0.0)
    sc = scenario('dop853', [Impact(T1, DT, torque)])
    split = simulate(sc, t_eval=[0.0, 0.5])
    unsplit = simulate(sc, t_eval=[0.0, 0.5], split_impacts=False)
    free = simulate(sc.replace(impacts=()), t_eval=[0.0, 0.5])
    kick = np.linalg.norm(np.array(torque) * DT)
    assert np.linalg.norm(split.omega[-1] - free.omega[-1]) > 0.5 * kick
    assert np.linalg.norm(unsplit.omega[-1] - free.omega[-1]) < 1e-6 * kick


def test_impact_scheduled_while_running_is_applied_exactly():
    sc = scenario('dop853', [])
    prop = Propagator(sc)
    prop.advance_to(0.1)
    before = prop.advance_to(0.2).copy()  # the stepper has run past 0.2 internally
    prop.schedule(Impact(0.2, DT, (0.0, 0.0, 1.5e6)))
    after = prop.advance_to(0.2 + DT)
    assert after[2] - before[2] == pytest.approx(1.5e6 * DT / INERTIA[2], rel=1e-6)


def test_impact_in_the_past_is_refused():
    prop = Propagator(scenario('rk4', []))
    prop.advance_to(0.2)
    with pytest.raises(ValueError, match='impact.start'):
        prop.schedule(Impact(0.1, DT, (1.0, 0.0, 0.0)))


def test_completed_impacts_report_their_measured_delta_omega():
    impacts = [Impact(0.1, DT, (0.0, 0.0, 1.5e6)), Impact(0.25, DT, (0.0, 0.0, -3.0e6), 'orbital')]
    sc = scenario('rk4', impacts).replace(omega0=(0.0, 0.0, 30.0), euler0=(0.5, 0.0, 0.0))
    prop = Propagator(sc)
    prop.advance_to(0.2)
    first = prop.pop_completed_impacts()
    assert [i for i, _, _ in first] == [impacts[0]]
    _, y1, y2 = first[0]
    assert y2[2] - y1[2] == pytest.approx(1.5e6 * DT / INERTIA[2], rel=1e-9)
    assert prop.pop_completed_impacts() == []  # reported once
    prop.advance_to(0.25 + DT)  # exactly the end of the second pulse
    (impact, y1, y2), = prop.pop_completed_impacts()
    assert impact == impacts[1] and y2[2] - y1[2] == pytest.approx(-3.0e6 * DT / INERTIA[2],
                                                                   rel=1e-9)

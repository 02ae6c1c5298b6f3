"""
The spin state of a tumbler (core/model/spinstate.py) against closed forms and simulated motion.

The rotation period against the time between the body-frame w's returns in a simulation, the
precession period against the turning of the reference axis about L in the simulated attitude,
both over many periods of torque-free motion; the symmetric top against its closed form.
"""
import math

import numpy as np
import pytest

from tumble_ros.core import IntegratorSettings, Scenario, simulate
from tumble_ros.core.model.rotation import euler_to_quaternion, quaternion_to_matrix
from tumble_ros.core.model.spinstate import spin_state


def test_the_symmetric_top_has_its_closed_form():
    inertia, w = (1.0, 1.0, 1.6), np.array([3.0, -4.0, 20.0])
    s = spin_state(w, inertia)
    assert s.mode == 'SAM'
    assert s.rotation_period == pytest.approx(2 * math.pi * 1.0 / (0.6 * 20.0), rel=1e-13)
    momentum = math.sqrt(3.0 ** 2 + 4.0 ** 2 + (1.6 * 20.0) ** 2)
    assert s.precession_period == pytest.approx(2 * math.pi * 1.0 / momentum, rel=1e-10)


@pytest.mark.parametrize('inertia, omega0, mode', [
    ((1.0, 1.5, 2.0), (2.0, 1.0, 10.0), 'SAM'),
    ((1.0, 1.5, 2.0), (10.0, 1.0, 2.0), 'LAM'),
    ((2.0, 1.0, 1.4), (1.0, 6.0, 2.5), 'LAM'),      # unsorted moments: the long axis is y
])
def test_periods_match_the_simulated_torque_free_motion(inertia, omega0, mode):
    s = spin_state(omega0, inertia, euler_to_quaternion(0.3, 0.2, 0.9))
    assert s.mode == mode
    span = 12 * max(s.rotation_period, s.precession_period)
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.3, 0.2, 0.9),
                  duration=span, output_interval=s.rotation_period / 400,
                  allow_unphysical_inertia=True,
                  integrator=IntegratorSettings(method='dop853', rtol=1e-12, atol=1e-12))
    r = simulate(sc)
    order = np.argsort(inertia, kind='stable')
    # the sn component (the middle axis) crosses zero upwards once per rotation period
    w2 = r.omega[:, order[1]]
    up = np.flatnonzero((w2[:-1] < 0) & (w2[1:] >= 0))
    crossings = r.t[up] - w2[up] * (r.t[up + 1] - r.t[up]) / (w2[up + 1] - w2[up])
    measured = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert len(crossings) >= 10
    assert measured == pytest.approx(s.rotation_period, rel=1e-6)
    # the reference axis (I3 in a SAM, I1 in a LAM) turns about L once per precession period
    axis = order[2] if mode == 'SAM' else order[0]
    c = np.array([quaternion_to_matrix(q) for q in r.quaternion])
    momentum = c[0] @ (np.array(inertia) * r.omega[0])
    l_hat = momentum / np.linalg.norm(momentum)
    e1 = np.cross(l_hat, [1.0, 0.0, 0.0] if abs(l_hat[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(l_hat, e1)
    ref = c[:, :, axis]
    azimuth = np.unwrap(np.arctan2(ref @ e2, ref @ e1))
    k = int(round(10 * s.rotation_period / sc.output_interval))   # 10 rotation periods
    rate = (azimuth[k] - azimuth[0]) / (r.t[k] - r.t[0])
    assert 2 * math.pi / abs(rate) == pytest.approx(s.precession_period, rel=1e-7)


def test_the_mode_follows_the_dynamic_moment():
    inertia = (1.0, 2.0, 3.0)
    sam = spin_state((0.1, 0.1, 1.0), inertia)
    lam = spin_state((1.0, 0.1, 0.1), inertia)
    assert sam.mode == 'SAM' and sam.dynamic_inertia > 2.0
    assert lam.mode == 'LAM' and lam.dynamic_inertia < 2.0
    principal = spin_state((0.0, 0.0, 5.0), inertia)
    assert principal.mode == 'principal'
    assert principal.rotation_period == pytest.approx(2 * math.pi / 5.0)
    # on the separatrix (D = I2) the period is infinite
    w1 = 1.0
    w3 = math.sqrt(1.0 * (2.0 - 1.0) / (3.0 * (3.0 - 2.0))) * w1
    assert spin_state((w1, 0.0, w3), inertia).mode == 'separatrix'


def test_the_pole_is_the_angular_momentum_direction():
    s = spin_state((0.0, 0.0, 5.0), (1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0))
    assert s.pole == pytest.approx((0.0, 0.0, 1.0))
    assert s.pole_latitude == pytest.approx(math.pi / 2)
    tilted = spin_state((0.0, 0.0, 5.0), (1.0, 2.0, 3.0), euler_to_quaternion(0.0, 0.0, 0.5))
    assert tilted.pole_latitude == pytest.approx(math.pi / 2 - 0.5)


@pytest.mark.parametrize('omega, inertia', [((0, 0, 0), (1, 2, 3)), ((1, 2, math.nan), (1, 2, 3)),
                                            ((1, 2, 3), (1, 0, 3))])
def test_bad_input_is_refused(omega, inertia):
    with pytest.raises(ValueError, match='spin_state'):
        spin_state(omega, inertia)


def _precession_by_quadrature(inertia, omega, state) -> float:
    """
    2 pi / <phi'> over one rotation period, phi' integrated along the Euler-Poinsot motion.

    The independent check of the elliptic-integral closed form: phi' = L (Ia wa^2 + Ib wb^2) /
    (Ia^2 wa^2 + Ib^2 wb^2), a and b the axes other than the reference (I3 for a SAM, I1 for a
    LAM), integrated with scipy's DOP853 at rtol 1e-12.
    """
    from scipy.integrate import solve_ivp

    order = np.argsort(inertia)
    i = np.asarray(inertia, dtype=float)[order]
    w0 = np.asarray(omega, dtype=float)[order]
    a, b = (0, 1) if state.mode == 'SAM' else (1, 2)

    def rhs(t, y):
        w = y[:3]
        dw = [(i[1] - i[2]) * w[1] * w[2] / i[0], (i[2] - i[0]) * w[2] * w[0] / i[1],
              (i[0] - i[1]) * w[0] * w[1] / i[2]]
        rate = (state.momentum * (i[a] * w[a] ** 2 + i[b] * w[b] ** 2)
                / (i[a] ** 2 * w[a] ** 2 + i[b] ** 2 * w[b] ** 2))
        return [*dw, rate]

    sol = solve_ivp(rhs, (0.0, state.rotation_period), [*w0, 0.0], method='DOP853', rtol=1e-12,
                    atol=1e-14 * max(1.0, float(np.max(np.abs(w0)))))
    return 2 * math.pi * state.rotation_period / abs(sol.y[3, -1])


def _polhode_point(inertia, d: float) -> np.ndarray:
    """Return a w with 2E = 1, L^2 = D, no intermediate component (SAM for D > I2, LAM below)."""
    i1, _, i3 = inertia
    return np.array([math.sqrt((i3 - d) / (i1 * (i3 - i1))), 0.0,
                     math.sqrt((d - i1) / (i3 * (i3 - i1)))])


@pytest.mark.parametrize('seed', range(12))
def test_the_precession_period_closed_form_is_the_quadrature(seed):
    """Pi(n, k) by Carlson's R_F, R_J against the quadrature: SAMs, LAMs, near the separatrix."""
    rng = np.random.default_rng(seed)
    inertia = np.sort(rng.uniform(0.3, 1.0, 3))
    i1, i2, i3 = inertia
    cases = [rng.normal(size=3) * rng.uniform(1.0, 50.0) for _ in range(6)]
    # D within 1e-6 I2 of the separatrix on both sides (closer, the periods themselves are
    # ill-conditioned: the rounding of L^2 / 2E moves D - I2 and with it K(k) and the
    # quadrature's end time), and near the pure spins
    near = 1e-6 * i2
    cases += [_polhode_point(inertia, d) * 20.0 for d in (
        i2 + min(near, (i3 - i2) / 2), i2 - min(near, (i2 - i1) / 2),
        i3 - 1e-3 * (i3 - i2), i1 + 1e-3 * (i2 - i1),
        i3 - 1e-12 * (i3 - i2), i1 + 1e-12 * (i2 - i1))]      # a wobble of ~1e-6 rad
    modes = []
    for omega in cases:
        state = spin_state(omega, inertia)
        modes.append(state.mode)
        assert state.precession_period == pytest.approx(
            _precession_by_quadrature(inertia, omega, state), rel=1e-9), (inertia, omega)
    assert {'SAM', 'LAM'} <= set(modes)


def test_a_sphere_spins_about_a_principal_axis():
    s = spin_state([1.0, 2.0, 2.0], [0.5, 0.5, 0.5])
    assert s.mode == 'principal' and s.rotation_period == pytest.approx(2 * math.pi / 3.0)


@pytest.mark.parametrize('omega', [(1e-9, 1e-9, 30.0), (1e-7, 0.0, 30.0), (30.0, 1e-9, 0.0),
                                   (30.0, 0.0, 1e-10)])
def test_a_nearly_pure_spin_has_finite_periods(omega):
    """Close to a principal rotation the precession tends to a finite limit, not 0/0."""
    inertia = (0.64, 0.97, 1.0)
    state = spin_state(omega, inertia)
    assert state.mode in ('SAM', 'LAM')
    assert math.isfinite(state.precession_period) and math.isfinite(state.rotation_period)
    assert state.precession_period == pytest.approx(
        _precession_by_quadrature(np.array(inertia), np.array(omega), state), rel=1e-9)

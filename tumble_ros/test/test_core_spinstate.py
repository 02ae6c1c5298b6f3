"""
The spin state of a tumbler (core/spinstate.py) against closed forms and simulated motion.

The rotation period against the time between the body-frame w's returns in a simulation, the
precession period against the turning of the reference axis about L in the simulated attitude,
both over many periods of torque-free motion; the symmetric top against its closed form.
"""
import math

import numpy as np
import pytest

from tumble_ros.core import IntegratorSettings, Scenario, simulate
from tumble_ros.core.rotation import euler_to_quaternion, quaternion_to_matrix
from tumble_ros.core.spinstate import spin_state


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

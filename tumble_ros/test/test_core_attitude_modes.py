"""Euler-angle and quaternion attitude integration agree, and where Euler breaks down."""
import math

import numpy as np

from tumble_ros.core import angular_momentum_orbital, IntegratorSettings, Scenario, simulate
from tumble_ros.core.model.rotation import quaternion_to_matrix

TIGHT = IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-14)


def test_euler_and_quaternion_modes_agree_away_from_the_singularity():
    # Paper Fig 5 (a = 0.5, theta = 0.5) with an asymmetric twist so every term matters.
    sc = Scenario(inertia=(1.0, 1.1, 1.5), omega0=(0.0, 1.0, 30.0), euler0=(0.5, 0.0, 0.5),
                  duration=2.0, output_interval=0.002, integrator=TIGHT)
    q = simulate(sc)
    e = simulate(sc.replace(attitude='euler'))
    assert q.success and e.success
    np.testing.assert_allclose(e.omega, q.omega, rtol=0, atol=1e-8 * 30)
    np.testing.assert_allclose(e.quaternion, q.quaternion, rtol=0, atol=1e-8)
    np.testing.assert_allclose(e.euler, q.euler, rtol=0, atol=1e-8 * np.abs(q.euler).max())
    # The quaternion mode's Euler angles are continuous (unwrapped): psi grows ~ 30 rad/yr.
    assert q.euler[-1, 1] > 50.0
    assert np.max(np.abs(np.diff(q.euler[:, :2], axis=0))) < 1.0


def test_quaternion_mode_is_accurate_through_theta_zero_where_euler_cannot_go():
    """
    theta0 = 1e-4 and a free symmetric top whose figure axis sweeps through Z'.

    psi0 is chosen so that Z' lies on the figure axis' precession cone: theta passes
    through 0, where eq 15 divides by zero.
    """
    inertia, w_perp, wz, theta0 = (1.0, 1.0, 1.5), 1.0, 30.0, 1e-4
    psi0 = math.acos(inertia[2] * wz * math.tan(theta0 / 2) / (inertia[0] * w_perp))
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=(0.0, w_perp, wz),
                  euler0=(0.3, psi0, theta0),
                  duration=1.0, output_interval=0.001, integrator=TIGHT)
    q = simulate(sc)
    assert q.success, q.message
    c = np.array([quaternion_to_matrix(x) for x in q.quaternion])
    momentum = angular_momentum_orbital(q.omega, c, inertia)
    assert (np.max(np.linalg.norm(momentum - momentum[0], axis=1))
            <= 1e-10 * np.linalg.norm(momentum[0]))
    # the figure axis (body z in orbital axes) really comes within 1e-6 rad of Z'
    fine = simulate(sc.replace(duration=0.2, output_interval=1e-5))
    axis_z = np.array([quaternion_to_matrix(x)[2, 2] for x in fine.quaternion])
    assert np.min(np.arccos(np.clip(axis_z, -1, 1))) < 1e-6

    e = simulate(sc.replace(attitude='euler'))
    assert not e.success
    assert 'singular' in e.message and 'quaternion' in e.message
    assert e.t[-1] < 0.2
    assert np.all(np.isfinite(e.omega)) and np.all(np.isfinite(e.euler))


def test_tracked_phi_and_psi_are_right_well_below_theta_0_1():
    """
    Follow phi and psi through their fast turns near theta = 0 (theta0 = 0.01).

    The quaternion mode derives them from the attitude; the Euler mode integrates them (eq 15)
    and is continuous by construction: the two agree, 2pi multiples included.
    """
    sc = Scenario(omega0=(0.0, 1.0, 30.0), euler0=(0.5, 0.0, 0.01), duration=2.0,
                  integrator=IntegratorSettings(method='dop853', rtol=1e-11, atol=1e-13))
    quaternion_mode, euler_mode = simulate(sc), simulate(sc.replace(attitude='euler'))
    turns = np.ptp(euler_mode.euler[:, :2], axis=0) / (2 * math.pi)
    assert euler_mode.success and turns.min() > 4  # phi and psi both turn several times
    np.testing.assert_allclose(quaternion_mode.euler, euler_mode.euler, rtol=0, atol=1e-7)

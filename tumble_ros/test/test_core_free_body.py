"""Torque-free motion (orbit_rate = 0): closed forms and conserved quantities."""
import itertools

import numpy as np
import pytest

from tumble_ros.core import (angular_momentum_orbital, IntegratorSettings, kinetic_energy, METHODS,
                             Scenario, simulate)
from tumble_ros.core.model.rotation import quaternion_to_matrix

TIGHT = IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-13)


def symmetric_top_omega(t, inertia, omega0):
    """Return the closed form for Ix = Iy: w_perp turns at lam = (Iz - Ix)/Ix wz, wz constant."""
    ix, _, iz = inertia
    wx0, wy0, wz0 = omega0
    lam = (iz - ix) / ix * wz0
    c, s = np.cos(lam * t), np.sin(lam * t)
    return np.stack([wx0 * c - wy0 * s, wx0 * s + wy0 * c, np.full_like(t, wz0)], -1)


def invariants(result, inertia):
    c = np.array([quaternion_to_matrix(q) for q in result.quaternion])
    energy = kinetic_energy(result.omega, inertia)
    momentum = angular_momentum_orbital(result.omega, c, inertia)
    return energy, momentum


def rel_drift(x):
    x = np.asarray(x)
    ref = x[0]
    return np.max(np.linalg.norm(np.atleast_2d((x - ref).T).T, axis=-1)) / np.linalg.norm(ref)


def test_symmetric_top_matches_closed_form_and_conserves_invariants():
    inertia = (1.0, 1.0, 1.5)
    omega0 = (0.3, 1.0, 30.0)
    spin_period = 2 * np.pi / (0.5 * 30.0)
    duration = 100 * spin_period
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.2, 0.7),
                  duration=duration, output_interval=duration / 2000, integrator=TIGHT)
    r = simulate(sc)
    assert r.success, r.message
    expected = symmetric_top_omega(r.t, inertia, omega0)
    np.testing.assert_allclose(r.omega, expected, atol=1e-9 * np.linalg.norm(omega0))
    energy, momentum = invariants(r, inertia)
    assert rel_drift(energy) <= 1e-10
    assert rel_drift(np.linalg.norm(momentum, axis=1)) <= 1e-10
    assert rel_drift(momentum) <= 1e-10  # L is fixed in inertial space, not only its length


def test_asymmetric_body_conserves_energy_and_momentum():
    inertia = (1.0, 1.6, 2.2)
    omega0 = (3.0, 0.5, 10.0)
    duration = 100 * 2 * np.pi / 10.0
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.2, 0.7),
                  duration=duration, output_interval=duration / 2000, integrator=TIGHT)
    r = simulate(sc)
    assert r.success, r.message
    assert np.ptp(r.omega[:, 0]) > 1.0  # it really tumbles: w changes in the body
    energy, momentum = invariants(r, inertia)
    assert rel_drift(energy) <= 1e-10
    assert rel_drift(momentum) <= 1e-10


CASES = list(itertools.product(sorted(METHODS), ['quaternion', 'euler']))


@pytest.mark.parametrize('method,attitude', CASES)
def test_every_method_and_attitude_reproduces_the_symmetric_top(method, attitude):
    inertia = (1.0, 1.0, 1.5)
    omega0 = (0.0, 1.0, 30.0)
    settings = IntegratorSettings(method=method, rtol=1e-10, atol=1e-12, step=2e-4)
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=omega0, euler0=(0.5, 0.0, 0.5),
                  attitude=attitude, duration=1.0, output_interval=0.01, integrator=settings)
    r = simulate(sc)
    assert r.success, r.message
    np.testing.assert_allclose(r.omega, symmetric_top_omega(r.t, inertia, omega0), atol=1e-6)
    _, momentum = invariants(r, inertia)
    assert rel_drift(momentum) <= 1e-6

"""The gravity-gradient torque (eq 12) against an independent brute-force sum."""
import numpy as np
import pytest

from tumble_ros.core.model.dynamics import ATTITUDE_MODELS
from tumble_ros.core.model.rotation import euler_to_matrix, quaternion_to_matrix
from tumble_ros.core.torques import gravity_gradient_torque, sun_direction_orbital

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 11


def point_cloud(rng, n=400):
    """
    Random masses, centred, expressed in their principal axes; returns (m, r, I).

    ``rng`` is the calling test's own generator (other test files use this function too).
    """
    m = rng.uniform(0.5, 1.5, n)
    r = rng.normal(size=(n, 3)) * np.array([1.0, 0.7, 0.4])
    r -= (m[:, None] * r).sum(0) / m.sum()
    tensor = sum(mi * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for mi, ri in zip(m, r))
    moments, axes = np.linalg.eigh(tensor)
    return m, r @ axes, moments


@pytest.mark.parametrize('trial', range(5))
def test_eq12_equals_sum_of_point_mass_torques(trial):
    rng = np.random.default_rng((SEED, trial))           # a body and a direction per trial
    m, r, inertia = point_cloud(rng)
    ws = 1.7
    distance = 1e5  # body size ~1: the quadrupole approximation holds to ~1e-5
    gm = ws**2 * distance**3  # GM / R0^3 = ws^2
    u = rng.normal(size=3)
    u /= np.linalg.norm(u)
    sun = distance * u  # the Sun, seen from the centre of mass, in body axes
    d = sun - r
    g = gm * d / np.linalg.norm(d, axis=1)[:, None] ** 3
    brute = np.sum(np.cross(r, m[:, None] * g), axis=0)
    eq12 = gravity_gradient_torque(u, inertia, ws)
    assert np.linalg.norm(eq12) > 0.1
    np.testing.assert_allclose(eq12, brute, rtol=1e-4, atol=1e-4 * np.linalg.norm(eq12))


def test_eq12_component_form():
    inertia = np.array([1.0, 1.3, 1.9])
    u = np.array([0.2, -0.5, 0.3])
    k = 3 * 0.8**2
    expected = k * np.array([u[1] * u[2] * (inertia[2] - inertia[1]),
                             u[0] * u[2] * (inertia[0] - inertia[2]),
                             u[0] * u[1] * (inertia[1] - inertia[0])])
    np.testing.assert_allclose(gravity_gradient_torque(u, inertia, 0.8), expected, rtol=1e-14)


@pytest.mark.parametrize('mode', sorted(ATTITUDE_MODELS))
def test_rhs_is_eulers_equation_with_eq12(mode):
    """
    The hot-path RHS equals I^-1 (M - w x I w), M from eq 12 with u = R R0(t)/R0.

    This is where the typo of eq 14 (third line) would show: Ix != Iy here.
    """
    model = ATTITUDE_MODELS[mode]
    inertia = np.array([1.0, 1.4, 2.1])
    ws, t = 1.3, 0.77
    angles = (0.4, -1.1, 0.9)
    w = np.array([0.5, -2.0, 7.0])
    y = np.concatenate([w, model.from_euler(*angles)])
    r = euler_to_matrix(*angles)
    u = r @ sun_direction_orbital(t, ws)
    m = gravity_gradient_torque(u, inertia, ws)
    expected = (m - np.cross(w, inertia * w)) / inertia
    rhs = model.make_rhs(inertia, ws)
    np.testing.assert_allclose(rhs(t, y)[:3], expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize('mode', sorted(ATTITUDE_MODELS))
def test_rhs_adds_pulse_torques_in_their_frames(mode):
    model = ATTITUDE_MODELS[mode]
    inertia = np.array([1.0, 1.4, 2.1])
    angles = (0.4, -1.1, 0.9)
    y = np.concatenate([[0.5, -2.0, 7.0], model.from_euler(*angles)])
    free = model.make_rhs(inertia, 1.0)(0.3, y)[:3]
    m_body = np.array([3.0, -1.0, 2.0])
    m_orb = np.array([-2.0, 0.5, 4.0])
    pulsed = model.make_rhs(inertia, 1.0, m_body, m_orb)(0.3, y)[:3]
    c = model.to_matrix(y[3:])
    np.testing.assert_allclose(pulsed - free, (m_body + c.T @ m_orb) / inertia, rtol=1e-12)
    np.testing.assert_allclose(c, quaternion_to_matrix(
        ATTITUDE_MODELS['quaternion'].from_euler(*angles)),
                               atol=1e-14)

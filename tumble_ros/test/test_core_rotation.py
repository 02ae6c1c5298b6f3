"""Attitude conventions: the paper's R(phi, psi, theta), quaternions, round trips."""
import math

import numpy as np
import pytest

from tumble_ros.core.model.rotation import (euler_to_matrix, euler_to_quaternion, matrix_to_euler,
                                            matrix_to_quaternion, quaternion_multiply,
                                            quaternion_to_euler, quaternion_to_matrix)

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 7
#: Euler angles (phi, psi, theta) [rad] of the parametrised tests: theta in (0, pi)
MATRIX_ANGLES = np.random.default_rng(SEED).uniform([-3, -3, 0.01], [3, 3, 3.1], size=(20, 3))
ROUND_TRIP_ANGLES = np.random.default_rng(SEED + 1).uniform(
    [-3, -3, 1e-6], [3, 3, math.pi - 1e-6], size=(20, 3))


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1.0]])  # passive (frame) rotation


def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, s], [0, -s, c]])


@pytest.mark.parametrize('angles', MATRIX_ANGLES)
def test_matrix_is_product_of_elementary_rotations(angles):
    phi, psi, theta = angles
    np.testing.assert_allclose(euler_to_matrix(phi, psi, theta), rz(psi) @ rx(theta) @ rz(phi),
                               atol=1e-15)


@pytest.mark.parametrize('angles', ROUND_TRIP_ANGLES)
def test_euler_matrix_quaternion_round_trips(angles):
    r = euler_to_matrix(*angles)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0)
    np.testing.assert_allclose(matrix_to_euler(r), angles, atol=1e-9)
    q = euler_to_quaternion(*angles)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    np.testing.assert_allclose(quaternion_to_matrix(q), r.T, atol=1e-14)
    np.testing.assert_allclose(quaternion_to_euler(q), angles, atol=1e-9)


def test_quaternion_matrix_round_trip_all_branches():
    rng = np.random.default_rng(SEED)
    for q in rng.normal(size=(200, 4)):
        q /= np.linalg.norm(q)
        q = q if q[0] >= 0 else -q
        np.testing.assert_allclose(matrix_to_quaternion(quaternion_to_matrix(q)), q, atol=1e-13)


def test_quaternion_product_composes_rotations():
    rng = np.random.default_rng(SEED)
    p, q = rng.normal(size=4), rng.normal(size=4)
    p, q = p / np.linalg.norm(p), q / np.linalg.norm(q)
    np.testing.assert_allclose(quaternion_to_matrix(quaternion_multiply(p, q)),
                               quaternion_to_matrix(p) @ quaternion_to_matrix(q), atol=1e-14)


def test_gimbal_lock_keeps_the_rotation():
    r = euler_to_matrix(0.4, 0.3, 0.0)
    np.testing.assert_allclose(euler_to_matrix(*matrix_to_euler(r)), r, atol=1e-15)


def test_quaternion_kinematics_match_matrix_kinematics():
    """dq/dt = 1/2 q*(0, w) must give dC/dt = C [w x] for C = body -> orbital."""
    rng = np.random.default_rng(SEED)
    from tumble_ros.core.model.dynamics import ATTITUDE_MODELS

    rhs = ATTITUDE_MODELS['quaternion'].make_rhs((1.0, 2.0, 2.5), 0.0)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w = np.array([0.3, -1.2, 2.0])
    dq = rhs(0.0, np.concatenate([w, q]))[3:]
    h = 1e-6
    dc = (quaternion_to_matrix(q + h * dq) - quaternion_to_matrix(q - h * dq)) / (2 * h)
    wx = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    np.testing.assert_allclose(dc, quaternion_to_matrix(q) @ wx, atol=1e-8)


def test_euler_kinematics_match_matrix_kinematics():
    """Paper eq 15 (as printed) must give dR/dt = -[w x] R for R = orbital -> body."""
    from tumble_ros.core.model.dynamics import ATTITUDE_MODELS

    rhs = ATTITUDE_MODELS['euler'].make_rhs((1.0, 2.0, 2.5), 0.0)
    e = np.array([0.7, -0.4, 1.1])
    w = np.array([0.3, -1.2, 2.0])
    de = rhs(0.0, np.concatenate([w, e]))[3:]
    h = 1e-6
    dr = (euler_to_matrix(*(e + h * de)) - euler_to_matrix(*(e - h * de))) / (2 * h)
    wx = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    np.testing.assert_allclose(dr, -wx @ euler_to_matrix(*e), atol=1e-8)


def test_quaternion_to_euler_is_the_matrix_paths_floats_bit_for_bit():
    """quaternion_to_euler (no arrays: a comparator's anchor per impact) = matrix_to_euler(C.T)."""
    rng = np.random.default_rng(23)
    quaternions = rng.normal(size=(20_000, 4))
    quaternions[::7, 1:3] = 0.0     # theta = 0: gimbal lock
    quaternions[::11, 0] = quaternions[::11, 3] = 0.0   # theta = pi
    quaternions[::13] = quaternions[::13] * 1e-100       # not normalised, tiny
    quaternions[~quaternions.any(axis=1), 0] = 1.0     # (no zero quaternion: no rotation)
    for q in quaternions:
        expected = matrix_to_euler(quaternion_to_matrix(q).T)
        assert np.array(quaternion_to_euler(q)).tobytes() == np.array(expected).tobytes()

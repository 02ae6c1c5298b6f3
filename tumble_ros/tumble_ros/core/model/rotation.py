"""
Attitude representations: the paper's Euler angles, rotation matrices and unit quaternions.

Frames
------
* orbital (inertial) frame X'Y'Z': Z' normal to the orbit plane, the Sun at
  R0(t) = R0 [sin ws t, cos ws t, 0] as seen from the asteroid's centre of mass;
* body frame XYZ: the principal axes of inertia.

Conventions (exactly as printed in the paper, Section 1)
--------------------------------------------------------
* Euler angles (phi, psi, theta), z-x-z, with the nodal line 'w':
  ``R(phi, psi, theta) = Rz(psi) @ Rx(theta) @ Rz(phi)`` maps orbital-frame components
  to body-frame components: ``v_body = R @ v_orbital``.
* Quaternions are unit, scalar first ``q = (q0, q1, q2, q3)``, and rotate body-frame
  components into the orbital frame: ``v_orbital = C(q) @ v_body`` with ``C(q) = R.T``.

All angles are in radians. Nothing here depends on ROS.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from tumble_ros.core.array_types import FloatSequence

__all__ = [
    'quaternions_to_matrices',
    'continuous_quaternions',
    'euler_to_matrix',
    'matrix_to_euler',
    'quaternion_to_matrix',
    'matrix_to_quaternion',
    'euler_to_quaternion',
    'quaternion_to_euler',
    'quaternion_multiply',
]


def euler_to_matrix(phi: float, psi: float, theta: float) -> np.ndarray:
    """Return the paper's matrix R(phi, psi, theta) (orbital -> body components), 3x3."""
    cf, sf = math.cos(phi), math.sin(phi)
    cp, sp = math.cos(psi), math.sin(psi)
    ct, st = math.cos(theta), math.sin(theta)
    return np.array(
        [
            [cf * cp - sf * sp * ct, sf * cp + cf * sp * ct, sp * st],
            [-cf * sp - sf * cp * ct, -sf * sp + cf * cp * ct, cp * st],
            [sf * st, -cf * st, ct],
        ]
    )


def matrix_to_euler(r: np.ndarray) -> tuple[float, float, float]:
    """
    Euler angles (phi, psi, theta) of an orbital -> body matrix, theta in [0, pi].

    phi and psi are returned in (-pi, pi]. At theta = 0 or pi only phi + psi (or
    phi - psi) is defined; psi is then set to 0.
    """
    return _euler_of(r[0, 2], r[1, 2], r[2, 2], r[2, 0], r[2, 1], lambda: (r[0, 1], r[0, 0]))


def _euler_of(r02: float, r12: float, r22: float, r20: float, r21: float,
              locked: Callable[[], tuple[float, float]]) -> tuple[float, float, float]:
    """:func:`matrix_to_euler` from the entries it reads (``locked()``: r01, r00, if needed)."""
    st = math.hypot(r02, r12)
    theta = math.atan2(st, r22)
    if st < 1e-300:
        # Gimbal lock: R = Rz(phi + psi) (theta = 0) or similar; put everything in phi.
        r01, r00 = locked()
        return math.atan2(r01, r00), 0.0, theta
    psi = math.atan2(r02, r12)
    phi = math.atan2(r20, -r21)
    return phi, psi, theta


def quaternion_to_matrix(q: FloatSequence) -> np.ndarray:
    """
    Rotation matrix C(q) (body -> orbital components) of a quaternion, scalar first.

    The quaternion need not be normalised: C is built from q / |q|.
    """
    return np.array(_matrix_rows(q))


def _matrix_rows(q: FloatSequence) -> tuple[tuple[float, float, float], ...]:
    """Return the rows of :func:`quaternion_to_matrix` as floats (the same arithmetic)."""
    q0, q1, q2, q3 = q
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    return (
        (1.0 - s * (q2 * q2 + q3 * q3), s * (q1 * q2 - q0 * q3), s * (q1 * q3 + q0 * q2)),
        (s * (q1 * q2 + q0 * q3), 1.0 - s * (q1 * q1 + q3 * q3), s * (q2 * q3 - q0 * q1)),
        (s * (q1 * q3 - q0 * q2), s * (q2 * q3 + q0 * q1), 1.0 - s * (q1 * q1 + q2 * q2)),
    )


def matrix_to_quaternion(c: np.ndarray) -> np.ndarray:
    """
    Return the unit quaternion (scalar first, q0 >= 0) of a body -> orbital rotation matrix.

    Shepperd's method: picks the numerically largest component first.
    """
    tr = c[0, 0] + c[1, 1] + c[2, 2]
    cand = (tr, c[0, 0], c[1, 1], c[2, 2])
    k = int(np.argmax(cand))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q = (0.25 * s, (c[2, 1] - c[1, 2]) / s, (c[0, 2] - c[2, 0]) / s, (c[1, 0] - c[0, 1]) / s)
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + 2.0 * c[0, 0] - tr)
        q = ((c[2, 1] - c[1, 2]) / s, 0.25 * s, (c[0, 1] + c[1, 0]) / s, (c[0, 2] + c[2, 0]) / s)
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + 2.0 * c[1, 1] - tr)
        q = ((c[0, 2] - c[2, 0]) / s, (c[0, 1] + c[1, 0]) / s, 0.25 * s, (c[1, 2] + c[2, 1]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + 2.0 * c[2, 2] - tr)
        q = ((c[1, 0] - c[0, 1]) / s, (c[0, 2] + c[2, 0]) / s, (c[1, 2] + c[2, 1]) / s, 0.25 * s)
    unit = np.array(q)
    unit /= np.linalg.norm(unit)
    return -unit if unit[0] < 0.0 else unit


def euler_to_quaternion(phi: float, psi: float, theta: float) -> np.ndarray:
    """Return the unit quaternion (body -> orbital, scalar first) of the paper's Euler angles."""
    return matrix_to_quaternion(euler_to_matrix(phi, psi, theta).T)


def quaternion_to_euler(q: FloatSequence) -> tuple[float, float, float]:
    """Return the paper's Euler angles (phi, psi, theta) of a body -> orbital quaternion."""
    # matrix_to_euler(quaternion_to_matrix(q).T) without the arrays (a comparator anchors its
    # model once per impact): the same entries, the same arithmetic, the same floats
    (c00, _, c02), (c10, _, c12), (c20, c21, c22) = _matrix_rows(q)
    return _euler_of(c20, c21, c22, c02, c12, lambda: (c10, c00))


def quaternion_multiply(p: FloatSequence, q: FloatSequence) -> np.ndarray:
    """Hamilton product p * q of two scalar-first quaternions."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return np.array(
        [
            p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
            p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
            p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
            p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0,
        ]
    )


def quaternions_to_matrices(q: np.ndarray) -> np.ndarray:
    """``rotation.quaternion_to_matrix`` for an (..., 4) array (same arithmetic): (..., 3, 3)."""
    q0, q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c = np.empty(q.shape[:-1] + (3, 3))
    c[..., 0, 0] = 1.0 - s * (q2 * q2 + q3 * q3)
    c[..., 0, 1] = s * (q1 * q2 - q0 * q3)
    c[..., 0, 2] = s * (q1 * q3 + q0 * q2)
    c[..., 1, 0] = s * (q1 * q2 + q0 * q3)
    c[..., 1, 1] = 1.0 - s * (q1 * q1 + q3 * q3)
    c[..., 1, 2] = s * (q2 * q3 - q0 * q1)
    c[..., 2, 0] = s * (q1 * q3 - q0 * q2)
    c[..., 2, 1] = s * (q2 * q3 + q0 * q1)
    c[..., 2, 2] = 1.0 - s * (q1 * q1 + q2 * q2)
    return c


def continuous_quaternions(q: np.ndarray, previous: np.ndarray | None = None) -> np.ndarray:
    """
    Normalise (..., n, 4) quaternions; flip signs so that consecutive ones have q.q' >= 0.

    Along the sample axis (-2), as :meth:`Propagator.sample` does one at a time; ``previous``
    (one body, (4,)) is the last quaternion handed out before these. (B, n, 4): B bodies.
    """
    # (components written out: numpy's reductions over 4 cost a loop's set-up per sample; the
    # same bits, summed in their order)
    q = q / np.sqrt((q[..., 0] * q[..., 0] + q[..., 1] * q[..., 1] + q[..., 2] * q[..., 2]
                     + q[..., 3] * q[..., 3])[..., None])
    if q.shape[-2] == 0:
        return q
    after, before = q[..., 1:, :], q[..., :-1, :]
    dots = (after[..., 0] * before[..., 0] + after[..., 1] * before[..., 1]
            + after[..., 2] * before[..., 2] + after[..., 3] * before[..., 3])
    first = -1.0 if previous is not None and np.dot(q[..., 0, :], previous) < 0.0 else 1.0
    flips = np.concatenate([np.full(q.shape[:-2] + (1,), first), np.where(dots < 0.0, -1.0, 1.0)],
                           axis=-1)
    return q * np.cumprod(flips, axis=-1)[..., None]

"""
The samples' post-processing, compiled: the Jacobi integral and continuous quaternions.

A run's samples get two quantities besides its state: the Jacobi integral J of each sample
(``dynamics.jacobi_integral``: J = 1/2 w.I.w + 3/2 ws^2 u.I.u + ws (I w).z', derivation in
docs/physics.md) and its quaternion made continuous (``rotation.continuous_quaternions``:
normalised, its sign flipped where q.q' < 0 with the sample before). numpy computes them with a
pass over memory per operation and a (n, 3, 3) array of rotation matrices (at N = 10^6
bodies and 11 samples, 3.6 s of a 10-s ensemble call); :func:`ensemble_samples` takes one
sample at a time in registers.

One formula, two evaluations: :func:`jacobi_sample` is the formula; numpy evaluates its
Python source on whole arrays (``dynamics.jacobi_integral``: a single body's ``simulate``), the
compiled loop one sample at a time (an ensemble). :func:`quaternion_matrix` repeats
``rotation.quaternions_to_matrices``' arithmetic for one sample (``core.model.rotation`` does
not import the kernels: an import-cycle risk), tied to it bit for bit by a test. Both give
the same bits: the same operations in the same order and no fused multiply-add (numba does not
contract without ``fastmath``: :data:`~.compiling.jit.JIT_OPTIONS`); sin and cos of the
Sun's phase come from numpy, once per time, in both. The continuity is
``rotation.continuous_quaternions``'s rule written as a loop (its cumulative product of signs
as a running sign). test_core_samples.py compares them bit for bit.

* :func:`quaternion_matrix`, :func:`jacobi_sample`: one sample (inlined);
* :func:`ensemble_samples`: an ensemble's bodies b0..b1 in place: J of each sample reached
  (the matrix built in registers), the quaternions made continuous, the samples not reached
  set to NaN.
"""
from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit, jit_inline
from tumble_ros.core.kernels.layout import Array

__all__ = ['quaternion_matrix', 'jacobi_sample', 'ensemble_samples']


@jit_inline
def quaternion_matrix(q0: float, q1: float, q2: float, q3: float
                      ) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Return C (body to orbital) row by row, ``rotation.quaternions_to_matrices``'s bits."""
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    return (1.0 - s * (q2 * q2 + q3 * q3), s * (q1 * q2 - q0 * q3), s * (q1 * q3 + q0 * q2),
            s * (q1 * q2 + q0 * q3), 1.0 - s * (q1 * q1 + q3 * q3), s * (q2 * q3 - q0 * q1),
            s * (q1 * q3 - q0 * q2), s * (q2 * q3 + q0 * q1), 1.0 - s * (q1 * q1 + q2 * q2))


@jit_inline
def jacobi_sample(sx: float, sy: float, w0: float, w1: float, w2: float,
                  c00: float, c01: float, c02: float, c10: float, c11: float, c12: float,
                  c20: float, c21: float, c22: float, i0: float, i1: float, i2: float,
                  orbit_rate: float, tidal: float) -> float:
    """
    Return J of one sample [rad^2/yr^2 x inertia units]: ``dynamics.jacobi_integral``'s bits.

    (sx, sy) = (sin, cos)(ws t), the Sun's direction in orbital axes; w [rad/yr, body axes];
    C body to orbital; (i0, i1, i2) the principal moments; ``tidal`` = 1.5 * ws**2 as Python
    computes it (the caller's), ws = ``orbit_rate`` [rad/yr].
    """
    # u: the Sun's direction in body axes (C^T of it); z: the orbit normal in body axes
    u0, u1, u2 = c00 * sx + c10 * sy, c01 * sx + c11 * sy, c02 * sx + c12 * sy
    kinetic = 0.5 * (w0 * w0 * i0 + w1 * w1 * i1 + w2 * w2 * i2)
    potential = tidal * (u0 * u0 * i0 + u1 * u1 * i1 + u2 * u2 * i2)
    return kinetic + potential + orbit_rate * (i0 * w0 * c20 + i1 * w1 * c21 + i2 * w2 * c22)


@jit
def ensemble_samples(sun_x: Array, sun_y: Array, y_out: Array, e_out: Array,
                     k_out: npt.NDArray[np.int64],
                     inertia: Array, orbit_rate: float, tidal: float, jac: Array,
                     b0: int, b1: int) -> None:
    """
    Post-process bodies b0..b1 of an ensemble's samples in place.

    y_out (n, m, 7): omega [rad/yr] and quaternion of each sample, k_out (n,) the samples each
    body reached, e_out (n, m, 3) its Euler angles [rad] (or (n, 0, 3): none). Writes J into
    jac (n, m), makes the quaternions continuous (the first one kept in sign) and sets every
    sample a body did not reach (y_out, e_out, jac) to NaN.
    """
    i0, i1, i2 = inertia[0], inertia[1], inertia[2]
    m = y_out.shape[1]
    for b in range(b0, b1):
        kk = min(k_out[b], m)
        sign = 1.0
        p0 = p1 = p2 = p3 = 0.0
        for k in range(kk):
            y = y_out[b, k]
            q0, q1, q2, q3 = y[3], y[4], y[5], y[6]
            c00, c01, c02, c10, c11, c12, c20, c21, c22 = quaternion_matrix(q0, q1, q2, q3)
            jac[b, k] = jacobi_sample(sun_x[k], sun_y[k], y[0], y[1], y[2], c00, c01, c02,
                                      c10, c11, c12, c20, c21, c22, i0, i1, i2, orbit_rate,
                                      tidal)
            norm = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
            n0, n1, n2, n3 = q0 / norm, q1 / norm, q2 / norm, q3 / norm
            if k > 0 and n0 * p0 + n1 * p1 + n2 * p2 + n3 * p3 < 0.0:
                sign = -sign
            p0, p1, p2, p3 = n0, n1, n2, n3
            y[3], y[4], y[5], y[6] = n0 * sign, n1 * sign, n2 * sign, n3 * sign
        for k in range(kk, m):
            jac[b, k] = math.nan
            for c in range(y_out.shape[2]):
                y_out[b, k, c] = math.nan
        for k in range(kk, e_out.shape[1]):
            for c in range(3):
                e_out[b, k, c] = math.nan

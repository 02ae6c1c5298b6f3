"""
The frame change every torque needs: orbital-frame vector -> body axes, by the attitude.

Frames: the quaternion q = (q0, q1, q2, q3), scalar first, turns body into orbital; C(q) is
its rotation matrix (body -> orbital), built with 2/|q|^2 so that a quaternion off unit norm
by rounding still gives a rotation.
"""
from __future__ import annotations

from tumble_ros.core.compiling.jit import jit_inline

__all__ = ['orbital_to_body']


@jit_inline
def orbital_to_body(mx: float, my: float, mz: float, q0: float, q1: float, q2: float,
                    q3: float) -> tuple[float, float, float]:
    """Return the body components C(q)^T m of the orbital-frame vector m."""
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    bx = ((1.0 - s * (q2 * q2 + q3 * q3)) * mx + s * (q1 * q2 + q0 * q3) * my
          + s * (q1 * q3 - q0 * q2) * mz)
    by = (s * (q1 * q2 - q0 * q3) * mx + (1.0 - s * (q1 * q1 + q3 * q3)) * my
          + s * (q2 * q3 + q0 * q1) * mz)
    bz = (s * (q1 * q3 + q0 * q2) * mx + s * (q2 * q3 - q0 * q1) * my
          + (1.0 - s * (q1 * q1 + q2 * q2)) * mz)
    return bx, by, bz

"""
The gravitational torque to degree N: a point-mass perturber and the body's full field.

The quadrupole torque (:mod:`.gravity_gradient`, :mod:`.orbits`) keeps the body's inertia
only. Here the body is its gravity field to degree N (``core.model.gravity_field``: Stokes
coefficients C_nm, S_nm of reference radius a, centre-of-mass principal-axis frame), and the
torque follows from the field's acceleration at the perturber.

The torque
----------
The perturber, a point mass m_p at R (body frame, from the body's centre of mass), pulls on
every mass element m_i at r_i with f_i = G m_i m_p (R - r_i) / |R - r_i|^3, parallel to
R - r_i; so (R - r_i) x f_i = 0 and the torque about the centre of mass is

    T = sum_i r_i x f_i = R x sum_i f_i = R x (-m_p a(R)) = -m_p R x a(R)

with a(R) the body's gravitational acceleration at R (the perturber feels m_p a(R); the body
the opposite force, Newton's third law). This holds to every degree; truncating a(R) at degree N
leaves an error of relative order (a/R)^(N+1) (the next term of the expansion). Degree 0 is
central (R x R = 0), degree 1 vanishes about the centre of mass, and degree 2 is the familiar
3 GM_p / R^3 u x (I u) (tests/test_core_multipole.py checks it to rounding). With m_p
= GM_p / G and a = G M (a per unit GM): T = -GM_p M R x (a(R) / GM).

The acceleration
----------------
Montenbruck & Gill, *Satellite Orbits* (2000), sec. 3.2.4-3.2.5: with
V_nm, W_nm = (a/r)^(n+1) P_nm(sin phi) (cos, sin) m lam computed by the recursions

    V_00 = a/r, W_00 = 0
    V_mm + i W_mm = (2m - 1) (a/r^2) (x + i y) (V_{m-1,m-1} + i W_{m-1,m-1})
    V_nm = (2n - 1)/(n - m) z a/r^2 V_{n-1,m} - (n + m - 1)/(n - m) a^2/r^2 V_{n-2,m}

(no angle: exact on the axes) to degree N + 1, the acceleration is (their eq 3.33)

    x'' = GM/a^2 sum_nm { -C_n0 V_{n+1,1}                                             m = 0
                          1/2 [-C V_{n+1,m+1} - S W_{n+1,m+1}
                               + (n-m+2)!/(n-m)! (C V_{n+1,m-1} + S W_{n+1,m-1})]    m > 0 }
    y'' = GM/a^2 sum_nm { -C_n0 W_{n+1,1}                                             m = 0
                          1/2 [-C W_{n+1,m+1} + S V_{n+1,m+1}
                               + (n-m+2)!/(n-m)! (-C W_{n+1,m-1} + S V_{n+1,m-1})]   m > 0 }
    z'' = GM/a^2 sum_nm (n - m + 1) (-C_nm V_{n+1,m} - S_nm W_{n+1,m})

Each V_pk enters three terms (m = k - 1, k, k + 1 of degree n = p - 1), so
:func:`field_acceleration` runs the recursion order by order (k outer, p inner) and adds the
terms of each V_pk as it is made: a handful of scalars, no array, no allocation in the loop.
Cost ~ (N + 2)^2 / 2 recursion steps.

Coefficients are read from one flat float64 array ``coefficients`` from ``offset``: C then S,
their lower triangles row by row (:meth:`GravityField.packed`: C_nm at offset + n(n+1)/2 + m,
S_nm T later, T = (N+1)(N+2)/2).

Units: any consistent set; the torque component uses km, years and the scenario's normalised
inertia (its torque is T_phys / scale, scale = principal moment [kg km^2] / normalised moment).
"""
from __future__ import annotations

import math

import numpy as np

from tumble_ros.core.compiling.jit import jit_inline

__all__ = ['field_acceleration', 'field_torque', 'packed_size']


def packed_size(degree: int) -> int:
    """Return the number of packed coefficients (C and S) to ``degree``: (N+1)(N+2)."""
    return (degree + 1) * (degree + 2)


@jit_inline
def field_acceleration(x: float, y: float, z: float, gm: float, radius: float, degree: int,
                       coefficients: np.ndarray, offset: int,
                       lowest: int = 0) -> tuple[float, float, float]:
    """
    Return the body's gravitational acceleration at (x, y, z) (body frame, outside the body).

    ``gm`` the body's GM [L^3/T^2], ``radius`` the coefficients' reference radius a [L],
    the degrees ``lowest`` to ``degree`` N (0: the whole field; 2: without the central
    attraction); ``coefficients[offset:]`` C then S packed to degree N (the module's
    docstring). Acceleration in L/T^2, body frame (Montenbruck & Gill eq 3.33, by the order-
    by-order recursion of the module's docstring).
    """
    r2 = x * x + y * y + z * z
    xs = x * radius / r2
    ys = y * radius / r2
    zs = z * radius / r2
    q = radius * radius / r2
    tri = (degree + 1) * (degree + 2) // 2
    base_s = offset + tri
    vmm = radius / math.sqrt(r2)
    wmm = 0.0
    ax = 0.0
    ay = 0.0
    az = 0.0
    for k in range(degree + 2):
        if k > 0:
            f = 2.0 * k - 1.0
            vmm, wmm = f * (xs * vmm - ys * wmm), f * (xs * wmm + ys * vmm)
        v1 = 0.0
        w1 = 0.0
        v2 = 0.0
        w2 = 0.0
        for p in range(k, degree + 2):
            if p == k:
                vp = vmm
                wp = wmm
            else:
                c1 = (2.0 * p - 1.0) / (p - k)
                c2 = (p + k - 1.0) / (p - k)
                vp = c1 * zs * v1 - c2 * q * v2
                wp = c1 * zs * w1 - c2 * q * w2
            v2 = v1
            w2 = w1
            v1 = vp
            w1 = wp
            if p <= lowest:
                continue
            n = p - 1
            row = n * (n + 1) // 2
            if k <= n:                               # z'' of (n, k)
                c = coefficients[offset + row + k]
                s = coefficients[base_s + row + k]
                az -= (n - k + 1.0) * (c * vp + s * wp)
            if k == 1:                               # x'', y'' of (n, 0)
                c = coefficients[offset + row]
                ax -= c * vp
                ay -= c * wp
            m = k - 1
            if 1 <= m <= n:                          # x'', y'' of (n, m): V_{n+1,m+1}
                c = coefficients[offset + row + m]
                s = coefficients[base_s + row + m]
                ax -= 0.5 * (c * vp + s * wp)
                ay += 0.5 * (s * vp - c * wp)
            m = k + 1
            if m <= n:                               # x'', y'' of (n, m): V_{n+1,m-1}
                c = coefficients[offset + row + m]
                s = coefficients[base_s + row + m]
                g = 0.5 * (n - m + 2.0) * (n - m + 1.0)
                ax += g * (c * vp + s * wp)
                ay += g * (s * vp - c * wp)
    scale = gm / (radius * radius)
    return scale * ax, scale * ay, scale * az


@jit_inline
def field_torque(x: float, y: float, z: float, gm_p_mass: float, radius: float, degree: int,
                 coefficients: np.ndarray, offset: int) -> tuple[float, float, float]:
    """
    Return the torque on the body of a point mass at (x, y, z) (body frame): -m_p R x a(R).

    ``gm_p_mass`` = GM_p M (the perturber's GM times the body's mass; or, normalised, GM_p M /
    scale); the rest as :func:`field_acceleration`. Torque about the centre of mass, body axes,
    in the units of gm_p_mass / L (e.g. kg km^2/s^2 for km^3/s^2 kg and km).

    Degrees 0 and 1 are left out: their torque is zero (R x R; the centre of mass), and the
    central term's a(R), ~(R/a)^2 larger than the rest, would leave its rounding in R x a.
    """
    ax, ay, az = field_acceleration(x, y, z, gm_p_mass, radius, degree, coefficients, offset,
                                    2)
    return -(y * az - z * ay), -(z * ax - x * az), -(x * ay - y * ax)

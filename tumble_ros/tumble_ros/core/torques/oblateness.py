"""
The torque from a perturber's own oblateness (its J2): the tidal tensor of the J2 potential.

An oblate perturber (the Earth: J2 = 1.0826e-3, Souchay et al. 2018 add it to the disturbing
potential) has, besides GM / s, the potential energy per unit mass

    V_J2(s) = GM J2 R^2 / s^3 P2(s.k / s) = (mu / 2) (3 (s.k)^2 / s^5 - 1 / s^3),
    mu = GM J2 R^2

at the position s relative to its centre (R its reference radius, k its unit pole, P2 the
Legendre polynomial). The torque on a rigid body of centre of mass at s is, to second order in
the body's size (the same truncation as the point-mass tidal torque):

    T_i = -eps_ijk Gamma_kl I_lj,      Gamma = -d^2 V / ds ds  (the tidal tensor)

with I the body's inertia tensor (derivation: docs/physics.md, "The perturber's J2"). For the
point mass, Gamma = GM / s^3 (3 u u^T - 1), this is 3 GM / s^3 u x (I u) (paper eq 12). With I
diagonal (principal axes) only Gamma's off-diagonal entries act:

    T = (H_yz (Iy - Iz), H_xz (Iz - Ix), H_xy (Ix - Iy)),   H = d^2 V / ds ds = -Gamma.

The Hessian of V_J2, every vector in one frame (here the body's):

    H_ij = (mu / 2) [6 k_i k_j / s^5 - 30 z (k_i s_j + k_j s_i) / s^7
                     + (105 z^2 / s^9 - 15 / s^7) s_i s_j - (15 z^2 / s^7 - 3 / s^5) delta_ij]

(z = s.k); it is even in s, so the perturber's position relative to the body serves as well as
the body's relative to the perturber. Units: mu [km^5/yr^2], s [km], torque in the inertia's
units * rad/yr^2. Proof: tests/test_core_perturbers.py sums the exact J2 force (the potential
differentiated by complex steps) over the point masses of a body.
"""
from __future__ import annotations

from tumble_ros.core.compiling.jit import jit_inline

__all__ = ['oblateness_hessian', 'tensor_torque', 'oblateness_torque']


@jit_inline
def oblateness_hessian(mu: float, kx: float, ky: float, kz: float, sx: float, sy: float,
                       sz: float) -> tuple[float, float, float]:
    """
    Return (H_xy, H_xz, H_yz): the off-diagonal Hessian of V_J2 at s [1/yr^2].

    ``mu`` = GM J2 R^2 [km^5/yr^2], k the perturber's unit pole and s the relative position
    [km], both in the same (body) axes.
    """
    s2 = sx * sx + sy * sy + sz * sz
    inv2 = 1.0 / s2
    inv5 = inv2 * inv2 / (s2 ** 0.5)
    inv7 = inv5 * inv2
    z = sx * kx + sy * ky + sz * kz
    half = 0.5 * mu
    a = 6.0 * inv5
    b = -30.0 * z * inv7
    c = (105.0 * z * z * inv2 - 15.0) * inv7
    hxy = half * (a * kx * ky + b * (kx * sy + ky * sx) + c * sx * sy)
    hxz = half * (a * kx * kz + b * (kx * sz + kz * sx) + c * sx * sz)
    hyz = half * (a * ky * kz + b * (ky * sz + kz * sy) + c * sy * sz)
    return hxy, hxz, hyz


@jit_inline
def tensor_torque(hxy: float, hxz: float, hyz: float, ix: float, iy: float,
                  iz: float) -> tuple[float, float, float]:
    """Return T_i = eps_ijk H_kl I_lj for a diagonal I: the torque of a potential's Hessian H."""
    return hyz * (iy - iz), hxz * (iz - ix), hxy * (ix - iy)


@jit_inline
def oblateness_torque(mu: float, kx: float, ky: float, kz: float, sx: float, sy: float,
                      sz: float, ix: float, iy: float, iz: float) -> tuple[float, float, float]:
    """
    Return the torque of the perturber's J2 on the body [I rad/yr^2], body axes.

    ``mu`` = GM J2 R^2 [km^5/yr^2], k the perturber's unit pole and s the perturber's position
    [km], both in body axes; (ix, iy, iz) the principal moments.
    """
    hxy, hxz, hyz = oblateness_hessian(mu, kx, ky, kz, sx, sy, sz)
    return tensor_torque(hxy, hxz, hyz, ix, iy, iz)

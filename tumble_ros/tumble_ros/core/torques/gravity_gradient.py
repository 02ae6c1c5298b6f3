"""
The Sun's gravity-gradient torque on the asteroid in a circular orbit (paper eqs 11-13).

Units: time in years, angular rates in rad/yr, inertia normalised (any unit), torque in
inertia-units * rad/yr^2. The circular orbit has GM/R0^3 = ws^2 (Kepler's third law), so the
torque only needs the orbit rate ws and the Sun's direction. Frames: the orbital frame
(X', Y' in the orbit plane, Z' its normal) and the body principal axes; a quaternion q turns
body into orbital (scalar first).

The scalar functions :func:`sun_direction_body` and :func:`tidal_torque` are what the
compiled kernels inline; the array helpers below run the *same* functions (their Python
source) on numpy arrays, so the formula exists once.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import called, jit_inline, python_source
from tumble_ros.core.torques.frames import orbital_to_body
from tumble_ros.core.trig import scaled_sin_cos_rows, sin_cos

__all__ = ['sun_direction_orbital', 'sun_direction_body', 'sun_in_orbit_plane',
           'sun_in_orbit_plane_rows', 'tidal_torque',
           'tidal_coefficients', 'point_mass_torque', 'gravity_gradient_torque',
           'gravity_gradient_potential', 'tidal_potential_coefficient']

#: ``trig.sin_cos`` compiled once and called: inlined, its two copies of the polynomials in
#: every right-hand side of every method cost ~20 s of the first run's compiling.
_sin_cos_called = called(sin_cos)


@jit_inline
def sun_direction_body(orbit_rate: float, t: float, q0: float, q1: float, q2: float,
                       q3: float) -> tuple[float, float, float]:
    """
    Return the unit Sun direction u = C(q)^T s(t) in body axes.

    s(t) = (sin ws t, cos ws t, 0) in the orbital frame (the paper's R0(t)/R0: it starts on +Y'
    and turns clockwise about Z'), C(q) the body -> orbital matrix of the quaternion q.
    """
    sx, sy = sun_in_orbit_plane(orbit_rate, t)
    return orbital_to_body(sx, sy, 0.0, q0, q1, q2, q3)


@jit_inline
def sun_in_orbit_plane(orbit_rate: float, t: float) -> tuple[float, float]:
    """
    Return (sin ws t, cos ws t): the X' and Y' components of the Sun's direction s(t).

    The attitude-free part of :func:`sun_direction_body` (its Z' component is 0): one sin/cos
    pair per time, shared by every body of an ensemble stepped in lockstep. The sin/cos are
    ``trig.sin_cos``'s (plain arithmetic, within 1 ulp of libm's), so that ``dop853``'s lanes,
    each at its own time, take them vectorised with a single body's bits
    (:func:`sun_in_orbit_plane_rows`, in ``kernels.lanes.lanes_rhs``).
    """
    return _sin_cos_called(orbit_rate * t)


@jit_inline
def sun_in_orbit_plane_rows(orbit_rate: float, t: npt.NDArray[np.float64],
                            sx: npt.NDArray[np.float64], sy: npt.NDArray[np.float64],
                            m: int) -> None:
    """Write :func:`sun_in_orbit_plane` at times t[i] [yr] to sx[i], sy[i], i < m (vectorised)."""
    scaled_sin_cos_rows(orbit_rate, t, sx, sy, m)


@jit_inline
def tidal_torque(kx: float, ky: float, kz: float, ux: float, uy: float,
                 uz: float) -> tuple[float, float, float]:
    """
    Return M = 3 ws^2 u x (I u) in body axes (paper eq 12 with GM/R0^3 = ws^2).

    (kx, ky, kz) = :func:`tidal_coefficients`: Mx = 3 ws^2 (Iz - Iy) uy uz, My = 3 ws^2
    (Ix - Iz) ux uz, Mz = 3 ws^2 (Iy - Ix) ux uy.
    """
    return kx * uy * uz, ky * ux * uz, kz * ux * uy


@jit_inline
def point_mass_torque(gm: float, x: float, y: float, z: float, ix: float, iy: float,
                      iz: float) -> tuple[float, float, float]:
    """
    Return M = 3 GM / R^3 u x (I u), body axes: the torque of a point mass at (x, y, z).

    ``gm`` [L^3/yr^2] (km^3/yr^2 for the perturbers), (x, y, z) the point mass's position
    relative to the body's centre of mass in body principal axes [L], R its norm, u = (x, y,
    z) / R; (ix, iy, iz) the principal moments. The degree-2 torque law of every perturber
    (:mod:`.perturbers`): the one call a torque to higher degree replaces.
    """
    r = math.sqrt(x * x + y * y + z * z)
    k = 3.0 * gm / (r * r * r)
    return tidal_torque(k * (iz - iy), k * (ix - iz), k * (iy - ix), x / r, y / r, z / r)


def tidal_coefficients(inertia: Sequence[float] | npt.NDArray[np.float64],
                       orbit_rate: float) -> tuple[float, float, float]:
    """Return (3 ws^2 (Iz - Iy), 3 ws^2 (Ix - Iz), 3 ws^2 (Iy - Ix)) for :func:`tidal_torque`."""
    ix, iy, iz = (float(v) for v in inertia)
    ws = float(orbit_rate)
    k = 3.0 * ws * ws
    return k * (iz - iy), k * (ix - iz), k * (iy - ix)


def sun_direction_orbital(t: npt.ArrayLike, orbit_rate: float) -> npt.NDArray[np.float64]:
    """
    Return the unit vector from the asteroid to the Sun in the orbital frame, R0(t)/R0.

    ``t`` [yr]: a number, (3,) out, or an array of n times, (n, 3) out.
    """
    angle = orbit_rate * np.asarray(t, dtype=float)
    direction: npt.NDArray[np.float64] = np.stack([np.sin(angle), np.cos(angle),
                                                   np.zeros_like(angle)], axis=-1)
    return direction


def gravity_gradient_torque(u_body: npt.ArrayLike,
                            inertia: Sequence[float] | npt.NDArray[np.float64],
                            orbit_rate: float) -> npt.NDArray[np.float64]:
    """
    Torque M = 3 ws^2 u x (I u) in body axes for (3,) or (n, 3) Sun directions ``u_body``.

    The same arithmetic as the kernels (:func:`tidal_torque`), on arrays.
    """
    u = np.asarray(u_body, dtype=float)
    on_arrays: Callable[..., Any] = python_source(tidal_torque)   # floats or arrays alike
    torque = on_arrays(*tidal_coefficients(inertia, orbit_rate), u[..., 0], u[..., 1], u[..., 2])
    stacked: npt.NDArray[np.float64] = np.stack(np.broadcast_arrays(*torque), axis=-1)
    return stacked


def gravity_gradient_potential(u_body: npt.ArrayLike, inertia: npt.ArrayLike,
                               orbit_rate: float) -> npt.NDArray[np.float64]:
    """
    Orientation-dependent part of the tidal potential energy, (3/2) ws^2 u.I.u.

    Its negative gradient with respect to a rotation of the body gives the torque above;
    it enters the Jacobi integral (see ``dynamics.jacobi_integral``).
    """
    u = np.asarray(u_body, dtype=float)
    i = np.asarray(inertia, dtype=float)
    uu = u * u * i
    # (written out: np.sum over 3 components costs a reduction's set-up per sample; same bits)
    weighted = uu[..., 0] + uu[..., 1] + uu[..., 2]
    potential: npt.NDArray[np.float64] = tidal_potential_coefficient(orbit_rate) * weighted
    return potential


def tidal_potential_coefficient(orbit_rate: float) -> float:
    """
    Return (3/2) ws^2 [1/yr^2] of the tidal potential, as Python computes it: its one place.

    ``dynamics.jacobi_integral`` and an ensemble's compiled post-processing multiply by this
    number (``kernels.samples.jacobi_sample``), so both give the same bits.
    """
    return 1.5 * orbit_rate**2

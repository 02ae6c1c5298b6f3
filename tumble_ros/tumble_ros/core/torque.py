"""
The Sun's gravity-gradient torque on the asteroid (paper eqs 11-13).

Units: time in years, angular rates in rad/yr, inertia normalised (any unit), torque in
inertia-units * rad/yr^2. The circular orbit has GM/R0^3 = ws^2 (Kepler's third law), so
the torque only needs the orbit rate ws and the Sun's direction.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ['sun_direction_orbital', 'gravity_gradient_torque', 'gravity_gradient_potential']


def sun_direction_orbital(t: float, orbit_rate: float) -> np.ndarray:
    """
    Return the unit vector from the asteroid to the Sun in the orbital frame, R0(t)/R0.

    The paper's R0(t) = R0 [sin ws t, cos ws t, 0]: it starts on +Y' and turns clockwise
    about Z' (angular velocity -ws Z').
    """
    return np.array([math.sin(orbit_rate * t), math.cos(orbit_rate * t), 0.0])


def gravity_gradient_torque(u_body, inertia, orbit_rate: float) -> np.ndarray:
    """
    Torque M = 3 ws^2 u x (I u) in body axes (paper eq 12 with GM/R0^3 = ws^2).

    Component-wise this is eq 12: Mx = 3 ws^2 uy uz (Iz - Iy), My = 3 ws^2 ux uz (Ix - Iz),
    Mz = 3 ws^2 ux uy (Iy - Ix).

    Parameters
    ----------
    u_body : (3,) or (n, 3) array
        Unit Sun direction in body principal axes.
    inertia : (3,) array
        Principal moments (Ix, Iy, Iz).
    orbit_rate : float
        ws [rad/yr].

    """
    u = np.asarray(u_body, dtype=float)
    i = np.asarray(inertia, dtype=float)
    return 3.0 * orbit_rate**2 * np.cross(u, u * i)


def gravity_gradient_potential(u_body, inertia, orbit_rate: float) -> np.ndarray:
    """
    Orientation-dependent part of the tidal potential energy, (3/2) ws^2 u.I.u.

    Its negative gradient with respect to a rotation of the body gives the torque above;
    it enters the Jacobi integral (see ``dynamics.jacobi_integral``).
    """
    u = np.asarray(u_body, dtype=float)
    i = np.asarray(inertia, dtype=float)
    return 1.5 * orbit_rate**2 * np.sum(u * u * i, axis=-1)

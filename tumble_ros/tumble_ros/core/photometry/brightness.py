"""
Disk-integrated brightness of a convex mesh lit by the Sun and seen by an observer.

Frames: the quaternion q (scalar first) turns body axes into the inertial frame (the
scenario's orbital frame), as everywhere in the project; ``sun`` and ``observer`` are unit
vectors from the body towards the Sun and towards the observer, inertial frame.

    B = sum over facets with mu0 > 0 and mu > 0 of  area * S(mu0, mu)

mu0 = n.s, mu = n.o with n the facet's outward normal and s, o the directions in body axes.
The sum is exact for a convex body (no facet shadows or hides another; ``shape``). B is in
units of the mesh's area times the incoming flux per unit area (up to the albedo).

Magnitude: m = -2.5 log10(B / B_ref) + 5 log10(r delta), with r and delta the distances to the
Sun and to the observer [au] (r = delta = 1 au: the reduced magnitude). The reference B_ref is a
fixed normalisation: the same law's brightness at zero phase of the sphere of the mesh's volume
(``Mesh.equivalent_radius`` R), B_ref = 2 pi R^2 int_0^1 S(mu, mu) dmu (lambert 2 pi R^2 / 3,
lommel_seeliger pi R^2 / 2); so m = 0 for that sphere at opposition 1 au from Sun and observer,
whatever the attitude. A sample with B = 0 (nothing both lit and seen) has m = +inf.

Aspect angles: the Sun's and the observer's directions in body axes as (latitude, longitude)
[rad]: latitude asin(d_z) from the body's xy plane (+pi/2 towards +z), longitude atan2(d_y, d_x)
from +x towards +y, in (-pi, pi]. (The aspect angle of the photometry literature, between the
spin axis and the line of sight, is pi/2 - latitude when the spin axis is z.)
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.model.scattering import law as find_law, ScatteringLaw
from tumble_ros.core.photometry.shape import Mesh
from tumble_ros.core.torques.frames import orbital_to_body

__all__ = ['brightness', 'brightness_in_body', 'to_body', 'phase_angle', 'aspect_angles',
           'latitude_longitude', 'reference_brightness', 'magnitude', 'CHUNK_ELEMENTS']

#: The samples x facets blocks of :func:`brightness` hold at most this many numbers (8 MB per
#: array of float64), so memory stays bounded for long runs and fine meshes.
CHUNK_ELEMENTS = 2**20
_to_body: Callable[..., Any] = python_source(orbital_to_body)
#: 20-point Gauss-Legendre nodes and weights on [-1, 1] (:func:`reference_brightness`).
_GAUSS_LEGENDRE = np.polynomial.legendre.leggauss(20)


def _directions(name: str, value: ArrayLike, n: int) -> FloatArray:
    """Return ``value`` as (n, 3) unit vectors; ValueError naming ``name`` otherwise."""
    d = np.asarray(value, dtype=float)
    if d.ndim == 1:
        d = np.broadcast_to(d, (n, 3)) if d.shape == (3,) else d
    if d.shape != (n, 3) or not np.all(np.isfinite(d)):
        raise ValueError(f'{name}: need ({n}, 3) finite unit vectors, got shape {d.shape}')
    norm = np.linalg.norm(d, axis=1)
    if not np.all(np.abs(norm - 1.0) < 1e-6):
        raise ValueError(f'{name}: need unit vectors, got norms from {norm.min():.6g} to '
                         f'{norm.max():.6g}')
    out: FloatArray = d / norm[:, None]
    return out


def _quaternions(value: ArrayLike) -> FloatArray:
    q = np.asarray(value, dtype=float).reshape(-1, 4)
    if not np.all(np.isfinite(q)) or np.any(np.sum(q * q, axis=1) == 0.0):
        raise ValueError('quaternion: need (n, 4) finite, non-zero quaternions (scalar first)')
    return q


def to_body(quaternion: ArrayLike, direction: ArrayLike) -> FloatArray:
    """Return inertial directions (n, 3) in body axes, C(q)^T d, for (n, 4) ``quaternion``."""
    q = _quaternions(quaternion)
    d = np.broadcast_to(np.asarray(direction, dtype=float), (q.shape[0], 3))
    body: FloatArray = np.stack(_to_body(*d.T, *q.T), axis=-1)
    return body


def brightness(quaternion: ArrayLike, sun: ArrayLike, observer: ArrayLike, mesh: Mesh,
               law: str | ScatteringLaw = 'lambert') -> FloatArray:
    """
    Return the disk-integrated brightness B (n,) [mesh area units] of ``mesh``.

    ``quaternion`` (n, 4) body -> inertial, scalar first; ``sun``, ``observer`` (n, 3) or (3,)
    unit vectors from the body, inertial frame; ``law``: a name of ``scattering.LAWS`` or a law.
    Computed in blocks of at most :data:`CHUNK_ELEMENTS` samples x facets.
    """
    q = _quaternions(quaternion)
    n = q.shape[0]
    return brightness_in_body(to_body(q, _directions('sun', sun, n)),
                              to_body(q, _directions('observer', observer, n)), mesh, law)


def brightness_in_body(sun: FloatArray, observer: FloatArray, mesh: Mesh,
                       law: str | ScatteringLaw = 'lambert') -> FloatArray:
    """Return :func:`brightness` of unit directions (n, 3) already in body axes."""
    scatter = find_law(law)
    s_body, o_body = sun, observer
    n = s_body.shape[0]
    out = np.empty(n)
    block = max(1, CHUNK_ELEMENTS // mesh.areas.size)
    columns = tuple(np.ascontiguousarray(mesh.normals[:, k]) for k in range(3))
    for start in range(0, n, block):
        # a facet neither lit nor seen counts 0: every law vanishes where mu0 or mu is 0
        mu0 = np.maximum(_cosines(s_body[start:start + block], columns), 0.0)
        mu = np.maximum(_cosines(o_body[start:start + block], columns), 0.0)
        out[start:start + block] = np.sum(scatter(mu0, mu) * mesh.areas, axis=1)
    return out


def _cosines(direction: FloatArray, normals: tuple[FloatArray, ...]) -> FloatArray:
    """
    Return d.n (m, F) of directions (m, 3) and the normals' columns (nx, ny, nz), elementwise.

    Not a matrix product: BLAS may order a product's sums by the array's size, and each sample
    must come out the same whatever block it is computed in (the live simulator's batches and
    the offline writer's differ); the row sums above are numpy's, row by row, alike.
    """
    cosines: FloatArray = direction[:, 0:1] * normals[0]
    cosines += direction[:, 1:2] * normals[1]
    cosines += direction[:, 2:3] * normals[2]
    return cosines


def phase_angle(sun: ArrayLike, observer: ArrayLike) -> FloatArray:
    """Return the Sun-body-observer angle [rad] in [0, pi] of unit vectors (n, 3) or (3,)."""
    s = np.asarray(sun, dtype=float)
    o = np.asarray(observer, dtype=float)
    # atan2(|s x o|, s.o): accurate near 0 and pi, where acos loses half the digits
    angle: FloatArray = np.arctan2(np.linalg.norm(np.cross(s, o), axis=-1),
                                   np.sum(s * o, axis=-1))
    return angle


def aspect_angles(quaternion: ArrayLike, direction: ArrayLike) -> FloatArray:
    """Return (latitude, longitude) [rad] (n, 2) of inertial unit ``direction`` in body axes."""
    return latitude_longitude(to_body(quaternion, direction))


def latitude_longitude(direction: FloatArray) -> FloatArray:
    """Return (latitude, longitude) [rad] (n, 2) of directions (n, 3) in body axes."""
    d = direction / np.linalg.norm(direction, axis=1, keepdims=True)
    angles: FloatArray = np.stack([np.arcsin(np.clip(d[:, 2], -1.0, 1.0)),
                                   np.arctan2(d[:, 1], d[:, 0])], axis=-1)
    return angles


def reference_brightness(mesh: Mesh, law: str | ScatteringLaw = 'lambert') -> float:
    """
    Return B_ref = 2 pi R^2 int_0^1 S(mu, mu) dmu, R the mesh's volume-equivalent radius.

    The zero-phase brightness of that sphere; the integral by 20-point Gauss-Legendre (exact
    for the polynomial and rational laws of the registry to rounding).
    """
    x, w = _GAUSS_LEGENDRE
    mu = 0.5 * (x + 1.0)
    integral = 0.5 * float(np.sum(w * find_law(law)(mu, mu)))
    return 2.0 * math.pi * mesh.equivalent_radius ** 2 * integral


def magnitude(brightness: ArrayLike, reference: float, sun_distance: ArrayLike = 1.0,
              observer_distance: ArrayLike = 1.0) -> FloatArray:
    """
    Return m = -2.5 log10(B / B_ref) + 5 log10(r delta), distances [au]; +inf where B = 0.

    With r = delta = 1 au (the defaults) the reduced magnitude.
    """
    b = np.asarray(brightness, dtype=float)
    with np.errstate(divide='ignore'):
        m: FloatArray = (-2.5 * np.log10(b / reference)
                         + 5.0 * np.log10(np.asarray(sun_distance, dtype=float)
                                          * np.asarray(observer_distance, dtype=float)))
    return m

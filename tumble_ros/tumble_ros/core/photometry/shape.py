"""
The surface a telescope sees: a convex triangulated mesh of the body, in body axes.

A :class:`Mesh` is vertices (V, 3), facets (F, 3) (vertex indices, counter-clockwise seen from
outside), and derived per facet the outward unit normals (F, 3) and areas (F,). Lengths are in
the caller's unit (the display scale of ``core.model.shape``: the longest semi-axis is 1);
brightness is proportional to area, so only the shape's proportions matter for a lightcurve.

Convex shapes only: the disk-integrated brightness sums every facet that faces both the Sun
and the observer (``brightness``), which is exact for a convex body and wrong for a concave one
(a facet can then be hidden or shadowed by another). :func:`convex_mesh` checks convexity and
refuses a mesh that is not; shadowing and occlusion are not modelled.

Shapes: :func:`ellipsoid_mesh` (an icosphere, subdivided ``subdivisions`` times, 20 4^k facets,
scaled by the semi-axes: the scaling of a convex polyhedron is convex), :func:`body_mesh` (the
uniform ellipsoid of a scenario's principal moments, ``core.model.shape.body_shape``; refused
for moments that no body has), and any convex polyhedron (:func:`convex_mesh`, e.g. a
polyhedral mass model's vertices and facets).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np
import numpy.typing as npt

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.lightcurve_settings import DEFAULT_SUBDIVISIONS, MAX_SUBDIVISIONS
from tumble_ros.core.model.mesh_checks import convexity_defect, CONVEXITY_TOLERANCE, \
    DEGENERATE_AREA
from tumble_ros.core.model.shape import body_shape

__all__ = ['Mesh', 'convex_mesh', 'icosphere', 'ellipsoid_mesh', 'body_mesh',
           'DEFAULT_SUBDIVISIONS', 'MAX_SUBDIVISIONS', 'CONVEXITY_TOLERANCE']

_IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class Mesh:
    """
    A closed convex triangulated surface in body axes (build it with :func:`convex_mesh`).

    ``vertices`` (V, 3) [length], ``facets`` (F, 3) vertex indices ordered counter-clockwise
    seen from outside, ``normals`` (F, 3) outward unit normals, ``areas`` (F,) [length^2],
    ``volume`` [length^3] (enclosed, by the divergence theorem).
    """

    vertices: FloatArray
    facets: _IntArray
    normals: FloatArray
    areas: FloatArray
    volume: float

    @property
    def equivalent_radius(self) -> float:
        """Return the radius of the sphere of the same volume [length]."""
        return float((3.0 * self.volume / (4.0 * math.pi)) ** (1.0 / 3.0))


def convex_mesh(vertices: ArrayLike, facets: ArrayLike, *, check_convex: bool = True) -> Mesh:
    """
    Return the :class:`Mesh` of a convex polyhedron: ``vertices`` (V, 3), ``facets`` (F, 3).

    Facets are re-oriented outward (their order of vertices does not matter). ValueError, naming
    the argument, for arrays of the wrong shape, non-finite coordinates, indices out of range,
    degenerate facets, or a polyhedron that is not convex or not one closed surface
    (:func:`~tumble_ros.core.model.mesh_checks.convexity_defect`: a vertex outside a
    neighbouring facet's plane by more than :data:`CONVEXITY_TOLERANCE` of its size, O(F log
    F)): the brightness sums visible lit facets without shadowing, which only a convex body
    makes exact. ``check_convex`` False skips that check for a mesh convex by construction
    (:func:`ellipsoid_mesh`).
    """
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(facets)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] < 4 or not np.all(np.isfinite(v)):
        raise ValueError(f'vertices: need (V >= 4, 3) finite coordinates, got shape {v.shape}')
    if (f.ndim != 2 or f.shape[1] != 3 or f.shape[0] < 4
            or not np.issubdtype(f.dtype, np.integer)):
        raise ValueError(f'facets: need (F >= 4, 3) integer vertex indices, got shape {f.shape} '
                         f'of {f.dtype}')
    f = f.astype(np.int64)
    if f.min() < 0 or f.max() >= v.shape[0]:
        raise ValueError(f'facets: indices must be in [0, {v.shape[0] - 1}], got '
                         f'{int(f.min())} to {int(f.max())}')
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cross = np.cross(b - a, c - a)
    double_area = np.linalg.norm(cross, axis=1)
    size = float(np.ptp(v, axis=0).max())
    if not np.all(double_area > DEGENERATE_AREA * size * size):
        k = int(np.argmin(double_area))
        raise ValueError(f'facets: facet {k} {f[k].tolist()} is degenerate (zero area)')
    normals = cross / double_area[:, None]
    centre = v.mean(axis=0)           # inside a convex polyhedron
    outward = np.einsum('ij,ij->i', normals, (a + b + c) / 3.0 - centre) > 0.0
    normals = np.where(outward[:, None], normals, -normals)
    f = np.where(outward[:, None], f, f[:, ::-1])
    defect = convexity_defect(v, f, normals) if check_convex else None
    if defect is not None:
        raise ValueError(f'vertices, facets: the mesh is not convex ({defect}; the brightness is '
                         'exact for convex bodies only: no shadowing or occlusion is modelled)')
    areas = 0.5 * double_area
    centroids = (a + b + c) / 3.0
    volume = float(np.sum(areas * np.einsum('ij,ij->i', centroids, normals)) / 3.0)
    return Mesh(v, f, normals, areas, volume)


def icosphere(subdivisions: int) -> tuple[FloatArray, _IntArray]:
    """
    Return (vertices (V, 3), facets (F, 3)) of the unit icosphere.

    The icosahedron with each triangle split into 4 ``subdivisions`` times, new vertices pushed
    onto the unit sphere: F = 20 4^k facets, V = 10 4^k + 2 vertices.
    """
    if isinstance(subdivisions, bool) or not isinstance(subdivisions, (int, np.integer)) \
            or not 0 <= subdivisions <= MAX_SUBDIVISIONS:
        raise ValueError(f'subdivisions: must be an integer in [0, {MAX_SUBDIVISIONS}], got '
                         f'{subdivisions!r}')
    p = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p),
             (0, -1, -p), (0, 1, -p), (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    vertices = np.array(verts, dtype=float)
    vertices /= np.linalg.norm(vertices, axis=1, keepdims=True)
    facets = np.array(faces, dtype=np.int64)
    for _ in range(int(subdivisions)):
        edges = np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]], facets[:, [2, 0]]])
        edges = np.sort(edges, axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = vertices[unique[:, 0]] + vertices[unique[:, 1]]
        middle /= np.linalg.norm(middle, axis=1, keepdims=True)
        mid = inverse.reshape(3, -1) + vertices.shape[0]     # mid[0]: edge 01, 1: 12, 2: 20
        vertices = np.concatenate([vertices, middle])
        a, b, c = facets.T
        ab, bc, ca = mid
        facets = np.concatenate([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                                 np.stack([ca, bc, c], 1), np.stack([ab, bc, ca], 1)])
    return vertices, facets


def ellipsoid_mesh(semi_axes: ArrayLike, subdivisions: int = DEFAULT_SUBDIVISIONS) -> Mesh:
    """
    Return the icosphere of ``subdivisions`` scaled by ``semi_axes`` (a, b, c) [length].

    Its vertices lie on the ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 (an inscribed polyhedron,
    convex); it converges to the ellipsoid as the facets shrink (test_core_photometry.py).
    """
    axes = np.asarray(semi_axes, dtype=float)
    if axes.shape != (3,) or not np.all(np.isfinite(axes)) or np.any(axes <= 0.0):
        raise ValueError(f'semi_axes: three positive finite lengths needed, got {semi_axes!r}')
    vertices, facets = icosphere(subdivisions)
    # convex by construction: points of a sphere span a convex polyhedron, and a linear map
    # (the scaling) keeps it convex (test_core_photometry.py checks it at every level)
    return convex_mesh(vertices * axes, facets, check_convex=False)


def body_mesh(inertia: ArrayLike, subdivisions: int = DEFAULT_SUBDIVISIONS) -> Mesh:
    """
    Return the mesh of the uniform ellipsoid of the principal moments ``inertia`` (Ix, Iy, Iz).

    Semi-axes from ``core.model.shape.body_shape`` (display scale, the longest is 1). ValueError
    for moments that break the triangle inequality (``allow_unphysical_inertia``): no body has
    them, so nothing can be seen.
    """
    shape = body_shape(inertia)
    if not shape.physical:
        raise ValueError(f'inertia: {list(np.asarray(inertia, dtype=float))} breaks the triangle '
                         'inequality (each moment at most the sum of the other two): no body has '
                         'these moments, so it has no lightcurve')
    return ellipsoid_mesh(shape.semi_axes, subdivisions)

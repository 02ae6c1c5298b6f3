"""
Mass models of the body: where the inertia (and the gravity field) of a scenario comes from.

Three kinds (:data:`MASS_MODELS`, name -> class), each a frozen dataclass validated when built:

- :class:`Ellipsoid`: a homogeneous triaxial ellipsoid, semi-axes (a, b, c) [km] along its x, y,
  z axes, density [kg/m^3];
- :class:`Polyhedron`: a closed triangulated surface of uniform density [kg/m^3], vertices [km]
  (read from a shape file by :func:`tumble_ros.core.model.shape_files.load_shape`);
- :class:`DensityMoments`: a gravity field given directly (mass, reference radius, Stokes
  coefficients, principal moments), for a body whose interior is not uniform.

Units: lengths [km], density [kg/m^3] (2.6 g/cm^3 = 2600 kg/m^3), mass [kg] (density x volume
[km^3] x 1e9 m^3/km^3), inertia [kg km^2].

The reference. The inertia tensor is always about the centre of mass; ``principal_moments`` and
``principal_axes`` diagonalise it. The gravity field (:meth:`gravity_field`) is always in the
centre-of-mass principal-axis frame, the frame the attitude dynamics integrates in. An
ellipsoid is built in it (its centre is the centre of mass, its x, y, z axes are principal: the
moments follow the order of the semi-axes). A polyhedron is kept in the frame of its file;
:meth:`Polyhedron.in_principal_axes` moves it into principal axes, ordered by increasing moment
(x the axis of least inertia, z of greatest), and records the move in its
:class:`Reference` (``r_principal = rotation @ (r_file - offset)``) so that a user can tell.

Formulas. Ellipsoid: volume 4/3 pi a b c, Ixx = m (b^2 + c^2) / 5 (cyclic). Polyhedron: the sum
over the signed tetrahedra (origin, facet) of the exact polynomial integrals (Tonon 2004, J.
Math. Stat. 1, 8; the same as Eberly's "Polyhedral mass properties"): a tetrahedron of vertices
0, p1, p2, p3 has volume V = det[p1 p2 p3] / 6, first moment V (p1 + p2 + p3) / 4 and second
moments ``integral x_i x_j dV = V / 20 (sum_k p_k,i p_k,j + s_i s_j)``, s = p1 + p2 + p3.
Stokes coefficients of a polyhedron: :func:`tetrahedron_rule`, a conical-product Gauss rule
exact for polynomials of degree N (Stroud 1971, "Approximate calculation of multiple
integrals", the collapsed-coordinate Gauss-Jacobi product), on every tetrahedron (centre of
mass, facet), fed to ``GravityField.from_point_masses`` as point masses: a solid harmonic of
degree n is a polynomial of degree n, so the coefficients are exact to rounding. Ellipsoid: the
closed form of Balmino 1994 (Celest. Mech. Dyn. Astron. 60, 331, "Gravitational potential
harmonics from the shape of an homogeneous body"), :func:`ellipsoid_stokes`.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
import math
from typing import Any, Mapping, Protocol

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.gravity_field import (GravityField, principal_axes,
                                                 regular_solid_harmonics, stokes_normalisation)
from tumble_ros.core.model.limits import (MAX_BODY_SIZE, MAX_DEGREE, MAX_FACETS, MIN_BODY_SIZE,
                                          ScenarioError)
from tumble_ros.core.model.mesh_checks import (components, convexity_defect, ConvexityDefect,
                                               degenerate_facet, mesh_size)

__all__ = ['MassModelError', 'Reference', 'IDENTITY', 'MassModel', 'Ellipsoid', 'Polyhedron',
           'DensityMoments', 'MASS_MODELS', 'KG_PER_KM3_PER_DENSITY', 'tetrahedron_rule',
           'ellipsoid_stokes', 'principal_frame']

#: Mass [kg] of 1 km^3 at a density of 1 kg/m^3.
KG_PER_KM3_PER_DENSITY = 1e9
#: Points summed at once into the solid harmonics (memory: 2 (N + 1)^2 doubles a point).
CHUNK_POINTS = 20_000
#: Accepted densities [kg/m^3]: from below a comet's (~500) to above osmium's (22,590); a
#: value under the minimum is most likely in g/cm^3.
MIN_DENSITY, MAX_DENSITY = 100.0, 30000.0


class MassModelError(ScenarioError):
    """
    An invalid mass model; the message starts with the field's name.

    ``facet``, ``vertex``: the facet or vertex at fault (0-based), if any.
    """

    def __init__(self, message: str, facet: int | None = None,
                 vertex: int | None = None) -> None:
        super().__init__(message)
        self.facet = facet
        self.vertex = vertex


def _fail(name: str, why: str, value: Any, facet: int | None = None,
          vertex: int | None = None) -> None:
    raise MassModelError(f'{name}: {why}, got {value!r}', facet, vertex)


def _size(name: str, size: float, value: Any) -> None:
    """Refuse a body's ``size`` [km] outside [MIN_BODY_SIZE, MAX_BODY_SIZE]."""
    if not MIN_BODY_SIZE <= size <= MAX_BODY_SIZE:
        _fail(name, f'a body {size:.3g} km across is outside [{MIN_BODY_SIZE:g}, '
              f'{MAX_BODY_SIZE:g}] km (MIN_BODY_SIZE, MAX_BODY_SIZE: from a boulder to beyond '
              'Ceres; lengths are in km)', value)


def _density(value: Any) -> float:
    try:
        rho = float(value)
    except (TypeError, ValueError):
        _fail('density', 'must be a number [kg/m^3]', value)
    if isinstance(value, bool) or not math.isfinite(rho) or rho <= 0.0:
        _fail('density', 'must be a finite number > 0 [kg/m^3]', value)
    if not MIN_DENSITY <= rho <= MAX_DENSITY:
        _fail('density', f'must be in [{MIN_DENSITY:g}, {MAX_DENSITY:g}] kg/m^3 (a density in '
              'g/cm^3? multiply by 1000)', value)
    return rho


@dataclass(frozen=True)
class Reference:
    """
    A body's frame in the frame it was given in: ``r_new = rotation @ (r_old - offset)``.

    ``offset``: the centre of mass in the old frame [km]; ``rotation``: a proper rotation, its
    rows the principal axes in the old frame.
    """

    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[tuple[float, float, float], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
                                                        (0.0, 0.0, 1.0))

    def apply(self, points: ArrayLike) -> FloatArray:
        """Return ``points`` (n, 3) [km] of the old frame in the new one."""
        out: FloatArray = (np.asarray(points, dtype=float) - np.asarray(self.offset)) @ \
            np.asarray(self.rotation).T
        return out

    def then(self, other: Reference) -> Reference:
        """Return the reference of applying ``self`` and then ``other``."""
        rotation = np.asarray(other.rotation) @ np.asarray(self.rotation)
        offset = np.asarray(self.offset) + np.asarray(self.rotation).T @ np.asarray(other.offset)
        return Reference(_triple(offset), tuple(_triple(row) for row in rotation))

    @property
    def is_identity(self) -> bool:
        """Whether nothing was moved."""
        return self == IDENTITY


def _triple(v: ArrayLike) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=float)
    return (float(a[0]), float(a[1]), float(a[2]))


IDENTITY = Reference()


def principal_frame(inertia: ArrayLike, offset: ArrayLike) -> Reference:
    """
    Return the :class:`Reference` into principal axes for an inertia tensor about the centre.

    ``inertia``: (3, 3) about the centre of mass [any unit]; ``offset``: the centre of mass [km].
    The axes are ordered by increasing moment, each row's largest component positive (the third
    row the cross product of the first two: a proper rotation). A tensor already diagonal (to
    :data:`~.gravity_field.PRINCIPAL_TOLERANCE` of its trace) keeps its axes, only sorted.
    """
    axes = principal_axes(inertia)
    return Reference(_triple(offset), tuple(_triple(row) for row in axes))


class MassModel(Protocol):
    """What every mass model gives (units: kg, km, kg km^2)."""

    @property
    def mass(self) -> float:
        """Mass [kg]."""

    @property
    def centre_of_mass(self) -> FloatArray:
        """Centre of mass in the model's frame [km], (3,)."""

    @property
    def inertia_tensor(self) -> FloatArray:
        """Inertia tensor about the centre of mass, model's axes [kg km^2], (3, 3)."""

    @property
    def principal_moments(self) -> FloatArray:
        """Principal moments [kg km^2], (3,), in the order of :meth:`gravity_field`'s axes."""

    def gravity_field(self, degree: int,
                      reference_radius: float | None = None) -> GravityField:
        """Return the GravityField to ``degree`` in the centre-of-mass principal-axis frame."""


# -- Quadrature ------------------------------------------------------------------------------


def _gauss_jacobi_01(n: int, alpha: float) -> tuple[FloatArray, FloatArray]:
    """Return n nodes and weights on [0, 1] for the weight (1 - x)^alpha."""
    # scipy.special when a mass model is integrated, not with the module (every process
    # importing tumble_ros.core paid ~0.15 s: benchmarks/HISTORY.md, "Node start-up")
    from scipy.special import roots_jacobi
    x, w = roots_jacobi(n, alpha, 0.0)
    return (x + 1.0) / 2.0, w / 2.0 ** (alpha + 1.0)


def tetrahedron_rule(degree: int) -> tuple[FloatArray, FloatArray]:
    """
    Return a quadrature rule exact for polynomials of total degree ``degree`` on a tetrahedron.

    Returns ``(barycentric (n, 3), weights (n,))``: a point is ``u p1 + v p2 + w p3`` (the 4th
    vertex at the origin), the weights are positive and sum to 1 (multiply by the volume). The
    conical product (Stroud 1971): u = x1, v = (1 - x1) x2, w = (1 - x1)(1 - x2) x3, Jacobian
    (1 - x1)^2 (1 - x2), Gauss-Jacobi of m = degree // 2 + 1 points in each coordinate (exact to
    2m - 1 >= degree). n = m^3.
    """
    if degree < 0:
        raise ValueError(f'degree: must be >= 0, got {degree}')
    m = degree // 2 + 1
    x1, w1 = _gauss_jacobi_01(m, 2.0)
    x2, w2 = _gauss_jacobi_01(m, 1.0)
    x3, w3 = _gauss_jacobi_01(m, 0.0)
    a, b, c = (g.ravel() for g in np.meshgrid(x1, x2, x3, indexing='ij'))
    weights = np.einsum('i,j,k->ijk', w1, w2, w3).ravel() * 6.0
    u = a
    v = (1.0 - a) * b
    w = (1.0 - a) * (1.0 - b) * c
    return np.column_stack([u, v, w]), weights


# -- Ellipsoid -------------------------------------------------------------------------------


def ellipsoid_stokes(semi_axes: ArrayLike, degree: int,
                     reference_radius: float) -> tuple[FloatArray, FloatArray]:
    """
    Return the unnormalised Stokes (C, S), (N+1, N+1), of a homogeneous ellipsoid.

    In its principal frame (semi-axes a, b, c along x, y, z [km]), reference radius R [km]
    (Balmino 1994, eq. for C_2l,2m)::

        C_2l,2m = 3 / R^2l * l! (2l - 2m)! / (2^2m (2l + 3) (2l + 1)!) * (2 - delta_0m)
                  * sum_i (a^2 - b^2)^(m + 2i) (c^2 - (a^2 + b^2) / 2)^(l - m - 2i)
                          / (16^i (l - m - 2i)! (m + i)! i!),   i = 0 .. (l - m) / 2

    every other coefficient is 0 (the odd degrees and orders by symmetry, S by the x-z plane's).
    C_20 = (2c^2 - a^2 - b^2) / (10 R^2), C_22 = (a^2 - b^2) / (20 R^2).
    """
    a, b, c = (float(v) for v in np.asarray(semi_axes, dtype=float))
    C = np.zeros((degree + 1, degree + 1))
    S = np.zeros((degree + 1, degree + 1))
    d, e = a * a - b * b, c * c - (a * a + b * b) / 2.0
    f = math.factorial
    for n in range(0, degree + 1, 2):
        ll = n // 2
        for order in range(0, n + 1, 2):
            mm = order // 2
            total = sum(d ** (mm + 2 * i) * e ** (ll - mm - 2 * i)
                        / (16 ** i * f(ll - mm - 2 * i) * f(mm + i) * f(i))
                        for i in range((ll - mm) // 2 + 1))
            C[n, order] = (3.0 / reference_radius ** n * f(ll) * f(n - order)
                           / (2 ** order * (n + 3) * f(n + 1)) * (1 if mm == 0 else 2) * total)
    return C, S


def _semi_axes(value: Any) -> tuple[float, float, float]:
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__') or len(value) != 3:
        _fail('semi_axes', 'must be a list of 3 numbers [km]', value)
    out = []
    for k, v in enumerate(value):
        try:
            x = float(v)
        except (TypeError, ValueError):
            _fail(f'semi_axes[{k}]', 'must be a number [km]', v)
        if isinstance(v, bool) or not math.isfinite(x) or x <= 0.0:
            _fail(f'semi_axes[{k}]', 'must be a finite number > 0 [km]', v)
        _size(f'semi_axes[{k}]', 2.0 * x, v)
        out.append(x)
    return (out[0], out[1], out[2])


@dataclass(frozen=True)
class Ellipsoid:
    """
    A homogeneous triaxial ellipsoid centred on the origin, axes along x, y, z.

    ``semi_axes`` (a, b, c) [km]; ``density`` [kg/m^3]. Its frame is its centre-of-mass
    principal-axis frame; the moments follow the semi-axes' order (a >= b >= c gives
    Ixx <= Iyy <= Izz).
    """

    semi_axes: tuple[float, float, float]
    density: float

    kind = 'ellipsoid'
    convex = True

    def __post_init__(self) -> None:
        object.__setattr__(self, 'semi_axes', _semi_axes(self.semi_axes))
        object.__setattr__(self, 'density', _density(self.density))

    @property
    def volume(self) -> float:
        """Volume [km^3]: 4/3 pi a b c."""
        a, b, c = self.semi_axes
        return 4.0 / 3.0 * math.pi * a * b * c

    @property
    def mass(self) -> float:
        """Mass [kg]."""
        return self.density * self.volume * KG_PER_KM3_PER_DENSITY

    @property
    def centre_of_mass(self) -> FloatArray:
        """Return the centre of mass: the origin [km]."""
        return np.zeros(3)

    @property
    def principal_moments(self) -> FloatArray:
        """(m (b^2 + c^2) / 5, m (a^2 + c^2) / 5, m (a^2 + b^2) / 5) [kg km^2]."""
        a2, b2, c2 = (s * s for s in self.semi_axes)
        out: FloatArray = self.mass / 5.0 * np.array([b2 + c2, a2 + c2, a2 + b2])
        return out

    @property
    def inertia_tensor(self) -> FloatArray:
        """Inertia tensor about the centre of mass [kg km^2] (diagonal)."""
        return np.diag(self.principal_moments)

    @property
    def principal_axes(self) -> FloatArray:
        """Rows: the principal axes in the model's frame (the identity)."""
        return np.eye(3)

    @property
    def reference(self) -> Reference:
        """Built in principal axes: nothing moved."""
        return IDENTITY

    @property
    def radius(self) -> float:
        """Return the default reference radius [km]: the longest semi-axis (Brillouin sphere)."""
        return max(self.semi_axes)

    def stokes(self, degree: int,
               reference_radius: float | None = None) -> tuple[FloatArray, FloatArray]:
        """Return the unnormalised (C, S) to ``degree`` (:func:`ellipsoid_stokes`)."""
        return ellipsoid_stokes(self.semi_axes, degree, reference_radius or self.radius)

    def gravity_field(self, degree: int,
                      reference_radius: float | None = None) -> GravityField:
        """Return the GravityField to ``degree`` (closed form), principal-axis frame."""
        C, S = self.stokes(degree, reference_radius)
        return _field(self.mass, reference_radius or self.radius, C, S,
                      self.principal_moments)

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any]) -> Ellipsoid:
        """Build from ``semi_axes`` [km] and ``density`` [kg/m^3]."""
        return cls(params.get('semi_axes'), params.get('density'))  # type: ignore[arg-type]


# -- Polyhedron ------------------------------------------------------------------------------


def _mesh_arrays(vertices: Any, facets: Any) -> tuple[FloatArray, np.ndarray]:
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4:
        _fail('vertices', 'must be an (n, 3) array of n >= 4 points [km]', np.shape(v))
    bad = np.flatnonzero(~np.all(np.isfinite(v), axis=1))
    if bad.size:
        _fail(f'vertices[{bad[0]}]', 'must be finite', tuple(v[bad[0]]), vertex=int(bad[0]))
    far = np.flatnonzero(np.any(np.abs(v) > MAX_BODY_SIZE, axis=1))
    if far.size:
        _fail(f'vertices[{far[0]}]', f'a coordinate beyond {MAX_BODY_SIZE:g} km (MAX_BODY_SIZE; '
              'lengths are in km)', tuple(float(x) for x in v[far[0]]), vertex=int(far[0]))
    _size('vertices', mesh_size(v), f'extent {mesh_size(v):.3g} km')
    f = np.asarray(facets)
    if f.ndim != 2 or f.shape[1] != 3 or len(f) < 4:
        _fail('facets', 'must be an (n, 3) array of n >= 4 vertex triples', np.shape(f))
    if len(f) > MAX_FACETS or len(v) > MAX_FACETS:
        _fail('facets', f'at most {MAX_FACETS:,} facets and vertices (MAX_FACETS: twice the '
              'largest radar shape model; decimate the mesh)', f'{len(f):,} facets and '
              f'{len(v):,} vertices')
    if not np.issubdtype(f.dtype, np.integer):
        _fail('facets', 'must be integer vertex indices', f.dtype)
    out = np.flatnonzero(np.any((f < 0) | (f >= len(v)), axis=1))
    if out.size:
        _fail(f'facets[{out[0]}]', f'vertex index outside [0, {len(v) - 1}]',
              tuple(int(i) for i in f[out[0]]), int(out[0]))
    repeated = np.flatnonzero((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2])
                              | (f[:, 0] == f[:, 2]))
    if repeated.size:
        _fail(f'facets[{repeated[0]}]', 'names a vertex twice',
              tuple(int(i) for i in f[repeated[0]]), int(repeated[0]))
    return v, f.astype(np.int64)


def _check_closed(facets: np.ndarray) -> None:
    """Every directed edge once, its reverse once: closed, manifold, consistently oriented."""
    edges = np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]], facets[:, [2, 0]]])
    owner = np.tile(np.arange(len(facets)), 3)
    n = int(facets.max()) + 1
    code = edges[:, 0] * n + edges[:, 1]
    order = np.argsort(code, kind='stable')
    sorted_code = code[order]
    dup = np.flatnonzero(sorted_code[1:] == sorted_code[:-1])
    if dup.size:
        i, j = order[dup[0]], order[dup[0] + 1]
        first, second = sorted((int(owner[i]), int(owner[j])))
        _fail(f'facets[{second}]',
              f'edge ({edges[i, 0]}, {edges[i, 1]}) runs the same way in facets {first} and '
              f'{second}: the facets are not consistently oriented (or the surface is not a '
              'manifold)', tuple(int(k) for k in facets[second]), second)
    reverse = edges[:, 1] * n + edges[:, 0]
    missing = np.flatnonzero(~np.isin(reverse, code))
    if missing.size:
        k = missing[0]
        _fail(f'facets[{owner[k]}]',
              f'edge ({edges[k, 0]}, {edges[k, 1]}) has no facet on its other side: the '
              'surface is open (a missing facet)', tuple(int(i) for i in facets[owner[k]]),
              int(owner[k]))


def _check_one_body(v: FloatArray, f: np.ndarray) -> None:
    """Refuse a facet of no area, and a surface of several separate bodies."""
    flat = degenerate_facet(v, f)
    if flat is not None:
        _fail(f'facets[{flat}]', 'has no area (its vertices are collinear or coincide): no '
              'outward normal', tuple(int(i) for i in f[flat]), flat)
    count, labels = components(f)
    if count > 1:
        second = int(np.flatnonzero(labels != labels[0])[0])
        sizes = np.bincount(np.unique(labels, return_inverse=True)[1])
        _fail(f'facets[{second}]', f'the surface is {count} separate bodies (facet {second} is '
              'not connected to facet 0): a rigid body is one; give each its own shape file',
              f'{", ".join(str(int(n)) for n in sizes)} facets', second)


def _tetra_moments(vertices: FloatArray, facets: np.ndarray,
                   origin: FloatArray) -> tuple[float, FloatArray, FloatArray]:
    """Return (volume, first moment (3,), second moments (3, 3)) about ``origin`` [km]."""
    p = vertices[facets] - origin          # (F, 3 vertices, 3)
    vol = np.einsum('ij,ij->i', p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0
    s = p.sum(axis=1)
    first = (vol[:, None] * s).sum(axis=0) / 4.0
    second = (np.einsum('f,fki,fkj->ij', vol, p, p) + np.einsum('f,fi,fj->ij', vol, s, s)) / 20.0
    return float(vol.sum()), first, second


@dataclass(frozen=True, eq=False)
class Polyhedron:
    """
    A closed triangulated surface of uniform density.

    ``vertices`` (n, 3) [km]; ``facets`` (m, 3) 0-based vertex indices, counter-clockwise seen
    from outside (outward normals); ``density`` [kg/m^3]; ``reference``: how these vertices
    were moved from the shape file's (:class:`Reference`; :data:`IDENTITY` when as read).
    Validated: finite vertices, indices in range, every edge shared by exactly two facets that
    run it in opposite directions (closed, manifold, consistently oriented), a positive volume
    (facets oriented outward). ``convex`` says whether the body equals its convex hull (a
    photometric model needs to know: a non-convex body shadows itself).
    """

    vertices: FloatArray
    facets: np.ndarray
    density: float
    reference: Reference = IDENTITY

    kind = 'polyhedron'

    def __post_init__(self) -> None:
        v, f = _mesh_arrays(self.vertices, self.facets)
        _check_closed(f)
        _check_one_body(v, f)
        v.setflags(write=False)
        f.setflags(write=False)
        object.__setattr__(self, 'vertices', v)
        object.__setattr__(self, 'facets', f)
        object.__setattr__(self, 'density', _density(self.density))
        volume = self._moments[0]
        size = float(np.ptp(v, axis=0).max())
        if abs(volume) <= 1e-9 * size ** 3:
            _fail('facets', f'enclose zero volume ({volume:.3g} km^3): a flat or degenerate '
                  'surface', len(f))
        if volume < 0.0:
            _fail('facets', f'are oriented inward (signed volume {volume:.6g} km^3 < 0): '
                  "list each facet's vertices counter-clockwise seen from outside", len(f))

    @cached_property
    def _moments(self) -> tuple[float, FloatArray, FloatArray]:
        origin = self.vertices.mean(axis=0)     # (about a point near the centre: less rounding)
        volume, first, second = _tetra_moments(self.vertices, self.facets, origin)
        centre = first / volume if volume != 0.0 else np.zeros(3)
        second_c = second - volume * np.outer(centre, centre)
        return volume, centre + origin, second_c

    @property
    def volume(self) -> float:
        """Volume [km^3]."""
        return self._moments[0]

    @property
    def mass(self) -> float:
        """Mass [kg]."""
        return self.density * self.volume * KG_PER_KM3_PER_DENSITY

    @property
    def centre_of_mass(self) -> FloatArray:
        """Centre of mass in the vertices' frame [km]."""
        out: FloatArray = self._moments[1].copy()
        return out

    @property
    def inertia_tensor(self) -> FloatArray:
        """Inertia tensor about the centre of mass, vertices' axes [kg km^2]: rho (tr P - P)."""
        second = self._moments[2] * self.density * KG_PER_KM3_PER_DENSITY
        out: FloatArray = np.trace(second) * np.eye(3) - second
        return out

    @cached_property
    def principal(self) -> Reference:
        """Return the move into centre-of-mass principal axes (:func:`principal_frame`)."""
        return principal_frame(self.inertia_tensor, self.centre_of_mass)

    @property
    def principal_moments(self) -> FloatArray:
        """Principal moments, increasing [kg km^2]."""
        axes = np.asarray(self.principal.rotation)
        out: FloatArray = np.einsum('ki,ij,kj->k', axes, self.inertia_tensor, axes)
        return out

    @property
    def principal_axes(self) -> FloatArray:
        """Rows: the principal axes (increasing moment) in the vertices' frame."""
        return np.asarray(self.principal.rotation)

    @property
    def is_principal(self) -> bool:
        """Whether the vertices' frame is already the centre-of-mass principal-axis frame."""
        size = float(np.ptp(self.vertices, axis=0).max())
        return bool(np.linalg.norm(self.centre_of_mass) <= 1e-9 * size
                    and np.allclose(self.principal_axes, np.eye(3), rtol=0.0, atol=1e-9))

    def in_principal_axes(self) -> Polyhedron:
        """Return the same body moved into its centre-of-mass principal axes (``reference``)."""
        move = self.principal
        return Polyhedron(move.apply(self.vertices), self.facets, self.density,
                          self.reference.then(move))

    @cached_property
    def convexity_defect(self) -> ConvexityDefect | None:
        """Say where the body is not convex (:func:`~.mesh_checks.convexity_defect`), or None."""
        return convexity_defect(self.vertices, self.facets)

    @property
    def convex(self) -> bool:
        """Tell whether the body is convex, to :data:`~.mesh_checks.CONVEXITY_TOLERANCE`."""
        return self.convexity_defect is None

    @property
    def radius(self) -> float:
        """Return the default reference radius [km]: the farthest vertex from the centre."""
        return float(np.linalg.norm(self.vertices - self.centre_of_mass, axis=1).max())

    def point_masses(self, degree: int,
                     apex: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """
        Return (masses [kg] (n,), positions [km] (n, 3)) in principal axes, exact to ``degree``.

        The :func:`tetrahedron_rule` on every tetrahedron (``apex``, facet), ``apex`` [km, in
        the principal frame] by default the centre of mass: the sum of ``m_k P(x_k)`` equals the
        integral of ``rho P`` over the body for every polynomial P of degree <= ``degree``,
        whatever the apex. A tetrahedron of negative signed volume (a facet seen from behind
        from the apex: a non-convex body, or an apex outside) gives negative masses.
        """
        body = self if self.is_principal else self.in_principal_axes()
        bary, weights = tetrahedron_rule(degree)
        top = body.centre_of_mass if apex is None else np.asarray(apex, dtype=float)
        p = body.vertices[body.facets] - top            # (F, 3, 3)
        vol = np.einsum('ij,ij->i', p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0
        positions = (np.einsum('qk,fkj->fqj', bary, p) + top).reshape(-1, 3)
        masses = (vol[:, None] * weights[None, :]).ravel() * self.density \
            * KG_PER_KM3_PER_DENSITY
        return masses, positions

    def gravity_field(self, degree: int,
                      reference_radius: float | None = None) -> GravityField:
        """
        Return the exact GravityField to ``degree`` in the principal-axis frame.

        The sums of :meth:`point_masses` over the regular solid harmonics (the gravity field
        module's formulas; signed masses, so a non-convex body too), ``reference_radius``
        [km] by default :attr:`radius`. Summed in chunks of :data:`CHUNK_POINTS` points.
        """
        radius = reference_radius or self.radius
        masses, positions = self.point_masses(degree)
        C, S = np.zeros((degree + 1, degree + 1)), np.zeros((degree + 1, degree + 1))
        for k in range(0, len(masses), CHUNK_POINTS):
            v, w = regular_solid_harmonics(positions[k:k + CHUNK_POINTS], degree)
            C += np.einsum('i,inm->nm', masses[k:k + CHUNK_POINTS], v)
            S += np.einsum('i,inm->nm', masses[k:k + CHUNK_POINTS], w)
        scale = self.mass * radius ** np.arange(degree + 1)[:, None]
        norm = stokes_normalisation(degree) / scale
        C, S = C * norm, S * norm
        C[0, 0], S[:, 0] = 1.0, 0.0
        return _field(self.mass, radius, C, S, self.principal_moments)

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any]) -> Polyhedron:
        """Build from ``vertices``, ``facets`` (0-based) and ``density``, as given."""
        return cls(np.asarray(params.get('vertices')), np.asarray(params.get('facets')),
                   params.get('density'))  # type: ignore[arg-type]


# -- Density moments given directly -----------------------------------------------------------


def _stokes_arrays(stokes: Any) -> tuple[FloatArray, FloatArray]:
    """Return (C, S) from a flat list n, m, C_nm, S_nm, n, m, ... (C00 = 1 implied)."""
    try:
        values = np.asarray(stokes, dtype=float).ravel()
    except (TypeError, ValueError):
        _fail('stokes', 'must be a flat list of numbers n, m, C_nm, S_nm, ...', stokes)
    if values.size % 4:
        _fail('stokes', 'must be a flat list of (n, m, C_nm, S_nm) quadruples', list(values))
    rows = values.reshape(-1, 4)
    if not np.all(np.isfinite(rows)):
        _fail('stokes', 'must be finite numbers', list(values))
    top = rows[:, 0].max(initial=0)
    if top > MAX_DEGREE:
        k = int(np.argmax(rows[:, 0]))
        _fail(f'stokes[{4 * k}]', f'degree n at most {MAX_DEGREE} (MAX_DEGREE, as '
              'gravity.degree)', float(rows[k, 0]))
    degree = int(max(2, top))
    C, S = np.zeros((degree + 1, degree + 1)), np.zeros((degree + 1, degree + 1))
    C[0, 0] = 1.0
    for k, (n, m, c, s) in enumerate(rows):
        if n != int(n) or m != int(m) or not 0 <= m <= n or n < 1:
            _fail(f'stokes[{4 * k}:{4 * k + 2}]', 'must be integers n >= 1, 0 <= m <= n',
                  (n, m))
        C[int(n), int(m)], S[int(n), int(m)] = c, s
    return C, S


@dataclass(frozen=True)
class DensityMoments:
    """
    A body given by its density moments directly: a :class:`GravityField`.

    The field (mass [kg], reference radius [km], unnormalised Stokes C, S, principal moments
    [kg km^2]: the trace is not in the coefficients, so it is given) is checked by
    GravityField: the frame is the centre of mass (C10, C11, S11 zero) and principal (C21,
    S21, S22 zero), C20 and C22 agree with the moments, the moments are a body's.
    """

    field: GravityField

    kind = 'moments'
    volume = None
    convex = None

    @property
    def mass(self) -> float:
        """Return the mass [kg]."""
        return self.field.mass

    @property
    def centre_of_mass(self) -> FloatArray:
        """Return the centre of mass: the origin [km]."""
        return np.zeros(3)

    @property
    def principal_moments(self) -> FloatArray:
        """Return the principal moments (A, B, C) [kg km^2]."""
        return np.asarray(self.field.principal_moments, dtype=float)

    @property
    def inertia_tensor(self) -> FloatArray:
        """Return the inertia tensor about the centre of mass [kg km^2] (diagonal)."""
        return np.diag(self.principal_moments)

    @property
    def reference(self) -> Reference:
        """Given in principal axes: nothing moved."""
        return IDENTITY

    def gravity_field(self, degree: int,
                      reference_radius: float | None = None) -> GravityField:
        """Return the field to ``degree`` (zeros beyond the degree given)."""
        if reference_radius not in (None, self.field.reference_radius):
            raise ValueError('reference_radius: density moments are given at '
                             f'{self.field.reference_radius} km, got {reference_radius}')
        if degree <= self.field.degree:
            return self.field.truncated(degree)
        C, S = np.zeros((degree + 1, degree + 1)), np.zeros((degree + 1, degree + 1))
        n = self.field.degree + 1
        C[:n, :n], S[:n, :n] = self.field.C, self.field.S
        return _field(self.mass, self.field.reference_radius, C, S, self.principal_moments)

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any]) -> DensityMoments:
        """Build from ``mass``, ``reference_radius``, ``stokes`` (flat), ``principal_moments``."""
        C, S = _stokes_arrays(params.get('stokes', ()))
        try:
            field = GravityField(params.get('mass'),  # type: ignore[arg-type]
                                 params.get('reference_radius'),  # type: ignore[arg-type]
                                 C, S, params.get('principal_moments'))  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            text = str(exc).replace('gravity_field.', '', 1)
            raise MassModelError(f'stokes {text}' if text[:2] in ('C[', 'S[') else text) \
                from None
        return cls(field)


def _field(mass: float, radius: float, C: FloatArray, S: FloatArray,
           moments: FloatArray) -> GravityField:
    return GravityField(mass=mass, reference_radius=radius, C=C, S=S,
                        principal_moments=(float(moments[0]), float(moments[1]),
                                           float(moments[2])))


#: The mass models by name (``body.model`` in a params file; ``inertia`` is no mass model).
MASS_MODELS: dict[str, Any] = {
    'ellipsoid': Ellipsoid,
    'polyhedron': Polyhedron,
    'moments': DensityMoments,
}

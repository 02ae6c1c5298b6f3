"""
The body's gravity field beyond its inertia: unnormalised Stokes coefficients to degree N.

Outside a sphere of radius ``a`` (the reference radius) about the body's centre of mass, its
potential (``U``, with the acceleration ``grad U``; Montenbruck & Gill, *Satellite Orbits*,
sec. 3.2) is

    U(r) = GM/a  sum_{n=0..N} sum_{m=0..n} (a/r)^(n+1) P_nm(sin phi) (C_nm cos m lam
                                                                        + S_nm sin m lam)

with (r, phi, lam) the point's distance, latitude and longitude in the body frame and
P_nm(u) = (1 - u^2)^(m/2) d^m/du^m P_n(u) the associated Legendre functions *without* the
Condon-Shortley phase (P_11 = cos phi > 0). For a body of point masses m_i at r_i (a density
integrated by quadrature is the same sum, positions and weights):

    C_nm = (2 - delta_m0) (n-m)!/(n+m)! / (M a^n)  sum_i m_i r_i^n P_nm(sin phi_i) cos m lam_i
    S_nm = (2 - delta_m0) (n-m)!/(n+m)! / (M a^n)  sum_i m_i r_i^n P_nm(sin phi_i) sin m lam_i

(M = sum m_i; C_00 = 1, S_n0 = 0). ``r^n P_nm cos m lam`` and ``r^n P_nm sin m lam`` are the
regular solid harmonics v_nm, w_nm, polynomials in (x, y, z) computed here without angles by
the recursions of Montenbruck & Gill eq 3.29-3.30 written for r^n instead of r^-(n+1):

    v_00 = 1, w_00 = 0
    v_mm + i w_mm = (2m - 1) (x + i y) (v_{m-1,m-1} + i w_{m-1,m-1})
    v_nm = ((2n - 1) z v_{n-1,m} - (n + m - 1) r^2 v_{n-2,m}) / (n - m)     (w_nm alike)

Degree 2 is the inertia: with the principal moments A, B, C (about x, y, z),
C_20 = (A + B - 2C) / (2 M a^2) (= -J2), C_22 = (B - A) / (4 M a^2), C_21 = S_21 = S_22 = 0;
degree 1 vanishes about the centre of mass. The trace A + B + C is not in the coefficients (a
field is blind to it): :attr:`GravityField.principal_moments` carries it.

Frame: the body's centre-of-mass principal-axis frame, x, y, z the axes of the scenario's
``inertia`` (Ix, Iy, Iz), in the scenario's order (no sorting: the field's x is the body's x).
A field is checked on construction to be about its centre of mass and principal (C_1m, S_11,
C_21, S_21, S_22 zero to :data:`FRAME_TOLERANCE` of the second moment) and its principal
moments to agree with C_20, C_22 to the same tolerance.

Units: mass [kg], reference radius [km], principal moments [kg km^2], coefficients
dimensionless. Proven in tests/test_core_multipole.py.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Sequence

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.limits import MAX_DEGREE
from tumble_ros.core.torques.component import TorqueComponent
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.torques.perturbers import Perturber

__all__ = ['GravityField', 'regular_solid_harmonics', 'stokes_normalisation', 'principal_frame',
           'principal_axes', 'PRINCIPAL_TOLERANCE', 'FRAME_TOLERANCE', 'MAX_DEGREE', 'G_KM3']

#: Relative tolerance of a field's frame (centre of mass, principal axes) and of its moments'
#: agreement with C_20, C_22: relative to the second moment (A + B + C) / (M a^2).
FRAME_TOLERANCE = 1e-9


def regular_solid_harmonics(positions: ArrayLike, degree: int,
                            ) -> tuple[FloatArray, FloatArray]:
    """
    Return (v, w): the regular solid harmonics r^n P_nm(sin phi) (cos, sin) m lam of points.

    ``positions``: (..., 3) Cartesian coordinates (any length unit L); ``v``, ``w``:
    (..., degree + 1, degree + 1) in L^n, index [..., n, m], zero for m > n. Recursions in
    (x, y, z) only (the module's docstring), no angles: exact at the poles and the origin.
    """
    p = np.asarray(positions, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r2 = x * x + y * y + z * z
    shape = p.shape[:-1] + (degree + 1, degree + 1)
    v = np.zeros(shape)
    w = np.zeros(shape)
    v[..., 0, 0] = 1.0
    for m in range(degree + 1):
        if m > 0:
            v[..., m, m] = (2 * m - 1) * (x * v[..., m - 1, m - 1] - y * w[..., m - 1, m - 1])
            w[..., m, m] = (2 * m - 1) * (x * w[..., m - 1, m - 1] + y * v[..., m - 1, m - 1])
        for n in range(m + 1, degree + 1):
            for h in (v, w):
                previous = h[..., n - 2, m] if n - 2 >= m else 0.0
                h[..., n, m] = ((2 * n - 1) * z * h[..., n - 1, m]
                                - (n + m - 1) * r2 * previous) / (n - m)
    return v, w


def stokes_normalisation(degree: int) -> FloatArray:
    """
    Return (2 - delta_m0) (n-m)!/(n+m)! as a (degree + 1, degree + 1) array (0 for m > n).

    The factor of the unnormalised Stokes coefficients over the sums of solid harmonics
    (the mass models' quadratures with signed weights use it too).
    """
    f = np.zeros((degree + 1, degree + 1))
    for n in range(degree + 1):
        for m in range(n + 1):
            f[n, m] = (2.0 - (m == 0)) * math.factorial(n - m) / math.factorial(n + m)
    return f


#: Relative size below which an off-diagonal product of inertia (of the trace), or a centre of
#: mass' offset, counts as zero: the body is already in principal axes (its axes kept, sorted).
PRINCIPAL_TOLERANCE = 1e-12


def principal_axes(inertia: ArrayLike) -> FloatArray:
    """
    Return the principal axes of an inertia tensor as the rows of a proper rotation.

    ``inertia``: (3, 3) about the centre of mass [any unit]. Rows ordered by increasing moment,
    each of the first two rows' largest component positive, the third their cross product. A
    tensor already diagonal (to :data:`PRINCIPAL_TOLERANCE` of its trace) keeps its axes, only
    sorted. The one convention of the point-mass sums (:func:`principal_frame`) and of the mass
    models (``mass_models.principal_frame``).
    """
    tensor = np.asarray(inertia, dtype=float)
    off = tensor - np.diag(np.diag(tensor))
    if np.max(np.abs(off)) <= PRINCIPAL_TOLERANCE * float(np.trace(tensor)):
        axes: FloatArray = np.eye(3)[np.argsort(np.diag(tensor), kind='stable')]
    else:
        axes = np.linalg.eigh(tensor)[1].T.copy()
    for k in range(2):
        if axes[k, np.argmax(np.abs(axes[k]))] < 0.0:
            axes[k] = -axes[k]
    axes[2] = np.cross(axes[0], axes[1])
    return axes


def principal_frame(masses: ArrayLike, positions_km: ArrayLike,
                    ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """
    Return (positions in the principal frame, principal moments, rotation) of point masses.

    The positions [km] relative to the centre of mass, rotated into the principal axes of
    ascending moment (x: the smallest): ``principal = rotation @ (r - centre)``; the moments
    [kg km^2]. For a mass model built in arbitrary axes, before :meth:`GravityField.
    from_point_masses` (whose frame is then the one of a scenario with Ix <= Iy <= Iz).
    """
    m = np.asarray(masses, dtype=float)
    p = np.asarray(positions_km, dtype=float)
    centred = p - (m[:, None] * p).sum(axis=0) / m.sum()
    second = np.einsum('i,ij,ik->jk', m, centred, centred)
    inertia = np.trace(second) * np.eye(3) - second
    rotation = principal_axes(inertia)
    moments: FloatArray = np.einsum('ij,jk,ik->i', rotation, inertia, rotation)
    rotated: FloatArray = centred @ rotation.T
    return rotated, moments, rotation


@dataclass(frozen=True, eq=False)
class GravityField:
    """
    A body's gravity field to degree N, in its centre-of-mass principal-axis frame.

    Attributes
    ----------
    mass : float
        The body's mass M [kg].
    reference_radius : float
        The reference radius a [km] of the coefficients (the expansion converges outside the
        sphere of radius a about the centre of mass that holds the body: take its largest
        extent).
    C, S : (N + 1, N + 1) float arrays
        Unnormalised Stokes coefficients, index [n, m] (zero for m > n; C[0, 0] = 1,
        S[n, 0] = 0): the module's docstring. Kept read-only.
    principal_moments : (A, B, C)
        The principal moments of inertia [kg km^2] about the frame's x, y, z (the scenario's
        ``inertia`` order).

    :attr:`degree` is N. Built once and checked (every ValueError names ``gravity_field.<field>``,
    its value and what is allowed), then trusted: centre of mass and principal axes, and the
    moments agree with C_20, C_22 (:data:`FRAME_TOLERANCE`).

    """

    mass: float
    reference_radius: float
    C: FloatArray
    S: FloatArray
    principal_moments: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ('mass', 'reference_radius'):
            value = getattr(self, name)
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not math.isfinite(value) or not value > 0.0):
                raise ValueError(f'gravity_field.{name}: must be a finite number > 0 '
                                 f'({"kg" if name == "mass" else "km"}), got {value!r}')
            object.__setattr__(self, name, float(value))
        arrays = {}
        for name in ('C', 'S'):
            a = np.array(getattr(self, name), dtype=float)
            if a.ndim != 2 or a.shape[0] != a.shape[1] or not 3 <= a.shape[0] <= MAX_DEGREE + 1:
                raise ValueError(f'gravity_field.{name}: must be a square (N+1, N+1) array, '
                                 f'2 <= N <= {MAX_DEGREE}, got shape {a.shape}')
            if not np.all(np.isfinite(a)):
                raise ValueError(f'gravity_field.{name}: must be finite, got {a.tolist()}')
            if np.any(np.triu(a, 1) != 0.0):
                raise ValueError(f'gravity_field.{name}: must be zero above the diagonal '
                                 f'(m > n), got {a.tolist()}')
            a.setflags(write=False)
            arrays[name] = a
        c, s = arrays['C'], arrays['S']
        if c.shape != s.shape:
            raise ValueError(f'gravity_field.S: must have the shape of C, {c.shape}, got '
                             f'{s.shape}')
        if c[0, 0] != 1.0 or np.any(s[:, 0] != 0.0):
            raise ValueError(f'gravity_field.C: C[0, 0] must be 1 and S[:, 0] zero, got '
                             f'C[0, 0] = {c[0, 0]!r}, S[:, 0] = {s[:, 0].tolist()}')
        object.__setattr__(self, 'C', c)
        object.__setattr__(self, 'S', s)
        moments = tuple(float(v) for v in np.asarray(self.principal_moments, dtype=float))
        if len(moments) != 3 or not all(math.isfinite(v) and v > 0.0 for v in moments):
            raise ValueError(f'gravity_field.principal_moments: must be 3 finite numbers > 0 '
                             f'[kg km^2], got {self.principal_moments!r}')
        object.__setattr__(self, 'principal_moments', moments)
        self._check_frame()

    def _check_frame(self) -> None:
        """Raise ValueError unless centre of mass, principal axes and moments agree."""
        a, b, cz = self.principal_moments
        scale = self.mass * self.reference_radius ** 2
        second = (a + b + cz) / scale
        tol = FRAME_TOLERANCE * second
        c, s = self.C, self.S
        off = {'C[1, 0]': c[1, 0], 'C[1, 1]': c[1, 1], 'S[1, 1]': s[1, 1], 'C[2, 1]': c[2, 1],
               'S[2, 1]': s[2, 1], 'S[2, 2]': s[2, 2]}
        off = {name: float(value) for name, value in off.items()}   # (a plain repr: -0.1)
        for name, value in off.items():
            if abs(value) > tol:
                raise ValueError(
                    f'gravity_field.{name}: must be 0 to {FRAME_TOLERANCE:g} of the second '
                    f'moment (the frame is the centre-of-mass principal-axis frame), got '
                    f'{value!r}')
        expected = {'C[2, 0]': (a + b - 2.0 * cz) / (2.0 * scale),
                    'C[2, 2]': (b - a) / (4.0 * scale)}
        for (name, value), got in zip(expected.items(), (float(c[2, 0]), float(c[2, 2]))):
            if abs(got - value) > tol:
                raise ValueError(
                    f'gravity_field.{name}: must agree with principal_moments '
                    f'{list(self.principal_moments)} (C[2, 0] = (A + B - 2C)/(2 M a^2), '
                    f'C[2, 2] = (B - A)/(4 M a^2)): {value!r} to {FRAME_TOLERANCE:g} of the '
                    f'second moment, got {got!r}')
        if not all(m <= (a + b + cz - m) * (1.0 + 1e-12) for m in (a, b, cz)):
            raise ValueError(f'gravity_field.principal_moments: each must be <= the sum of the '
                             f'other two (a real body), got {list(self.principal_moments)}')

    @property
    def degree(self) -> int:
        """Return N, the highest degree held."""
        return int(self.C.shape[0] - 1)

    @property
    def gm(self) -> float:
        """Return the body's GM [km^3/s^2] (G = 6.67430e-20 km^3 kg^-1 s^-2, CODATA 2018)."""
        return G_KM3 * self.mass

    @classmethod
    def from_point_masses(cls, masses: ArrayLike, positions_km: ArrayLike, degree: int,
                          reference_radius: float) -> 'GravityField':
        """
        Return the field of point masses [kg] at ``positions_km`` (n, 3), by exact sums.

        The positions must be in the centre-of-mass principal-axis frame already
        (:func:`principal_frame` gives it); a density integrated by quadrature is the same
        call with the nodes and their weights. ``degree`` N >= 2, ``reference_radius`` [km].
        """
        m = np.asarray(masses, dtype=float).reshape(-1)
        p = np.asarray(positions_km, dtype=float).reshape(-1, 3)
        if m.shape[0] != p.shape[0] or m.size == 0 or not np.all(m > 0.0):
            raise ValueError(f'gravity_field.masses: must be n > 0 masses > 0 kg, one per '
                             f'position ({p.shape[0]}), got {m.size} (min {m.min(initial=0)!r})')
        if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not (
                2 <= degree <= MAX_DEGREE):
            raise ValueError(f'gravity_field.degree: must be an integer in [2, {MAX_DEGREE}], '
                             f'got {degree!r}')
        total = float(m.sum())
        v, w = regular_solid_harmonics(p, int(degree))
        scale = (float(reference_radius) ** np.arange(degree + 1))[:, None]
        norm = stokes_normalisation(int(degree)) / (total * scale)
        c = norm * np.einsum('i,inm->nm', m, v)
        s = norm * np.einsum('i,inm->nm', m, w)
        c[0, 0] = 1.0
        s[:, 0] = 0.0
        x2, y2, z2 = (np.einsum('i,i->', m, p[:, k] * p[:, k]) for k in range(3))
        return cls(total, reference_radius, c, s, (y2 + z2, x2 + z2, x2 + y2))

    @classmethod
    def from_principal_moments(cls, mass: float, reference_radius: float,
                               principal_moments: Sequence[float] | FloatArray,
                               degree: int = 2) -> 'GravityField':
        """
        Return the field of the inertia alone: C_20 and C_22 of the moments [kg km^2].

        Every other coefficient to ``degree`` zero (the field of a body of that inertia with
        no higher moments, e.g. a homogeneous ellipsoid to degree 3).
        """
        a, b, cz = (float(v) for v in principal_moments)
        scale = float(mass) * float(reference_radius) ** 2
        c = np.zeros((degree + 1, degree + 1))
        c[0, 0] = 1.0
        c[2, 0] = (a + b - 2.0 * cz) / (2.0 * scale)
        c[2, 2] = (b - a) / (4.0 * scale)
        return cls(mass, reference_radius, c, np.zeros_like(c), (a, b, cz))

    def with_principal_moments(self, principal_moments: Sequence[float] | FloatArray,
                               ) -> 'GravityField':
        """
        Return this field with other principal moments [kg km^2]: degree 2 made theirs.

        C_20 and C_22 follow the moments (the module's docstring); the mass, the reference
        radius and every coefficient of degree 0, 1 and 3 ... N are kept (a body whose inertia
        changed but not its higher moments, e.g. an inertia drawn in an ensemble).
        """
        a, b, cz = (float(v) for v in principal_moments)
        scale = self.mass * self.reference_radius ** 2
        c = self.C.copy()
        c[2, 0] = (a + b - 2.0 * cz) / (2.0 * scale)
        c[2, 2] = (b - a) / (4.0 * scale)
        return GravityField(self.mass, self.reference_radius, c, self.S.copy(), (a, b, cz))

    def truncated(self, degree: int) -> 'GravityField':
        """Return this field to ``degree`` (2 <= degree <= :attr:`degree`)."""
        if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not (
                2 <= degree <= self.degree):
            raise ValueError(f'gravity_field.degree: must be an integer in [2, {self.degree}] '
                             f'(the degree the field holds), got {degree!r}')
        k = int(degree) + 1
        return GravityField(self.mass, self.reference_radius, self.C[:k, :k].copy(),
                            self.S[:k, :k].copy(), self.principal_moments)

    def packed(self, degree: int | None = None) -> tuple[float, ...]:
        """
        Return C then S to ``degree`` (default all), lower triangles row by row.

        C_nm at index n (n + 1) / 2 + m, S_nm at (N + 1)(N + 2)/2 + n (n + 1) / 2 + m: the
        layout :func:`~tumble_ros.core.torques.multipole.field_acceleration` reads.
        """
        n = self.degree if degree is None else int(degree)
        rows = np.tril_indices(n + 1)
        return tuple(float(v) for v in self.C[rows]) + tuple(float(v) for v in self.S[rows])

    def inertia_scale(self, inertia: Sequence[float] | FloatArray) -> float:
        """
        Return scale = principal moment [kg km^2] / normalised moment of a scenario's inertia.

        ValueError unless :attr:`principal_moments` are proportional to ``inertia`` (the
        scenario's normalised (Ix, Iy, Iz), same axes) to :data:`FRAME_TOLERANCE` relative: a
        field and the inertia the body turns with cannot disagree.
        """
        ratios = [m / float(i) for m, i in zip(self.principal_moments, inertia)]
        scale = sum(ratios) / 3.0
        if not all(abs(r - scale) <= FRAME_TOLERANCE * scale for r in ratios):
            raise ValueError(
                f'gravity_field.principal_moments: must be proportional to the inertia '
                f'{[float(i) for i in inertia]} (same axes) to {FRAME_TOLERANCE:g} relative, '
                f'got {list(self.principal_moments)} kg km^2 (ratios {ratios})')
        return scale

    def torque_component(self, orbit: KeplerOrbit, inertia: Sequence[float] | FloatArray,
                         degree: int) -> TorqueComponent:
        """
        Return the torque of a perturber on ``orbit`` on this field to ``degree``.

        In the scenario's normalised ``inertia`` units (:meth:`inertia_scale`) * rad/yr^2: the
        orbit as a perturber (:class:`~tumble_ros.core.torques.perturbers.Perturber`, named
        ``kepler_orbit`` as the scenario's) whose torque law takes this field.
        """
        return Perturber('kepler_orbit', orbit).torque_component(inertia, self.truncated(degree))

    def __eq__(self, other: Any) -> bool:
        """Return True for the same mass, radius, moments and coefficients."""
        if not isinstance(other, GravityField):
            return NotImplemented
        return (self.mass == other.mass and self.reference_radius == other.reference_radius
                and self.principal_moments == other.principal_moments
                and np.array_equal(self.C, other.C) and np.array_equal(self.S, other.S))

    def __hash__(self) -> int:
        """Return a hash of the values compared by ``==``."""
        return hash((self.mass, self.reference_radius, self.principal_moments,
                     self.C.tobytes(), self.S.tobytes()))


#: The constant of gravitation [km^3 kg^-1 s^-2] (CODATA 2018: 6.67430e-11 m^3 kg^-1 s^-2).
G_KM3 = 6.67430e-20

"""
Perturbers: the bodies whose gravity torques the asteroid, each a torque component.

A :class:`Perturber` is a name, a GM, where it is (its *source*: a :class:`~.orbits.KeplerOrbit`
relative to the asteroid, or a tabulated :class:`~.ephemeris.Ephemeris`) and, optionally, its
own oblateness (J2, reference radius, pole). Its torque on the body, body axes, at time t and
attitude q (body -> orbital):

    s = C(q)^T r(t)                              (r: the source's position, orbital frame [km])
    M = point_mass_torque(GM, s, I)              (3 GM / s^3 u x (I u), paper eq 12)
      + oblateness_torque(GM J2 R^2, C(q)^T k, s, I)      (when J2 != 0; :mod:`.oblateness`)

in one compiled function per kind of source (:data:`SOURCE_KINDS`, a registry) that reads the
component's ``par``: ``par[0:9]`` = (GM [km^3/yr^2], Ix, Iy, Iz, GM J2 R^2 [km^5/yr^2], pole
kx, ky, kz (orbital frame), o), then the source's own block, then, when the body's field to
degree N is given (o > 0), at ``par[o:]`` (GM M / scale, its reference radius [km], N, its
packed Stokes coefficients with C_00 = 0). Several perturbers are several components: the
kernels add their torques (``kernels.physics.body_torque``).

:func:`perturber_torque` is the one place the torque law is applied: the point-mass law on the
inertia (``gravity_gradient.point_mass_torque``, degree 2), or, with the body's field, the
torque -m_p R x a(R) to degree N (``multipole.field_torque``), for every source at once. The
field's monopole is left out (C_00 = 0): it exerts no torque, and R x a_00(R) computed in
floating point is not 0 but ~1e-16 |R| |a_00|, which at R = 1e6 km from a 0.3-km body is 5e-3
of the quadrupole torque.

Units: GM [km^3/s^2] in the dataclass (as every table states it), km^3/yr^2 inside.
"""
from __future__ import annotations

from dataclasses import dataclass
import functools
import math
from typing import Any, Callable, Protocol, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit_inline
from tumble_ros.core.torques.component import torque_function, TorqueComponent
from tumble_ros.core.torques.ephemeris import Ephemeris, ephemeris_position
from tumble_ros.core.torques.frames import orbital_to_body
from tumble_ros.core.torques.gravity_gradient import point_mass_torque
from tumble_ros.core.torques.multipole import field_torque
from tumble_ros.core.torques.oblateness import oblateness_torque
from tumble_ros.core.torques.orbits import (KeplerOrbit, MAX_GM, orbit_state, perturber_radius,
                                            plane_to_orbital)
from tumble_ros.core.units import PERTURBER_RADII, SECONDS_PER_YEAR

__all__ = ['Perturber', 'Source', 'check_name', 'SourceKind', 'SOURCE_KINDS',
           'perturber_torque', 'kepler_perturber_torque', 'ephemeris_perturber_torque', 'MAX_J2',
           'LAW_WIDTH', 'BodyField', 'field_block']

#: Where a perturber is: a Kepler orbit or a tabulated ephemeris, relative to the asteroid.
Source = KeplerOrbit | Ephemeris
#: Largest |J2| accepted: 0.1 (the Earth's is 1.08e-3, Saturn's, the most oblate planet's,
#: 1.63e-2).
MAX_J2 = 0.1
#: Parameters of the torque law ahead of the source's block: GM, Ix, Iy, Iz, GM J2 R^2, pole,
#: the offset of the body's field block (0: none).
LAW_WIDTH = 9
_KM3_PER_YR2 = SECONDS_PER_YEAR * SECONDS_PER_YEAR


@jit_inline
def perturber_torque(par: npt.NDArray[np.float64], x: float, y: float, z: float, q0: float,
                     q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """
    Return a perturber's torque on the body [I rad/yr^2], body axes.

    (x, y, z): the perturber's position relative to the asteroid [km], orbital frame; ``par``
    its law block (module docstring); q the attitude (body -> orbital).
    """
    sx, sy, sz = orbital_to_body(x, y, z, q0, q1, q2, q3)
    o = int(par[8])
    if o == 0:
        tx, ty, tz = point_mass_torque(par[0], sx, sy, sz, par[1], par[2], par[3])
    else:
        tx, ty, tz = field_torque(sx, sy, sz, par[o], par[o + 1], int(par[o + 2]), par, o + 3)
    if par[4] != 0.0:
        kx, ky, kz = orbital_to_body(par[5], par[6], par[7], q0, q1, q2, q3)
        jx, jy, jz = oblateness_torque(par[4], kx, ky, kz, sx, sy, sz, par[1], par[2], par[3])
        tx += jx
        ty += jy
        tz += jz
    return tx, ty, tz


def kepler_perturber_torque(par: npt.NDArray[np.float64], t: float, q0: float, q1: float,
                            q2: float, q3: float) -> tuple[float, float, float]:
    """
    Return the torque of a perturber on a Kepler orbit, body axes.

    par[9:17] = (a, e, t_p, lambda_p, cos i, sin i, cos node, sin node): :func:`~.orbits.
    orbit_state` with the GM par[0] and :func:`~.orbits.plane_to_orbital`. The Python law;
    the kernels call its compiled form, ``SOURCE_KINDS[KeplerOrbit].function``.
    """
    distance, angle = orbit_state(t, par[0], par[9], par[10], par[11], par[12])
    sx, sy, sz = plane_to_orbital(math.sin(angle), math.cos(angle), par[13], par[14], par[15],
                                  par[16])
    return perturber_torque(par, distance * sx, distance * sy, distance * sz, q0, q1, q2, q3)


def ephemeris_perturber_torque(par: npt.NDArray[np.float64], t: float, q0: float, q1: float,
                               q2: float, q3: float) -> tuple[float, float, float]:
    """
    Return the torque of a perturber on a tabulated ephemeris (par[9:]: its block).

    The Python law; the kernels call its compiled form, ``SOURCE_KINDS[Ephemeris].function``.
    """
    x, y, z = ephemeris_position(par, LAW_WIDTH, t)
    return perturber_torque(par, x, y, z, q0, q1, q2, q3)


class BodyField(Protocol):
    """The body's gravity field as the torque law reads it (``model.gravity_field``)."""

    @property
    def mass(self) -> float:
        """Return the mass M [kg]."""

    @property
    def reference_radius(self) -> float:
        """Return the coefficients' reference radius [km]."""

    @property
    def degree(self) -> int:
        """Return the degree N."""

    def packed(self, degree: int | None = None) -> tuple[float, ...]:
        """Return C then S, lower triangles row by row (C_00 first)."""

    def inertia_scale(self, inertia: Sequence[float] | npt.NDArray[np.float64]) -> float:
        """Return principal moment [kg km^2] / normalised moment."""


def field_block(field: BodyField, inertia: Sequence[float] | npt.NDArray[np.float64],
                gm: float) -> tuple[float, ...]:
    """
    Return the field block of the torque law for a perturber of GM ``gm`` [km^3/yr^2].

    (GM M / scale, reference radius [km], N, C and S packed with C_00 = 0): the torque
    -GM M R x a(R) / GM_body in the scenario's normalised inertia units (scale =
    ``field.inertia_scale(inertia)``; ValueError when the field's moments disagree with it).
    """
    packed = list(field.packed())
    packed[0] = 0.0                         # no monopole (module docstring)
    return (gm * field.mass / field.inertia_scale(inertia), float(field.reference_radius),
            float(field.degree), *packed)


def _kepler_block(orbit: KeplerOrbit) -> tuple[float, ...]:
    return (orbit.a, orbit.e, orbit.t_p, orbit.lambda_p, math.cos(orbit.inclination),
            math.sin(orbit.inclination), math.cos(orbit.node), math.sin(orbit.node))


def _ephemeris_block(ephemeris: Ephemeris) -> tuple[float, ...]:
    return ephemeris.parameters()


@functools.lru_cache(maxsize=None)
def _compiled(law: Callable[..., Any]) -> Callable[..., Any]:
    return torque_function(law)


@dataclass(frozen=True)
class SourceKind:
    """
    How one kind of source is run: its torque law and its parameter block.

    ``law`` is the Python function; :attr:`function`, the :func:`~.component.torque_function`
    the kernels call, is made from it on first use, not when this module is imported: numba
    loading two C callbacks from its cache (and the typing machinery they need, ~0.2 s) was
    paid by every process importing ``tumble_ros.core``, the nodes included, with perturbers
    or without (benchmarks/HISTORY.md, "Node start-up").
    """

    name: str
    law: Callable[..., Any]
    block: Callable[[Any], tuple[float, ...]]

    @property
    def function(self) -> Callable[..., Any]:
        """Return the compiled torque function of :attr:`law` (compiled once a process)."""
        return _compiled(self.law)


#: The kinds of source, by type (a registry: a new kind of source is a new row).
SOURCE_KINDS: dict[type, SourceKind] = {
    KeplerOrbit: SourceKind('kepler', kepler_perturber_torque, _kepler_block),
    Ephemeris: SourceKind('ephemeris', ephemeris_perturber_torque, _ephemeris_block),
}


def check_name(name: object) -> str:
    """
    Return a perturber's ``name``; ValueError unless an identifier (letters, digits, _).

    The name is a parameter key (``perturbers.<name>.kind``): checked before any of its
    fields is read, so ``moon-1`` is refused for its name, not for a ``kind`` never found.
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError('perturbers.names: each name must be an identifier (letters, digits, '
                         f'_; a parameter key), got {name!r}')
    return name


def _number(field: str, value: object, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f'{field}: must be a finite number{unit}, got {value!r}')
    return float(value)


@dataclass(frozen=True)
class Perturber:
    """
    A body whose gravity torques the asteroid.

    Attributes
    ----------
    name : str
        Its name (``earth``, ``moon``, ``sun``...): a ROS parameter key and a marker's label.
    source : KeplerOrbit or Ephemeris
        Where it is relative to the asteroid, in the orbital frame.
    gm : float
        Its GM [km^3/s^2]. 0 (default): the Kepler orbit's ``gm`` (an ephemeris needs it given).
    j2 : float
        Its oblateness J2 (the Earth: 1.0826e-3), |J2| <= :data:`MAX_J2`; 0: a point mass.
    radius : float
        The reference radius of J2 [km]; 0: the Sun's, the Earth's or the Moon's when ``gm`` is
        theirs (``units.PERTURBER_RADII``). Needed (> 0) when ``j2`` is not 0.
    pole : (float, float, float)
        The direction of the perturber's pole (the symmetry axis of its J2), orbital frame; any
        length but 0 (kept as given, normalised where used: :meth:`law`).

    Every field is checked here; a ValueError names it (``perturbers.<name>.<field>``).

    """

    name: str
    source: Source
    gm: float = 0.0
    j2: float = 0.0
    radius: float = 0.0
    pole: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        check_name(self.name)
        field = f'perturbers.{self.name}'
        if type(self.source) not in SOURCE_KINDS:
            raise ValueError(f'{field}.source: must be a KeplerOrbit or an Ephemeris, got '
                             f'{self.source!r}')
        gm = _number(f'{field}.gm', self.gm, ' [km^3/s^2]')
        if isinstance(self.source, KeplerOrbit) and gm == 0.0:
            gm = self.source.gm
        if not 0.0 < gm <= MAX_GM:
            raise ValueError(f'{field}.gm: must be in (0, {MAX_GM:g}] km^3/s^2 (0: the Kepler '
                             f"orbit's; an ephemeris needs it), got {self.gm!r}")
        if isinstance(self.source, KeplerOrbit) and gm != self.source.gm:
            raise ValueError(f'{field}.gm: a Kepler orbit moves with its own gm '
                             f'({self.source.gm!r} km^3/s^2): give 0 or that, got {self.gm!r}')
        object.__setattr__(self, 'gm', gm)
        j2 = _number(f'{field}.j2', self.j2, '')
        if not abs(j2) <= MAX_J2:
            raise ValueError(f'{field}.j2: must be in [-{MAX_J2}, {MAX_J2}] (the Earth: '
                             f'1.0826e-3), got {self.j2!r}')
        object.__setattr__(self, 'j2', j2)
        radius = _number(f'{field}.radius', self.radius, ' [km]')
        if radius < 0.0:
            raise ValueError(f"{field}.radius: must be >= 0 km (0: the Sun's, the Earth's or "
                             f"the Moon's by gm), got {self.radius!r}")
        if radius == 0.0:
            radius = perturber_radius(gm)[0]
        if j2 != 0.0 and radius == 0.0:
            known = ', '.join(PERTURBER_RADII)
            raise ValueError(f'{field}.radius: J2 needs its reference radius (> 0 km; taken '
                             f'by gm only for the {known}), got {self.radius!r}')
        object.__setattr__(self, 'radius', radius)
        if isinstance(self.source, Ephemeris) and radius > 0.0:
            closest, when = self.source.closest_approach()
            if not closest > radius:
                raise ValueError(f'{field}.ephemeris_file: the table passes {closest:.6g} km from '
                                 f'the perturber at t = {when:.6g} yr, inside its radius '
                                 f'{radius!r} km (a collision, not a flyby)')
        pole = self.pole
        if isinstance(pole, (str, bytes)) or not hasattr(pole, '__len__') or len(pole) != 3:
            raise ValueError(f'{field}.pole: must be 3 numbers (orbital frame), got {pole!r}')
        k = [_number(f'{field}.pole[{j}]', v, '') for j, v in enumerate(pole)]
        norm = math.sqrt(sum(v * v for v in k))
        if not norm > 0.0:
            raise ValueError(f'{field}.pole: must not be the zero vector, got {pole!r}')
        object.__setattr__(self, 'pole', (k[0], k[1], k[2]))

    @property
    def kind(self) -> SourceKind:
        """Return how the source is run (:data:`SOURCE_KINDS`)."""
        return SOURCE_KINDS[type(self.source)]

    def law(self, inertia: Sequence[float] | npt.NDArray[np.float64],
            field_offset: int = 0) -> tuple[float, ...]:
        """
        Return the torque law's block.

        (GM [km^3/yr^2], Ix, Iy, Iz, GM J2 R^2 [km^5/yr^2], unit pole, the offset of the body's
        field block or 0).
        """
        gm = self.gm * _KM3_PER_YR2
        ix, iy, iz = (float(v) for v in inertia)
        norm = math.sqrt(sum(v * v for v in self.pole))
        return (gm, ix, iy, iz, gm * self.j2 * self.radius * self.radius,
                self.pole[0] / norm, self.pole[1] / norm, self.pole[2] / norm,
                float(field_offset))

    def torque_component(self, inertia: Sequence[float] | npt.NDArray[np.float64],
                         field: BodyField | None = None) -> TorqueComponent:
        """
        Return this perturber's torque on a body of principal moments ``inertia``.

        ``field``: the body's gravity field to degree N (``model.gravity_field.GravityField``,
        its moments proportional to ``inertia``): the torque to that degree; None: the
        point-mass law on the inertia (degree 2).
        """
        kind = self.kind
        source = kind.block(self.source)
        if field is None:
            return TorqueComponent(self.name, kind.function, self.law(inertia) + source)
        offset = LAW_WIDTH + len(source)
        return TorqueComponent(self.name, kind.function,
                               self.law(inertia, offset) + source
                               + field_block(field, inertia, self.gm * _KM3_PER_YR2))

    def position(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return where the perturber is relative to the asteroid [km], orbital frame, (n, 3)."""
        position: npt.NDArray[np.float64] = self.source.position(t)
        return position

    @property
    def mean_motion(self) -> float:
        """Return its own rate [rad/yr]: a Kepler orbit's n; 0 for an ephemeris."""
        return self.source.mean_motion if isinstance(self.source, KeplerOrbit) else 0.0

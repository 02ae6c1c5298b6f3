"""
A run's synthetic lightcurve: where the Sun and the observer are, and what the observer sees.

Frames and units: the scenario's inertial (orbital) frame; times [yr] as in core; distances
[au] (``units.KM_PER_AU``); angles [rad]. :func:`observer_geometry` places the Sun and the
observer from the scenario's orbit, once per sample:

- circular orbit (``orbit_rate`` > 0, no ``orbit``): the Sun is the torquing body, its
  direction ``gravity_gradient.sun_direction_orbital`` and its distance the orbit's radius
  (Kepler's third law, ``Scenario.perturber_position``); the observer stands in the fixed
  direction ``settings.observer`` 1 au away (the default (0, 0, 0): along the Sun, zero phase:
  a telescope at opposition);
- a Kepler orbit whose GM is the Sun's: the same, with the Sun on that orbit;
- a Kepler orbit or flyby of another body (the Earth: Apophis 2029): the observer is on that
  body (a geocentric observer: the topocentric parallax, up to R_earth / distance, 9.6 deg at
  Apophis' perigee, is not modelled), at its distance; the Sun is fixed in direction
  ``settings.sun`` at 1 au. Over a flyby of days this ignores the Sun's apparent motion,
  ~1 deg per day (the Earth's heliocentric motion; the asteroid's own position change adds
  distance / 1 au, 2.6e-4 rad at 38,000 km): +-3 deg over the 6 days of the Apophis run;
- no torque at all (``orbit_rate`` 0, no orbit): the Sun fixed along ``settings.sun`` at 1 au,
  the observer as on a circular orbit.

Light time (``settings.light_time``): the observer receives at t + delta / c what the body
emitted at t; the record's times are then the reception times, each sample's brightness the
attitude at its own (emission) time: exact, no interpolation; the geometry is taken at t.
Without it the record's times are the simulation's.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, TYPE_CHECKING

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.units import KM_PER_AU, SECONDS_PER_YEAR
from tumble_ros.core.photometry.brightness import (aspect_angles, brightness, magnitude,
                                                   phase_angle, reference_brightness)
from tumble_ros.core.photometry.scattering import LAWS
from tumble_ros.core.photometry.shape import (body_mesh, DEFAULT_SUBDIVISIONS,
                                              MAX_SUBDIVISIONS, Mesh)
from tumble_ros.core.torques.gravity_gradient import sun_direction_orbital
from tumble_ros.core.torques.orbits import perturber_radius, SPEED_OF_LIGHT

if TYPE_CHECKING:
    from tumble_ros.core.model.scenario import Scenario

__all__ = ['LightcurveSettings', 'ObserverGeometry', 'LightcurveRecord', 'observer_geometry',
           'synthetic_lightcurve', 'lightcurve_mesh', 'LIGHTCURVE_PARAMETER_DOCS']


def _unit_or_zero(name: str, value: Any, zero_allowed: bool) -> tuple[float, float, float]:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = np.array([np.nan])
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f'lightcurve.{name}: must be three finite numbers (a direction, '
                         f'orbital frame), got {value!r}')
    norm = float(np.linalg.norm(v))
    if norm == 0.0:
        if zero_allowed:
            return (0.0, 0.0, 0.0)
        raise ValueError(f'lightcurve.{name}: must be a non-zero direction, got {value!r}')
    return (float(v[0] / norm), float(v[1] / norm), float(v[2] / norm))


@dataclass(frozen=True)
class LightcurveSettings:
    """
    What the synthetic lightcurve assumes; validated once (every error names its field).

    Attributes
    ----------
    enabled : bool
        Compute and publish the lightcurve (when the body is physical).
    law : str
        Scattering law, a name of ``scattering.LAWS`` (default ``kaasalainen``).
    observer : (x, y, z)
        Direction to the observer, orbital frame, used where the orbit places no observer
        (``lightcurve`` module docstring); normalised here; (0, 0, 0) (default): along the Sun.
    sun : (x, y, z)
        Direction to the Sun, orbital frame, used where the orbit does not give it (a flyby of
        the Earth, no orbit); normalised here; default +Y' (0, 1, 0).
    light_time : bool
        Label samples with their reception times t + delta / c (default False).
    subdivisions : int
        Icosphere subdivisions of the body's mesh, 0 to ``shape.MAX_SUBDIVISIONS``.
    """

    enabled: bool = True
    law: str = 'kaasalainen'
    observer: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sun: tuple[float, float, float] = (0.0, 1.0, 0.0)
    light_time: bool = False
    subdivisions: int = DEFAULT_SUBDIVISIONS

    def __post_init__(self) -> None:
        for name in ('enabled', 'light_time'):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f'lightcurve.{name}: must be true or false, got '
                                 f'{getattr(self, name)!r}')
            object.__setattr__(self, name, bool(getattr(self, name)))
        if self.law not in LAWS:
            raise ValueError(f"lightcurve.law: must be one of {', '.join(LAWS)}, got "
                             f'{self.law!r}')
        object.__setattr__(self, 'observer', _unit_or_zero('observer', self.observer, True))
        object.__setattr__(self, 'sun', _unit_or_zero('sun', self.sun, False))
        k = self.subdivisions
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) \
                or not 0 <= k <= MAX_SUBDIVISIONS:
            raise ValueError(f'lightcurve.subdivisions: must be an integer in [0, '
                             f'{MAX_SUBDIVISIONS}], got {k!r}')
        object.__setattr__(self, 'subdivisions', int(k))

    def to_parameters(self) -> dict[str, Any]:
        """Return the flat ``lightcurve.*`` parameters."""
        return {'lightcurve.enabled': self.enabled, 'lightcurve.law': self.law,
                'lightcurve.observer': list(self.observer), 'lightcurve.sun': list(self.sun),
                'lightcurve.light_time': self.light_time,
                'lightcurve.subdivisions': self.subdivisions}

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any]) -> 'LightcurveSettings':
        """Build from the ``lightcurve.*`` keys of a flat mapping (others are ignored)."""
        prefix = 'lightcurve.'
        values = {k[len(prefix):]: v for k, v in params.items() if k.startswith(prefix)}
        unknown = sorted(set(values) - set(cls.__dataclass_fields__))
        if unknown:
            raise ValueError(f'lightcurve.{unknown[0]}: unknown lightcurve parameter (known: '
                             f"{', '.join(LIGHTCURVE_PARAMETER_DOCS)})")
        for name in ('observer', 'sun'):
            if name in values:
                values[name] = tuple(values[name]) if isinstance(values[name], (list, tuple)) \
                    else values[name]
        return cls(**values)


#: Unit and meaning of every ``lightcurve.*`` parameter (docs/ros.md's table).
LIGHTCURVE_PARAMETER_DOCS: dict[str, tuple[str, str]] = {
    'lightcurve.enabled': ('', 'compute and publish the lightcurve topic (physical bodies only)'),
    'lightcurve.law': ('', 'scattering law: ' + ', '.join(LAWS)),
    'lightcurve.observer': ('', 'direction to the observer, orbital frame, where the orbit '
                            'places none; (0, 0, 0) = along the Sun (zero phase)'),
    'lightcurve.sun': ('', 'direction to the Sun, orbital frame, where the orbit does not give '
                       "it (a flyby of the Earth, no torque); default +Y'"),
    'lightcurve.light_time': ('', 'stamp samples at their reception time t + delta / c'),
    'lightcurve.subdivisions': ('', f'icosphere subdivisions of the body mesh, 0 to '
                                f'{MAX_SUBDIVISIONS} (20 4^k facets)'),
}


@dataclass(frozen=True)
class ObserverGeometry:
    """
    Where the Sun and the observer are at n sample times.

    ``sun``, ``observer``: unit directions from the body, (n, 3) orbital frame;
    ``sun_distance``, ``observer_distance``: (n,) [au].
    """

    sun: FloatArray
    observer: FloatArray
    sun_distance: FloatArray
    observer_distance: FloatArray


def _tile(direction: tuple[float, float, float], n: int) -> FloatArray:
    out: FloatArray = np.tile(np.asarray(direction, dtype=float), (n, 1))
    return out


def observer_geometry(scenario: Scenario, t: ArrayLike,
                      settings: LightcurveSettings) -> ObserverGeometry:
    """Return the Sun's and the observer's places at times ``t`` [yr] (module docstring)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    n = t.size
    one_au = np.ones(n)
    orbit = scenario.orbit
    sun_is_perturber = (orbit is None and scenario.orbit_rate != 0.0) or (
        orbit is not None and perturber_radius(orbit.gm)[1] == 'Sun')
    if sun_is_perturber:
        if orbit is None:
            sun = sun_direction_orbital(t, scenario.orbit_rate)
        else:
            sun = orbit.direction(t)
        sun_distance = np.linalg.norm(scenario.perturber_position(t), axis=1) / KM_PER_AU
    else:
        sun = _tile(settings.sun, n)
        sun_distance = one_au
    if orbit is not None and not sun_is_perturber:
        position = scenario.perturber_position(t)
        observer_distance = np.linalg.norm(position, axis=1)
        observer = position / observer_distance[:, None]
        observer_distance = observer_distance / KM_PER_AU
    else:
        observer = sun.copy() if settings.observer == (0.0, 0.0, 0.0) \
            else _tile(settings.observer, n)
        observer_distance = one_au
    return ObserverGeometry(sun, observer, sun_distance, observer_distance)


@dataclass(frozen=True)
class LightcurveRecord:
    """
    A synthetic lightcurve, one row per sample.

    ``t`` (n,) [yr]: the sample times, or the reception times with light time; ``light_time``
    (n,) [s] delta / c (0 without it); ``brightness`` (n,) [mesh area units];
    ``magnitude`` (n,) [mag]; ``phase_angle`` (n,) [rad]; ``sun_aspect``, ``observer_aspect``
    (n, 2) (latitude, longitude) [rad] in body axes (``brightness`` module docstring).
    """

    t: FloatArray
    light_time: FloatArray
    brightness: FloatArray
    magnitude: FloatArray
    phase_angle: FloatArray
    sun_aspect: FloatArray
    observer_aspect: FloatArray


def lightcurve_mesh(scenario: Scenario, settings: LightcurveSettings) -> Mesh:
    """Return the body's mesh (``shape.body_mesh``; ValueError for unphysical moments)."""
    return body_mesh(scenario.inertia, settings.subdivisions)


def synthetic_lightcurve(scenario: Scenario, t: ArrayLike, quaternion: ArrayLike,
                         settings: LightcurveSettings | None = None,
                         mesh: Mesh | None = None) -> LightcurveRecord:
    """
    Return what the observer sees of the body at times ``t`` [yr] with attitudes ``quaternion``.

    ``quaternion`` (n, 4) body -> orbital, scalar first (``simulate(scenario).quaternion``);
    ``settings`` default :class:`LightcurveSettings`; ``mesh`` default the scenario's
    (:func:`lightcurve_mesh`: pass it to reuse it across calls). ValueError for a body that
    breaks the triangle inequality.
    """
    settings = LightcurveSettings() if settings is None else settings
    t = np.atleast_1d(np.asarray(t, dtype=float))
    q = np.asarray(quaternion, dtype=float).reshape(-1, 4)
    if q.shape[0] != t.size:
        raise ValueError(f'quaternion: need one per time ({t.size}), got {q.shape[0]}')
    mesh = lightcurve_mesh(scenario, settings) if mesh is None else mesh
    geometry = observer_geometry(scenario, t, settings)
    b = brightness(q, geometry.sun, geometry.observer, mesh, settings.law)
    m = magnitude(b, reference_brightness(mesh, settings.law), geometry.sun_distance,
                  geometry.observer_distance)
    delay = (geometry.observer_distance * KM_PER_AU / SPEED_OF_LIGHT if settings.light_time
             else np.zeros(t.size))
    stamped = t + delay / SECONDS_PER_YEAR
    return LightcurveRecord(stamped, delay, b, m, phase_angle(geometry.sun, geometry.observer),
                            aspect_angles(q, geometry.sun), aspect_angles(q, geometry.observer))

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
from typing import TYPE_CHECKING

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.lightcurve_settings import LightcurveSettings
from tumble_ros.core.model.mass_models import Ellipsoid, Polyhedron
from tumble_ros.core.model.shape import body_shape
from tumble_ros.core.photometry.brightness import (brightness_in_body, latitude_longitude,
                                                   magnitude, phase_angle,
                                                   reference_brightness, to_body)
from tumble_ros.core.photometry.shape import body_mesh, convex_mesh, ellipsoid_mesh, Mesh
from tumble_ros.core.torques.gravity_gradient import sun_direction_orbital
from tumble_ros.core.torques.orbits import perturber_radius, SPEED_OF_LIGHT
from tumble_ros.core.units import KM_PER_AU, SECONDS_PER_YEAR

if TYPE_CHECKING:
    from tumble_ros.core.model.scenario import Scenario

__all__ = ['ObserverGeometry', 'LightcurveRecord', 'observer_geometry', 'synthetic_lightcurve',
           'lightcurve_mesh', 'LightcurveSampler', 'LightcurveSettings']


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

    ``t`` (n,) [yr]: the sample times, or the reception times t + delta / c with
    ``settings.light_time``; ``light_time`` (n,) [s] delta / c (either way); ``brightness``
    (n,) [mesh area units]; ``magnitude`` (n,) [mag]; ``phase_angle`` (n,) [rad];
    ``sun_aspect``, ``observer_aspect`` (n, 2) (latitude, longitude) [rad] in body axes
    (``brightness`` module docstring).
    """

    t: FloatArray
    light_time: FloatArray
    brightness: FloatArray
    magnitude: FloatArray
    phase_angle: FloatArray
    sun_aspect: FloatArray
    observer_aspect: FloatArray


def lightcurve_mesh(scenario: Scenario, settings: LightcurveSettings) -> Mesh:
    """
    Return the body's mesh, in its principal axes (the scenario's body frame).

    The mass model's shape where the scenario has one (``body.model``): a polyhedron's own
    facets (ValueError when it is not convex: its self-shadowing is not modelled), an
    ellipsoid's semi-axes meshed as :func:`~.shape.ellipsoid_mesh`; else the uniform ellipsoid
    of the principal moments (:func:`~.shape.body_mesh`; ValueError for unphysical moments).
    """
    model = scenario.body.mass_model
    if isinstance(model, Polyhedron):     # (its convexity known: checked once, by the model)
        if not model.convex:
            raise ValueError(f'body.shape_file: the polyhedron is not convex '
                             f'({model.convexity_defect}): no shadowing is modelled')
        return convex_mesh(model.vertices, model.facets, check_convex=False)
    if isinstance(model, Ellipsoid):
        return ellipsoid_mesh(model.semi_axes, settings.subdivisions)
    return body_mesh(scenario.inertia, settings.subdivisions)


def synthetic_lightcurve(scenario: Scenario, t: ArrayLike, quaternion: ArrayLike,
                         settings: LightcurveSettings | None = None,
                         mesh: Mesh | None = None) -> LightcurveRecord:
    """
    Return what the observer sees of the body at times ``t`` [yr] with attitudes ``quaternion``.

    ``quaternion`` (n, 4) body -> orbital, scalar first (``simulate(scenario).quaternion``);
    ``settings`` default the scenario's (``Scenario.lightcurve``); ``mesh`` default its
    (:func:`lightcurve_mesh`: pass it to reuse it across calls). ValueError for a body that
    breaks the triangle inequality.
    """
    settings = scenario.lightcurve if settings is None else settings
    t = np.atleast_1d(np.asarray(t, dtype=float))
    q = np.asarray(quaternion, dtype=float).reshape(-1, 4)
    if q.shape[0] != t.size:
        raise ValueError(f'quaternion: need one per time ({t.size}), got {q.shape[0]}')
    mesh = lightcurve_mesh(scenario, settings) if mesh is None else mesh
    geometry = observer_geometry(scenario, t, settings)
    # both directions turned in one call (a fixed cost per call: the live batches are small)
    n = t.size
    turned = to_body(np.concatenate([q, q]), np.concatenate([geometry.sun, geometry.observer]))
    sun, observer = turned[:n], turned[n:]
    b = brightness_in_body(sun, observer, mesh, settings.law)
    m = magnitude(b, reference_brightness(mesh, settings.law), geometry.sun_distance,
                  geometry.observer_distance)
    unobserved = ~settings.observed(t)          # between a campaign's nights: not seen
    b[unobserved] = np.nan
    m[unobserved] = np.nan
    delay = geometry.observer_distance * KM_PER_AU / SPEED_OF_LIGHT
    stamped = t + delay / SECONDS_PER_YEAR if settings.light_time else t.copy()
    return LightcurveRecord(stamped, delay, b, m, phase_angle(geometry.sun, geometry.observer),
                            latitude_longitude(sun), latitude_longitude(observer))


@dataclass(frozen=True)
class LightcurveSampler:
    """
    A run's lightcurve, batch by batch: :func:`synthetic_lightcurve` with the mesh built once.

    The run layer (``runs.session``) makes one per run with :meth:`of` and calls it on each
    block of samples, for the live simulator and the offline recording alike.
    """

    scenario: Scenario
    mesh: Mesh

    @classmethod
    def of(cls, scenario: Scenario) -> 'LightcurveSampler | None':
        """
        Return the sampler of ``scenario``; None when it has no lightcurve.

        None when ``lightcurve.enabled`` is false or the moments break the triangle inequality
        (no body has them). A non-convex polyhedron (its self-shadowing is not modelled) with
        ``lightcurve.enabled`` is refused by the Scenario itself, with the reason.
        """
        if not scenario.lightcurve.enabled or not body_shape(scenario.inertia).physical:
            return None
        return cls(scenario, lightcurve_mesh(scenario, scenario.lightcurve))

    def __call__(self, t: ArrayLike, quaternion: ArrayLike) -> LightcurveRecord:
        """Return the lightcurve at times ``t`` [yr] of attitudes ``quaternion`` (n, 4)."""
        return synthetic_lightcurve(self.scenario, t, quaternion, mesh=self.mesh)

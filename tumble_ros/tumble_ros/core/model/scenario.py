"""
Scenarios: everything that defines one simulation, validated once at the boundary.

A :class:`Scenario` is a frozen dataclass. Building one validates every field and raises
:class:`ScenarioError` (a ``ValueError``) whose message starts with the field's name,
e.g. ``"integrator.rtol: must be in [1e-14, 0.1), got 0.5"``. Code inside the core
trusts a Scenario.

The same scenario is described to ROS as flat parameters (``inertia``,
``integrator.method``, ``impacts.start``...): :meth:`Scenario.to_parameters` and
:meth:`Scenario.from_parameters` convert, and :func:`load_scenario` reads the ROS 2
``--params-file`` YAML files in ``config/``. One set of rules serves the Python API, the
YAML files and the nodes' parameters.

Units: time [yr], angles [rad], rates [rad/yr], inertia normalised, torque in
inertia-units * rad/yr^2.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
import math
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.integrators import INTEGRATORS
from tumble_ros.core.model.body import BODY_PARAMETER_DOCS, BodySpec
from tumble_ros.core.model.dynamics import ATTITUDE_MODELS
from tumble_ros.core.model.gravity_field import GravityField, MAX_DEGREE
from tumble_ros.core.model.lightcurve_settings import LIGHTCURVE_PARAMETER_DOCS, LightcurveSettings
from tumble_ros.core.model.limits import (MAX_ATOL, MAX_DURATION, MAX_IMPACTS, MAX_OMEGA,
                                          MAX_ORBIT_RATE, MAX_ROTATION, MAX_RTOL, MAX_SAMPLES,
                                          MAX_STEPS, MIN_ORBIT_RATE, MIN_RTOL, RESOLUTION_ULPS,
                                          ScenarioError, step_budget)
from tumble_ros.core.model.mass_models import DensityMoments
from tumble_ros.core.model.observables import (SPIN_DEFAULTS, spin_from_parameters,
                                               SPIN_PARAMETER_DOCS, SpinObservables)
from tumble_ros.core.model.params_file import check_params_file, parse_params_text
from tumble_ros.core.model.shipped import config_dir
from tumble_ros.core.model.timebase import MAX_STAMP_NS, SampleGrid, TimeBase
from tumble_ros.core.torques import orbital_to_body, TorqueComponent
from tumble_ros.core.torques.ephemeris import Ephemeris, read_ephemeris
from tumble_ros.core.torques.orbits import KeplerOrbit, perturber_position
from tumble_ros.core.torques.perturbers import check_name, Perturber
from tumble_ros.core.units import seconds_per_year_of, TIME_UNITS, to_years

__all__ = [
    'ScenarioError',
    'Impact',
    'IntegratorSettings',
    'Scenario',
    'IMPACT_FRAMES',
    'ENCOUNTER_TORQUE_FRACTION',
    'ImpactLimits',
    'PARAMETER_DOCS',
    'PERTURBER_DOCS',
    'PERTURBER_FIELDS',
    'PERTURBER_DEFAULTS',
    'ORBIT_PERTURBER',
    'perturber_parameter_names',
    'time_resolution',
    'load_scenario',
    'parse_scenario',
    'dump_scenario',
]

IMPACT_FRAMES = ('body', 'orbital')
#: A flyby's encounter window: where its tidal torque exceeds this fraction of the perigee value
#: (R < 21.5 r_p); outside, the motion is taken as torque-free (:attr:`Scenario.encounter_window`).
ENCOUNTER_TORQUE_FRACTION = 1e-4


#: Longest value quoted whole in an error message [characters]; a longer one is summarised.
_MAX_QUOTED = 120


def _quoted(value: Any) -> str:
    """Return ``repr(value)``, or for a long one its start and its length (one short line)."""
    if isinstance(value, (list, tuple)) and len(value) > 16:
        head = ', '.join(repr(v) for v in value[:3])
        return f'{type(value).__name__} of {len(value):,} entries [{head}, ...]'
    text = repr(value)
    return text if len(text) <= _MAX_QUOTED else text[:_MAX_QUOTED - 3] + '...'


def _fail(name: str, why: str, value: Any) -> None:
    raise ScenarioError(f'{name}: {why}, got {_quoted(value)}')


def _finite(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        _fail(name, 'must be a number', value)
    if isinstance(value, bool) or not math.isfinite(v):
        _fail(name, 'must be a finite number', value)
    return v


def _vector(name: str, value: Any, n: int = 3) -> tuple[float, ...]:
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__') or len(value) != n:
        _fail(name, f'must be a list of {n} numbers', value)
    return tuple(_finite(f'{name}[{k}]', v) for k, v in enumerate(value))


def _positive(name: str, value: Any) -> float:
    v = _finite(name, value)
    if v <= 0.0:
        _fail(name, 'must be > 0', value)
    return v


def _one_of(name: str, value: Any, allowed: Iterable[str]) -> str:
    if value not in allowed:
        _fail(name, f'must be one of {sorted(allowed)}', value)
    return str(value)


def _set(obj: object, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def time_resolution(t: float) -> float:
    """
    Return the shortest interval [yr] that float64 times resolve at time ``t``.

    RESOLUTION_ULPS ulp of max(|t|, 1): the integrators' collapse test counts a step from
    t = 0 against ulp(1).
    """
    return RESOLUTION_ULPS * math.ulp(max(abs(t), 1.0))


def _check_step(name: str, step: float, duration: float) -> None:
    """
    Check a fixed step (or an adaptive method's max_step).

    It must be one that float64 resolves at the end of the run and that covers ``duration`` in
    at most MAX_STEPS steps.
    """
    # 4x the resolution: the steps actually taken are span / ceil(span / step) >= step / 2,
    # and t_k = t0 + k h is itself rounded.
    shortest = 4.0 * time_resolution(duration)
    if step < shortest:
        _fail(name,
              f'must be >= {shortest:.3g} yr: shorter steps are below the float64 time resolution '
              f'at t = duration ({duration:g} yr)', step)
    if duration / step > MAX_STEPS:
        _fail(name, f'duration / step = {duration / step:.3g} steps exceeds {MAX_STEPS:.0e}: '
              f'use a step >= {duration / MAX_STEPS:.3g} yr', step)


@dataclass(frozen=True, slots=True)
class Impact:
    """
    A short torque pulse (paper Fig. 10): constant torque on [start, start + duration).

    Attributes
    ----------
    start : float
        Start time t1 [yr].
    duration : float
        Pulse length t2 - t1 [yr] (the paper: ~3e-7 yr).
    torque : (float, float, float)
        Torque components [inertia-units * rad/yr^2] in ``frame``.
    frame : str
        ``"body"``: fixed in the body's principal axes; ``"orbital"``: fixed in the orbital
        (inertial) frame X'Y'Z' and rotated into body axes as the body turns.

    """

    start: float
    duration: float
    torque: tuple[float, float, float]
    frame: str = 'body'

    def __post_init__(self) -> None:
        self.validate('impact')

    def validate(self, name: str) -> None:
        """Check and normalise the fields; ``name`` prefixes error messages."""
        if self._normal():
            return   # (valid and normalised already: a scenario validates each impact again)
        start = _finite(f'{name}.start', self.start)
        if start < 0.0:
            _fail(f'{name}.start', 'must be >= 0 (the scenario starts at t = 0)', self.start)
        _set(self, 'start', start)
        duration = _positive(f'{name}.duration', self.duration)
        # A pulse shorter than the time resolution at its end has start + duration == start
        # (or nearly): it would be applied as no pulse at all (delta w = 0) or with a wrong length.
        if duration < time_resolution(start + duration):
            _fail(f'{name}.duration',
                  f'must be >= {time_resolution(start + duration):.3g} yr, the float64 time '
                  f'resolution at t = {start + duration:g} yr (a shorter pulse is not resolved)',
                  self.duration)
        _set(self, 'duration', duration)
        _set(self, 'torque', _vector(f'{name}.torque', self.torque))
        _one_of(f'{name}.frame', self.frame, IMPACT_FRAMES)

    def _normal(self) -> bool:
        """
        Return whether the fields pass :meth:`validate` and are what it would set them to.

        Plain floats (no bool, no numpy scalar), a tuple of three, a frame of
        :data:`IMPACT_FRAMES` (a str): :meth:`validate` would change nothing. Its checks
        without building a message per field (~5 us an impact; a run may schedule 10^6).
        """
        start, duration, torque = self.start, self.duration, self.torque
        if not (type(start) is float and type(duration) is float and type(torque) is tuple
                and len(torque) == 3 and type(self.frame) is str and self.frame in IMPACT_FRAMES):
            return False
        x, y, z = torque
        return (type(x) is float and type(y) is float and type(z) is float
                and math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
                and math.isfinite(start) and start >= 0.0
                and math.isfinite(duration) and duration > 0.0
                and not duration < time_resolution(start + duration))

    @property
    def end(self) -> float:
        """End time t2 [yr] (exclusive)."""
        return self.start + self.duration


@dataclass(frozen=True)
class ImpactLimits:
    """
    Caps on impacts requested while a simulation runs (the simulator's service).

    Attributes
    ----------
    max_duration : float
        Longest accepted pulse [yr].
    max_impulse : float
        Largest accepted |M| * duration [inertia-units * rad/yr].

    """

    max_duration: float = 1e-3
    max_impulse: float = 1e3

    def __post_init__(self) -> None:
        _set(self, 'max_duration', _positive('max_impact_duration', self.max_duration))
        _set(self, 'max_impulse', _positive('max_impact_impulse', self.max_impulse))

    def check(self, impact: Impact, now: float, end: float) -> None:
        """
        Raise ScenarioError (naming the field) unless ``impact`` may be scheduled.

        ``now`` is the current simulated time and ``end`` the end of the run [yr].
        """
        if impact.duration > self.max_duration:
            _fail('duration', f'must be <= max_impact_duration = {self.max_duration:g} yr',
                  impact.duration)
        impulse = math.hypot(*impact.torque) * impact.duration
        if impulse > self.max_impulse:
            _fail('torque', f'|M| * duration = {impulse:.6g} exceeds max_impact_impulse = '
                            f'{self.max_impulse:g}', list(impact.torque))
        if impact.start < now:
            _fail('start', f'is in the past (the simulation is at t = {now!r} yr)', impact.start)
        if impact.end > end:
            _fail('start', f'the pulse would end at {impact.end!r} yr, after the end of the run '
                           f'({end!r} yr)', impact.start)


@dataclass(frozen=True)
class IntegratorSettings:
    """
    Which integrator, and how accurate.

    Attributes
    ----------
    method : str
        A key of ``integrators.INTEGRATORS``: rk4, rk45, dop853, radau, bdf, lsoda, adams
        (``METHODS``) or splitting, splitting4, splitting6 (``SPLITTING_METHODS``, attitude
        'quaternion' only: checked by :class:`Scenario`).
    rtol, atol : float
        Relative and absolute tolerances of adaptive methods.
    step : float
        Step [yr] of fixed-step methods (rk4, splitting*; shortened so that segment edges
        are hit).
    max_step : float
        Largest step [yr] an adaptive method may take; 0 = no limit.

    """

    method: str = 'dop853'
    rtol: float = 1e-10
    atol: float = 1e-12
    step: float = 1e-4
    max_step: float = 0.0

    def __post_init__(self) -> None:
        self.validate('integrator')

    def validate(self, name: str) -> None:
        """Check and normalise the fields; ``name`` prefixes error messages."""
        _one_of(f'{name}.method', self.method, INTEGRATORS)
        rtol = _finite(f'{name}.rtol', self.rtol)
        if not MIN_RTOL <= rtol < MAX_RTOL:
            _fail(f'{name}.rtol', f'must be in [{MIN_RTOL:g}, {MAX_RTOL:g})', self.rtol)
        _set(self, 'rtol', rtol)
        atol = _positive(f'{name}.atol', self.atol)
        if atol > MAX_ATOL:
            _fail(f'{name}.atol',
                  f"must be in (0, {MAX_ATOL:g}] (the attitude quaternion's components are <= 1)",
                  self.atol)
        _set(self, 'atol', atol)
        _set(self, 'step', _positive(f'{name}.step', self.step))
        max_step = _finite(f'{name}.max_step', self.max_step)
        if max_step < 0.0:
            _fail(f'{name}.max_step', 'must be >= 0 (0 = no limit)', self.max_step)
        _set(self, 'max_step', max_step)


@dataclass(frozen=True)
class Scenario:
    """
    One simulation: body, orbit, initial state, integrator, impacts and output grid.

    The default is the paper's Fig. 4 case (a = 0.5, theta0 = 0.1), a physically
    realisable body for which the paper's approximate solution works well.

    Attributes
    ----------
    inertia : (Ix, Iy, Iz)
        Principal moments of inertia, normalised; only their ratios matter.
    allow_unphysical_inertia : bool
        Accept moments that violate the triangle inequality (each moment <= the sum of
        the other two, true of every real mass distribution). The paper's Figs 3 and 6-10
        use a = (Iz - Ix)/Ix = 2 or 3 with Ix = Iy, which no real body has; their config
        files set this flag to reproduce them.
    orbit_rate : float
        Orbital angular rate ws [rad/yr] of the circular orbit (GM/R0^3 = ws^2); 0
        switches the gravity-gradient torque off (a free body).
    omega0 : (wx0, wy0, wz0)
        Initial angular velocity [rad/yr], body axes.
    euler0 : (phi0, psi0, theta0)
        Initial attitude as the paper's Euler angles [rad] (z-x-z, orbital -> body).
        The paper gives no psi0; its figures use psi0 = 0.
    attitude : str
        How the attitude is integrated: ``"quaternion"`` (default, no singularity) or
        ``"euler"`` (the paper's eq 15, singular at theta = 0, pi).
    duration : float
        Simulated time span tk [yr], starting at t = 0. Within 4 ulp of the time of a stamp of
        :attr:`timebase` (a duration in days or hours converted to years), it is that time: the
        output grid's last sample is at the end of the run.
    output_interval : float
        Spacing of output samples [yr] (the paper: tk / n with n = 1000); at least 1e-9 yr,
        rounded to whole nanoseconds of ROS time (:attr:`output_times`).
    integrator : IntegratorSettings
    impacts : tuple of Impact
    orbit : KeplerOrbit or None
        The torquing body's Kepler orbit (``core.torques.orbits``; elliptic or a hyperbolic
        flyby); None: the circular orbit of ``orbit_rate`` (the paper's). With an orbit,
        ``orbit_rate`` must be 0 (the orbit gives the tidal torque).
    torques : tuple of TorqueComponent
        Extra torques added to the gravity gradient and the impacts, on the whole run
        (``core.torques``: defined outside core, run by every integrator). Python API only:
        they are functions, so they are not ROS parameters (:meth:`to_parameters` leaves them
        out).
    perturbers : tuple of Perturber
        More torquing bodies (``core.torques.perturbers``: the Earth, the Moon, the Sun...),
        each from a Kepler orbit or a tabulated ephemeris, optionally with its J2; each is a
        torque component. ``orbit``, when given, is the first perturber (:attr:`all_perturbers`,
        named ``kepler_orbit``). With perturbers, ``orbit_rate`` must be 0.
    gravity_degree : int
        Degree N of every perturber's gravitational torque (ROS ``gravity.degree``): 2 (default)
        the quadrupole of the inertia (``gravity_gradient.point_mass_torque``); 3 to the
        field's degree, the body's ``gravity_field`` to degree N (:mod:`~.torques.multipole`,
        through ``perturbers.perturber_torque``). Above 2 it needs a perturber and
        ``gravity_field``.
    gravity_field : GravityField or None
        The body's field (``core.model.gravity_field``): its principal moments must be
        proportional to ``inertia`` (same axes) to 1e-9 relative; they do not set it. Python API
        only for now (:meth:`to_parameters` leaves it out).
    body : BodySpec
        The mass model (ROS ``body.*``; docs/physics.md, "Mass models"): ``body.model``
        ``inertia`` (default: ``inertia`` is the body) or ``ellipsoid``, ``polyhedron``,
        ``moments``. With a mass model, ``inertia`` is derived from it (principal moments over
        the largest): an ``inertia`` left at its default is replaced, another one must agree
        to 1e-9 relative; ``gravity_field``, when None (or of a lower degree) and
        ``gravity_degree`` > 2, is the model's to that degree.
    lightcurve : LightcurveSettings
        What the synthetic lightcurve assumes (``core.photometry``; the ``lightcurve.*``
        parameters): the scattering law, the observer, light time.
    time_unit : str
        The scenario's own time unit (a key of ``units.TIME_UNITS``: yr, d, h, min, s; ROS
        ``time_unit``). The fields stay in years; the unit sets the output grid's time base, one
        ROS second per unit (:attr:`timebase`, the sim node's default), and the unit every
        printed time, rate and period is given in.

    """

    inertia: tuple[float, float, float] = (1.0, 1.0, 1.5)
    allow_unphysical_inertia: bool = False
    orbit_rate: float = 1.0
    omega0: tuple[float, float, float] = (0.0, 1.0, 30.0)
    euler0: tuple[float, float, float] = (0.5, 0.0, 0.1)
    attitude: str = 'quaternion'
    duration: float = 2.0
    output_interval: float = 0.002
    integrator: IntegratorSettings = field(default_factory=IntegratorSettings)
    impacts: tuple[Impact, ...] = ()
    torques: tuple[TorqueComponent, ...] = ()
    orbit: KeplerOrbit | None = None
    perturbers: tuple[Perturber, ...] = ()
    gravity_degree: int = 2
    gravity_field: GravityField | None = None
    body: BodySpec = field(default_factory=BodySpec)
    lightcurve: LightcurveSettings = field(default_factory=LightcurveSettings)
    time_unit: str = 'yr'

    def __post_init__(self) -> None:
        _one_of('time_unit', self.time_unit, TIME_UNITS)
        self._apply_body()
        inertia = _vector('inertia', self.inertia)
        for k, v in enumerate(inertia):
            if v <= 0.0:
                _fail(f'inertia[{k}]', 'must be > 0', v)
        if not isinstance(self.allow_unphysical_inertia, bool):
            _fail('allow_unphysical_inertia', 'must be true or false',
                  self.allow_unphysical_inertia)
        if not self.allow_unphysical_inertia:
            for k in range(3):
                others = sum(inertia) - inertia[k]
                if inertia[k] > others * (1.0 + 1e-12):
                    _fail(
                        'inertia',
                        f'is not physically realisable: inertia[{k}] = {inertia[k]:g} exceeds the '
                        f'sum of the other two ({others:g}); set allow_unphysical_inertia: true '
                        "to simulate such a body anyway (as the paper's figures with a > 1 do)",
                        list(inertia),
                    )
        _set(self, 'inertia', inertia)
        orbit_rate = _finite('orbit_rate', self.orbit_rate)
        if orbit_rate != 0.0 and not MIN_ORBIT_RATE <= orbit_rate <= MAX_ORBIT_RATE:
            _fail('orbit_rate',
                  f'must be 0 (no torque) or in [{MIN_ORBIT_RATE:g}, {MAX_ORBIT_RATE:g}] rad/yr '
                  '(real heliocentric orbits: ~2e-7 to ~2e4 rad/yr)', self.orbit_rate)
        _set(self, 'orbit_rate', orbit_rate)
        omega0 = _vector('omega0', self.omega0)
        if math.hypot(*omega0) > MAX_OMEGA:
            _fail('omega0',
                  f'|omega0| = {math.hypot(*omega0):.3g} rad/yr exceeds {MAX_OMEGA:g} rad/yr '
                  '(a spin period of 0.02 s; the fastest known asteroids take a few seconds)',
                  list(omega0))
        _set(self, 'omega0', omega0)
        euler0 = _vector('euler0', self.euler0)
        _one_of('attitude', self.attitude, ATTITUDE_MODELS)
        method = INTEGRATORS[self.integrator.method] if isinstance(self.integrator,
                                                                   IntegratorSettings) else None
        if method is not None and self.attitude not in method.attitudes:
            # Capability check: the method says what it can integrate, and why not the rest.
            _fail('integrator.method',
                  f'{method.name!r} cannot integrate attitude {self.attitude!r}: '
                  f"{method.requirement or 'unsupported'}", self.integrator.method)
        if self.attitude == 'euler' and not 0.0 < euler0[2] < math.pi:
            _fail('euler0[2]', "theta0 must lie strictly inside (0, pi) with attitude 'euler' "
                  "(eq 15 divides by sin theta); use attitude 'quaternion'", euler0[2])
        if ATTITUDE_MODELS[self.attitude].singular(euler0):
            _fail('euler0[2]', "theta0 is too close to 0 or pi for attitude 'euler'; "
                  "use attitude 'quaternion'", euler0[2])
        _set(self, 'euler0', euler0)
        duration = _positive('duration', self.duration)
        if duration > MAX_DURATION:
            _fail('duration',
                  f'must be <= {MAX_DURATION:g} yr (the model ignores orbital evolution and '
                  'YORP, which act over such times)', self.duration)
        _set(self, 'duration', _grid_end(duration, self.timebase))
        rotation = max(math.hypot(*self.omega0), self.orbit_rate) * duration
        if rotation > MAX_ROTATION:
            _fail('duration',
                  f'the body or its orbit turns by max(|omega0|, orbit_rate) * duration = '
                  f'{rotation:.3g} rad, above {MAX_ROTATION:.0e} rad: every method needs about a '
                  'step per radian', self.duration)
        _set(self, 'output_interval', _positive('output_interval', self.output_interval))
        if self.output_interval > self.duration:
            _fail('output_interval', f'must be <= duration ({self.duration:g} yr)',
                  self.output_interval)
        try:  # the grid must fit ROS stamps (at least 1 ns apart: 1e-9 yr at 1 s per year)
            self.timebase.check(self.output_interval, self.duration)
        except ScenarioError as err:
            raise ScenarioError(f'{err} (time_unit {self.time_unit}: one ROS second per '
                                f'{self.time_unit}; simulate(scenario, t_eval) samples any '
                                'times)') from None
        samples = self.duration / self.output_interval + 1.0
        if samples > MAX_SAMPLES:
            _fail('output_interval',
                  f'duration / output_interval + 1 = {samples:.3g} samples exceeds '
                  f'{MAX_SAMPLES:.0e}: use an output_interval >= '
                  f'{self.duration / (MAX_SAMPLES - 1):.3g} yr',
                  self.output_interval)
        if not isinstance(self.integrator, IntegratorSettings):
            _fail('integrator', 'must be an IntegratorSettings', self.integrator)
        if method.adaptive:
            if self.integrator.max_step > 0.0:
                _check_step('integrator.max_step', self.integrator.max_step, duration)
        else:
            _check_step('integrator.step', self.integrator.step, duration)
        impacts = tuple(self.impacts)
        if len(impacts) > MAX_IMPACTS:
            _fail('impacts', f'at most {MAX_IMPACTS:,} scheduled impacts per run (MAX_IMPACTS, '
                  'docs/ros.md "Limits of the inputs")', impacts)
        for k, impact in enumerate(impacts):
            if not isinstance(impact, Impact):
                _fail(f'impacts[{k}]', 'must be an Impact', impact)
            impact.validate(f'impacts[{k}]')
            if impact.end > self.duration:
                _fail(f'impacts[{k}].start',
                      f'the pulse must end by the end of the run ({self.duration:g} yr); '
                      f'it ends at {impact.end!r}', impact.start)
        _set(self, 'impacts', impacts)
        torques = tuple(self.torques)
        for k, torque in enumerate(torques):
            if not isinstance(torque, TorqueComponent):
                _fail(f'torques[{k}]', 'must be a core.torques.TorqueComponent', torque)
        _set(self, 'torques', torques)
        if self.orbit is not None:
            if not isinstance(self.orbit, KeplerOrbit):
                _fail('orbit', 'must be a core.torques.orbits.KeplerOrbit or None', self.orbit)
            if self.orbit_rate != 0.0:
                _fail('orbit_rate', 'must be 0 with a Kepler orbit (orbit.kind kepler or flyby): '
                      'the orbit gives the tidal torque', self.orbit_rate)
        _set(self, 'perturbers', _checked_perturbers(self))
        self._check_gravity()
        self._check_lightcurve()
        _check_clearance(self)

    def _check_lightcurve(self) -> None:
        """Refuse a lightcurve of a non-convex polyhedron: its shadows are not modelled."""
        model = self.body.mass_model
        defect = getattr(model, 'convexity_defect', None)
        if self.lightcurve.enabled and defect is not None:
            _fail('lightcurve.enabled',
                  f'the polyhedron of body.shape_file {self.body.shape_file} is not convex '
                  f'({defect}): the lightcurve sums the lit visible facets without shadowing, '
                  'exact for a convex body only; set lightcurve.enabled: false to simulate it '
                  'without a lightcurve', self.lightcurve.enabled)

    def _apply_body(self) -> None:
        """Derive ``inertia`` (and ``gravity_field``) from the mass model ``body``."""
        if not isinstance(self.body, BodySpec):
            _fail('body', 'must be a core.model.body.BodySpec', self.body)
        derived = self.body.inertia
        if derived is None:
            return
        if tuple(self.inertia) != Scenario.__dataclass_fields__['inertia'].default:
            _check_body_inertia(self.inertia, self.body)
        _set(self, 'inertia', derived)
        degree = self.gravity_degree
        held = self.gravity_field
        if isinstance(degree, int) and 2 < degree <= MAX_DEGREE and (
                held is None or (isinstance(held, GravityField) and held.degree < degree)):
            _set(self, 'gravity_field', self.body.gravity_field(degree))

    def _check_gravity(self) -> None:
        """Validate ``gravity_degree`` (``gravity.degree``) and ``gravity_field``."""
        degree, body = self.gravity_degree, self.gravity_field
        if isinstance(degree, bool) or not isinstance(degree, int) or not (
                2 <= degree <= MAX_DEGREE):
            _fail('gravity.degree', f'must be an integer in [2, {MAX_DEGREE}]', degree)
        if body is not None and not isinstance(body, GravityField):
            _fail('gravity_field', 'must be a core.model.gravity_field.GravityField or None', body)
        if degree > 2 and not self.all_perturbers:
            _fail('gravity.degree', 'above 2 needs a perturber (a Kepler orbit: orbit.kind '
                  'kepler or flyby; or perturbers)', degree)
        if degree > 2 and (body is None or degree > body.degree):
            _fail('gravity.degree', f"must be <= the gravity_field's degree "
                  f"({body.degree if body is not None else 'no gravity_field'})", degree)
        if body is not None:
            try:
                body.inertia_scale(self.inertia)
            except ValueError as err:
                raise ScenarioError(str(err)) from None
        if not isinstance(self.lightcurve, LightcurveSettings):
            _fail('lightcurve', 'must be a core.photometry.LightcurveSettings', self.lightcurve)

    # -- derived quantities ---------------------------------------------------------
    @property
    def encounter_window(self) -> tuple[float, float] | None:
        """
        Return (t_in, t_out) [yr]: when a flyby's tidal torque exceeds ENCOUNTER_TORQUE_FRACTION.

        The interval around perigee where the torque (~ 1/R^3) is above that fraction of its
        perigee value, i.e. R < r_p * fraction^(-1/3), not clipped to the run; None without
        a hyperbolic orbit (a circular or elliptic orbit torques all the time). Outside it the
        motion is torque-free to that fraction: the comparator's torque-free models anchor on
        each side (:mod:`.analytic`), and the integration is cut at its edges
        (:attr:`segment_cuts`) so the simulator describes the state there.
        """
        orbit = self.primary_orbit
        if orbit is None or orbit.e < 1.0:
            return None
        tau = orbit.time_from_pericentre(
            orbit.pericentre * ENCOUNTER_TORQUE_FRACTION ** (-1.0 / 3.0))
        return orbit.t_p - tau, orbit.t_p + tau

    @property
    def segment_cuts(self) -> tuple[float, ...]:
        """Return the times [yr] inside (0, duration) where the integration is cut: the window."""
        window = self.encounter_window
        if window is None:
            return ()
        return tuple(t for t in window if 0.0 < t < self.duration)

    @property
    def own_rate(self) -> float:
        """Return the scenario's own rate [rad/yr]: max(|omega0|, orbit_rate, orbits' n)."""
        return max([math.hypot(*self.omega0), self.orbit_rate]
                   + [p.mean_motion for p in self.all_perturbers])

    @property
    def step_budget(self) -> tuple[float, float]:
        """
        Return the work budget of an adaptive method: (window [yr], most steps within it).

        :func:`~.limits.step_budget` of the output interval, :attr:`own_rate` and the max_step:
        an adaptive run that takes more steps within less than one output_interval of simulated
        time stops (FAILED, the node's DIVERGED) saying so.
        """
        return step_budget(self.output_interval, self.own_rate, self.integrator.max_step)

    @property
    def all_perturbers(self) -> tuple[Perturber, ...]:
        """Return the torquing bodies: ``orbit`` first (``kepler_orbit``), then ``perturbers``."""
        orbit = (Perturber(ORBIT_PERTURBER, self.orbit),) if self.orbit is not None else ()
        return orbit + self.perturbers

    @property
    def primary_orbit(self) -> KeplerOrbit | None:
        """Return the first perturber's Kepler orbit (the flyby's), None if it has none."""
        bodies = self.all_perturbers
        source = bodies[0].source if bodies else None
        return source if isinstance(source, KeplerOrbit) else None

    @property
    def extra_torques(self) -> tuple[TorqueComponent, ...]:
        """
        Return the torques beyond the circular orbit's and the impacts': perturbers, torques.

        Each perturber's torque on the inertia's quadrupole, or with ``gravity_degree`` > 2 on
        the body's ``gravity_field`` to that degree.
        """
        field = (self.gravity_field.truncated(self.gravity_degree)
                 if self.gravity_degree > 2 and self.gravity_field is not None else None)
        return tuple(p.torque_component(self.inertia, field)
                     for p in self.all_perturbers) + self.torques

    def perturber_position(self, t: ArrayLike) -> FloatArray:
        """
        Return where the (first) torquing body is in the orbital frame, (n, 3) [km], at ``t`` [yr].

        The first of :attr:`all_perturbers`, or on the circular orbit the Sun at the distance the
        orbit rate gives (:func:`~.torques.orbits.perturber_position`).
        """
        bodies = self.all_perturbers
        if bodies:
            return bodies[0].position(t)
        return perturber_position(self.orbit_rate, None, t)

    def perturber_positions(self, t: ArrayLike) -> dict[str, FloatArray]:
        """Return where each perturber is, orbital frame: {name: (n, 3) [km]} at ``t`` [yr]."""
        return {p.name: p.position(t) for p in self.all_perturbers}

    def perturber_in_body(self, t: ArrayLike, quaternion: ArrayLike) -> FloatArray:
        """
        Return where the torquing body is in body axes, (n, 3) [km], at ``t`` [yr].

        ``quaternion``: (n, 4) attitudes (scalar first, body -> orbital) at those times. Its
        direction is the unit vector u of the tidal torque (paper eq 12), its norm the distance.
        """
        position = self.perturber_position(t)
        q = np.asarray(quaternion, dtype=float).reshape(-1, 4)
        body = python_source(orbital_to_body)(*position.T, *q.T)
        stacked: FloatArray = np.stack(body, axis=-1)
        return stacked

    @property
    def timebase(self) -> TimeBase:
        """Return the scenario's time base: one ROS second per ``time_unit``."""
        return TimeBase(seconds_per_year_of(self.time_unit))

    @property
    def output_grid(self) -> SampleGrid:
        """Return the output grid at the scenario's time base (:attr:`timebase`)."""
        return self.timebase.grid(self.output_interval, self.duration)

    @property
    def output_times(self) -> np.ndarray:
        """
        Return the output grid [yr]: every ``output_interval`` from 0 to ``duration`` included.

        The grid the sim node publishes at its default ``seconds_per_year`` (0: one ROS second
        per ``time_unit``), the offline recording writes and ``simulate(scenario)`` samples
        (:class:`~.timebase.SampleGrid` at :attr:`timebase`: the interval rounded to whole
        nanoseconds of ROS time, t_k = k interval_ns / ns_per_year), whatever the time unit.
        """
        return self.output_grid.times()

    def replace(self, **changes: Any) -> 'Scenario':
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    # -- flat parameters (ROS 2 parameters, YAML) ----------------------------------
    def to_parameters(self) -> dict[str, Any]:
        """Flat parameter dictionary as ROS 2 parameters (``integrator.rtol``, ...)."""
        params: dict[str, Any] = {
            'time_unit': self.time_unit,
            # the values below are in years (read back bit for bit; a unit's would be rounded)
            'values_in_years': self.time_unit != 'yr',
            'inertia': list(self.inertia),
            'allow_unphysical_inertia': self.allow_unphysical_inertia,
            'orbit_rate': self.orbit_rate,
            'omega0': list(self.omega0),
            'euler0': list(self.euler0),
            'attitude': self.attitude,
            'duration': self.duration,
            'output_interval': self.output_interval,
        }
        for f in dataclasses.fields(IntegratorSettings):
            params[f'integrator.{f.name}'] = getattr(self.integrator, f.name)
        params['impacts.start'] = [i.start for i in self.impacts]
        params['impacts.duration'] = [i.duration for i in self.impacts]
        params['impacts.torque'] = [c for i in self.impacts for c in i.torque]
        params['impacts.frame'] = [i.frame for i in self.impacts]
        orbit = self.orbit if self.orbit is not None else _DEFAULT_ORBIT
        params['orbit.kind'] = 'kepler' if self.orbit is not None else 'circular'
        for name in _ORBIT_FIELDS:
            params[f'orbit.{name}'] = getattr(orbit, name)
        params.update(dict.fromkeys((f'orbit.{name}' for name in _FLYBY_FIELDS), 0.0))
        params.update(_perturber_parameters(self.perturbers))
        params['gravity.degree'] = self.gravity_degree
        params.update(self.body.to_parameters())
        params.update(self.lightcurve.to_parameters())
        params.update(SPIN_DEFAULTS)   # (the spin.* block is converted when read: omega0, euler0)
        return params

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any],
                        params_file: str | Path | None = None) -> 'Scenario':
        """
        Build from a flat parameter mapping; missing keys take their defaults.

        ``params_file``: the file the parameters come from, if any (``body.shape_file`` and the
        perturbers' ``ephemeris_file`` may be relative to it). Raises ScenarioError for unknown
        keys and invalid values, and for an ``inertia`` given beside a mass model that disagrees
        with it. A ``spin.*`` block (the spin state as the literature gives it:
        :mod:`~.observables`) gives ``inertia``, ``omega0`` and ``euler0``, converted here once.
        """
        known = set(PARAMETER_NAMES) | set(perturber_parameter_names(params))
        unknown = sorted(set(params) - known)
        if unknown:
            raise ScenarioError(
                f"{unknown[0]}: unknown scenario parameter (known: {', '.join(sorted(known))})")
        time_unit = _one_of('time_unit', params.get('time_unit', 'yr'), TIME_UNITS)
        in_years = params.get('values_in_years', False)
        if not isinstance(in_years, bool):
            _fail('values_in_years', 'must be true or false', in_years)
        unit = 'yr' if in_years else time_unit   # the unit of the values
        perturbers = _perturbers_from_parameters(
            params, unit, Path(params_file).parent if params_file is not None else None)
        given, params = params, to_years(params, unit)
        plain = {k: params[k] for k in _SCENARIO_PLAIN if k in params}
        integ = {
            k.split('.', 1)[1]: params[k] for k in params if k.startswith('integrator.')
        }
        plain['integrator'] = IntegratorSettings(**integ)
        plain['impacts'] = _impacts_from_parameters(params)
        plain['orbit'] = _orbit_from_parameters(params)
        plain['perturbers'] = perturbers
        plain['gravity_degree'] = params.get('gravity.degree', 2)
        plain['body'] = body = BodySpec.from_parameters(params, params_file)
        stated = params.get('inertia')
        if body.inertia is not None and stated is not None and tuple(
                float(v) for v in stated) != Scenario.__dataclass_fields__['inertia'].default:
            # (the default counts as not given, as in the dataclass: a node holds every declared
            # parameter, so the simulator's parameters always carry an inertia)
            _check_body_inertia(stated, body)
        plain['lightcurve'] = LightcurveSettings.from_parameters(params)
        spin = spin_from_parameters(params)
        if spin is not None:
            plain.update(_spin_fields(spin, given, body))
        plain['time_unit'] = time_unit
        return cls(**plain)


def _grid_end(duration: float, timebase: TimeBase) -> float:
    """
    Return ``duration`` [yr], or the time of its stamp when only float rounding separates them.

    A duration stated in a unit (``1190 d`` * years per day) can come out an ulp or two off the
    time of its own stamp (1190 s of ROS time / 365.25 s per year): a grid sample at that stamp
    would then lie past the end and be dropped, or an ulp before it. Within 4 ulp, the duration
    is the stamp's time, so the last sample is at the end of the run; a duration between two
    stamps is kept as given.
    """
    if not duration * timebase.ns_per_year <= MAX_STAMP_NS:
        return duration   # (refused by the grid's check, naming the field)
    end = timebase.to_years(timebase.to_ns(duration))
    return end if abs(end - duration) <= 4.0 * math.ulp(duration) else duration


def _check_body_inertia(inertia: Any, body: BodySpec) -> None:
    """Refuse an ``inertia`` not proportional (1e-9) to the mass model's principal moments."""
    derived = body.inertia
    assert derived is not None
    given = _vector('inertia', inertia)
    top = max(given)
    if top <= 0.0 or any(abs(g / top - d) > 1e-9 for g, d in zip(given, derived)):
        _fail('inertia', f'disagrees with the mass model (body.model {body.model}), whose '
              f'normalised principal moments are {list(derived)}: give one or the other (a '
              'body and its inertia cannot disagree)', inertia)


def _spin_fields(spin: SpinObservables, params: Mapping[str, Any],
                 body: BodySpec) -> dict[str, Any]:
    """
    Return the inertia, omega0 and euler0 of the ``spin.*`` block, refusing a second statement.

    omega0 and euler0 must be left out (or at their defaults, as ``params`` states them before
    any time_unit conversion: a node holds every declared parameter); a stated inertia, or a
    mass model's, must have the block's ratios.
    """
    defaults = Scenario.__dataclass_fields__
    for name in ('omega0', 'euler0'):
        if name in params and _vector(name, params[name]) != defaults[name].default:
            _fail(name, f'give the spin state once: omega0 and euler0, or the spin.* block '
                  f'(spin.mode {spin.mode})', params[name])
    inertia: tuple[float, ...] | None = body.inertia
    stated = params.get('inertia')
    if inertia is None and stated is not None and _vector('inertia', stated) != \
            defaults['inertia'].default:
        inertia = _vector('inertia', stated)
    return spin.scenario_fields(inertia)


_SCENARIO_PLAIN = (
    'inertia', 'allow_unphysical_inertia', 'orbit_rate', 'omega0', 'euler0', 'attitude',
    'duration', 'output_interval',
)
_IMPACT_KEYS = ('impacts.start', 'impacts.duration', 'impacts.torque', 'impacts.frame')
#: The fields of a Kepler orbit (orbit.kind kepler), and what a flyby states instead of a, e.
_ORBIT_FIELDS = ('gm', 'a', 'e', 't_p', 'lambda_p', 'inclination', 'node', 'radius')
_FLYBY_FIELDS = ('perigee', 'v_inf', 'v_perigee')
_ORBIT_KINDS = ('circular', 'kepler', 'flyby')
#: The orbit.* values of a scenario without a Kepler orbit (orbit.kind circular).
_DEFAULT_ORBIT = KeplerOrbit(gm=1.0, a=1.0)
PARAMETER_NAMES: tuple[str, ...] = (
    ('time_unit', 'values_in_years') + _SCENARIO_PLAIN
    + tuple(f'integrator.{f.name}' for f in dataclasses.fields(IntegratorSettings))
    + _IMPACT_KEYS
    + ('orbit.kind',) + tuple(f'orbit.{name}' for name in _ORBIT_FIELDS + _FLYBY_FIELDS)
    + ('perturbers.names',)
    + ('gravity.degree',)
    + tuple(BODY_PARAMETER_DOCS)
    + tuple(LIGHTCURVE_PARAMETER_DOCS)
    + tuple(SPIN_PARAMETER_DOCS)
)


def _orbit_from_parameters(params: Mapping[str, Any], prefix: str = 'orbit',
                           kinds: tuple[str, ...] = _ORBIT_KINDS,
                           kind: str | None = None) -> KeplerOrbit | None:
    """
    Return the Kepler orbit of ``<prefix>.*`` (None for orbit.kind circular, the default).

    ``flyby`` states the hyperbola by its perigee and speed (:meth:`KeplerOrbit.flyby`) instead
    of a and e; the scenario keeps the resulting Kepler orbit (it is written back as ``kepler``).
    """
    if kind is None:
        kind = _one_of(f'{prefix}.kind', params.get(f'{prefix}.kind', 'circular'), kinds)
    values = {name: params.get(f'{prefix}.{name}', getattr(_DEFAULT_ORBIT, name))
              for name in _ORBIT_FIELDS}
    flyby = {name: params.get(f'{prefix}.{name}', 0.0) for name in _FLYBY_FIELDS}
    unused = {'circular': {**values, **flyby}, 'kepler': flyby,
              'flyby': {name: values[name] for name in ('a', 'e')}}[kind]
    defaults = {**{n: getattr(_DEFAULT_ORBIT, n) for n in _ORBIT_FIELDS},
                **dict.fromkeys(_FLYBY_FIELDS, 0.0)}
    for name, value in unused.items():
        if value != defaults[name]:
            used_by = 'flyby' if name in _FLYBY_FIELDS else (
                'kepler' if name in ('a', 'e') else 'kepler and flyby')
            _fail(f'{prefix}.{name}', f'is used only with {prefix}.kind: {used_by}', value)
    if kind == 'circular':
        return None
    try:
        if kind == 'kepler':
            return KeplerOrbit(**values)
        shared = {n: values[n] for n in ('t_p', 'lambda_p', 'inclination', 'node', 'radius')}
        return KeplerOrbit.flyby(values['gm'], flyby['perigee'], v_inf=flyby['v_inf'],
                                 v_perigee=flyby['v_perigee'], **shared)
    except ValueError as err:
        raise ScenarioError(str(err).replace('orbit.', f'{prefix}.')) from None


#: Unit and meaning of every scenario parameter (the nodes' descriptors, the README tables).
PARAMETER_DOCS: dict[str, tuple[str, str]] = {
    'time_unit': ('', "the scenario's time unit: yr (default), d, h, min or s; the unit of every "
                  'time, rate and torque below (converted to years once, when the scenario is '
                  'read: core/units.py), of the output grid (one ROS second per unit) and '
                  'of every printed time, rate and period'),
    'values_in_years': ('', 'true: the times, rates and torques below are in years whatever '
                        'time_unit says (a written scenario: to_parameters, the scenario '
                        'topic, so that it reads back bit for bit)'),
    'inertia': ('normalised', 'principal moments of inertia (Ix, Iy, Iz); only ratios matter'),
    'allow_unphysical_inertia': (
        '', 'accept moments that break the triangle inequality (paper Figs 3, 6-10)'),
    'orbit_rate': (
        'rad/yr',
        'orbital rate ws of the circular orbit, GM/R0^3 = ws^2; 0 = no torque, else 1e-9 to 1e6'),
    'omega0': ('rad/yr', 'initial angular velocity (wx, wy, wz), body axes; |omega0| <= 1e10'),
    'euler0': ('rad', "initial attitude as the paper's Euler angles (phi, psi, theta)"),
    'attitude': ('', 'attitude state: quaternion (no singularity) or euler (paper eq 15)'),
    'duration': (
        'yr',
        'simulated time span tk, from t = 0; <= 1e9, max(|omega0|, orbit_rate) * duration '
        '<= 1e10 rad'),
    'output_interval': (
        'yr', 'spacing of published samples; at most 1e7 samples, at least 1 ns of ROS time'),
    'integrator.method': ('', 'integrator: ' + ', '.join(INTEGRATORS)),
    'integrator.rtol': ('', 'relative tolerance (adaptive methods)'),
    'integrator.atol': ('', 'absolute tolerance (adaptive methods), in (0, 0.1]'),
    'integrator.step': (
        'yr',
        'step of fixed-step methods (rk4, splitting*); at most 1e10 steps, above the float64 '
        'resolution'),
    'integrator.max_step': (
        'yr', 'largest step of adaptive methods; 0 = no limit, else as integrator.step'),
    'impacts.start': ('yr', 'start time of each scheduled impact'),
    'impacts.duration': ('yr', 'length of each impact pulse; >= 16 ulp of its end time'),
    'impacts.torque': ('I rad/yr^2', 'torque of each impact, 3 numbers per impact, flattened'),
    'impacts.frame': ('', "frame of each impact's torque: body or orbital (empty = all body)"),
    'orbit.kind': ('', 'circular (orbit_rate, the paper), kepler (the elements gm, a, e, ...) or '
                   'flyby (gm, perigee, v_inf or v_perigee, ...); with kepler or flyby, '
                   'orbit_rate must be 0'),
    'orbit.gm': ('km^3/s^2', "the torquing body's GM (Sun 1.3271244e11, Earth 398600.4418)"),
    'orbit.a': ('km', 'semi-major axis, > 0 (|a| of a hyperbola) (kepler)'),
    'orbit.e': ('', 'eccentricity: 0 to 0.99 (ellipse) or >= 1.000001 (hyperbola) (kepler)'),
    'orbit.t_p': ('yr', 'time of pericentre (kepler, flyby)'),
    'orbit.lambda_p': ('rad', "direction of pericentre in the orbit plane, clockwise from +Y' "
                       "about Z' (kepler, flyby)"),
    'orbit.inclination': ('rad', "tilt of the orbit plane about X' (kepler, flyby)"),
    'orbit.node': ('rad', "turn of the tilted orbit plane about Z' (kepler, flyby)"),
    'orbit.radius': ('km', "the perturber's radius, the pericentre must lie outside it; 0 = the "
                     "Sun's 695700, the Earth's 6378.137 or the Moon's 1737.4 when gm is theirs, "
                     'else a point mass (kepler, flyby)'),
    'orbit.perigee': ('km', 'closest distance of the flyby (flyby)'),
    'orbit.v_inf': ('km/s', 'hyperbolic excess speed; give it or v_perigee (flyby)'),
    'orbit.v_perigee': ('km/s', 'speed at perigee; give it or v_inf (flyby)'),
    'perturbers.names': ('', 'more torquing bodies (earth, moon, sun...), each described by '
                         'perturbers.<name>.*: docs/ros.md, "Perturbers"'),
    'gravity.degree': ('', "degree N of every perturber's gravitational torque: 2 (default) the "
                       "inertia's quadrupole; 3 to 30 the body's gravity field to degree N "
                       '(needs a perturber and the field)'),
    **BODY_PARAMETER_DOCS,
    **LIGHTCURVE_PARAMETER_DOCS,
    **SPIN_PARAMETER_DOCS,
}


# -- perturbers: the Scenario's checks and its perturbers.* parameters ---------------------------
#: The name of ``orbit``'s perturber (:attr:`Scenario.all_perturbers`).
ORBIT_PERTURBER = 'kepler_orbit'
PERTURBER_KINDS = ('kepler', 'flyby', 'ephemeris')
#: A perturber's parameters besides the orbit's (``perturbers.<name>.<field>``) and their
#: defaults; the orbit's are ``_ORBIT_FIELDS`` and ``_FLYBY_FIELDS``.
_PERTURBER_OWN = {'kind': '', 'ephemeris_file': '', 'epoch_jd': 0.0, 'ephemeris_time_unit': '',
                  'j2': 0.0, 'pole': [0.0, 0.0, 1.0]}
PERTURBER_FIELDS = tuple(_PERTURBER_OWN) + _ORBIT_FIELDS + _FLYBY_FIELDS
#: The default of every ``perturbers.<name>.<field>`` (the nodes declare them with these).
PERTURBER_DEFAULTS: dict[str, Any] = {**_PERTURBER_OWN,
                                      **{f: getattr(_DEFAULT_ORBIT, f) for f in _ORBIT_FIELDS},
                                      **dict.fromkeys(_FLYBY_FIELDS, 0.0)}
#: Where a relative ephemeris file is looked for after the params file's folder: the package's
#: scenario files (the source tree's ``config/``, or the pip install's: :mod:`.shipped`).
PACKAGE_CONFIG = config_dir()


def _checked_perturbers(scenario: Scenario) -> tuple[Perturber, ...]:
    """Return ``scenario.perturbers`` checked against the rest of the scenario."""
    perturbers = tuple(scenario.perturbers)
    names = [ORBIT_PERTURBER] if scenario.orbit is not None else []
    for k, body in enumerate(perturbers):
        if not isinstance(body, Perturber):
            _fail(f'perturbers[{k}]', 'must be a core.torques.perturbers.Perturber', body)
        if body.name in names:
            _fail('perturbers.names', f'must be distinct (and not {ORBIT_PERTURBER!r}, the '
                  "name of orbit's perturber)", [p.name for p in perturbers])
        names.append(body.name)
        source = body.source
        if isinstance(source, Ephemeris) and not (source.start <= 0.0
                                                  and scenario.duration <= source.end):
            _fail(f'perturbers.{body.name}.ephemeris_file',
                  f'the table must cover the run, [0, {scenario.duration:g}] yr; it covers '
                  f'[{source.start:.6g}, {source.end:.6g}] yr', source.source)
    if perturbers and scenario.orbit_rate != 0.0:
        _fail('orbit_rate', 'must be 0 with perturbers: they give the tidal torque',
              scenario.orbit_rate)
    return perturbers


#: The body.* parameter that sets the size of each mass model (named by the clearance check).
_SIZE_PARAMETER = {'ellipsoid': 'body.semi_axes', 'polyhedron': 'body.shape_file',
                   'moments': 'body.reference_radius'}


def _body_radius(scenario: Scenario) -> tuple[float, str]:
    """Return (the body's bounding radius [km], the field that sets it); (0, '') if no size."""
    model = scenario.body.mass_model
    if model is not None:
        radius = (model.field.reference_radius if isinstance(model, DensityMoments)
                  else model.radius)             # moments: the field's reference radius
        return float(radius), _SIZE_PARAMETER[model.kind]
    if scenario.gravity_field is not None:
        return float(scenario.gravity_field.reference_radius), 'gravity_field'
    return 0.0, ''


def _check_clearance(scenario: Scenario) -> None:
    """
    Refuse a perturber whose closest approach lies inside the body's bounding sphere.

    A mass model's bounding radius (an ellipsoid's longest semi-axis, a polyhedron's farthest
    vertex, a field's reference radius) against each perturber's pericentre or an ephemeris'
    closest approach: inside it the perturber would pass through the body, and the field's
    expansion (gravity.degree > 2) diverges.
    """
    radius, field = _body_radius(scenario)
    if radius <= 0.0:
        return
    for body in scenario.all_perturbers:
        source = body.source
        if isinstance(source, KeplerOrbit):
            closest, what = source.pericentre, 'its pericentre'
        else:
            closest, when = source.closest_approach()
            what = f'its ephemeris at t = {when:.6g} yr'
        if not closest > radius:
            _fail(field, f"the body's bounding radius {radius:.6g} km must lie inside the "
                  f'closest approach of perturber {body.name}, {closest:.6g} km ({what}): the '
                  'perturber would pass through the body',
                  getattr(scenario.body, field[5:]) if field.startswith('body.') else radius)


def perturber_parameter_names(params: Mapping[str, Any]) -> tuple[str, ...]:
    """Return the ``perturbers.<name>.<field>`` names of the perturbers ``params`` names."""
    names = params.get('perturbers.names', []) or []
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        _fail('perturbers.names', 'must be a list of names', names)
    if len(set(names)) != len(names):
        _fail('perturbers.names', 'must be distinct', names)
    for name in names:
        try:
            check_name(name)
        except ValueError as err:
            raise ScenarioError(str(err)) from None
    return tuple(f'perturbers.{n}.{f}' for n in names for f in PERTURBER_FIELDS)


def _ephemeris_path(field: str, value: Any, folder: Path | None) -> Path:
    """Return the ephemeris file: absolute, else in ``folder`` (or the cwd), else in config/."""
    if not isinstance(value, str) or not value:
        _fail(field, 'must name a file (a Horizons vector table or t, x, y, z)', value)
    path = Path(value).expanduser()
    places = [path] if path.is_absolute() else [(folder or Path.cwd()) / path,
                                                PACKAGE_CONFIG / path]
    for place in places:
        if place.is_file():
            return place
    _fail(field, 'no such file (looked in ' + ', '.join(str(p) for p in places) + ')', value)
    raise AssertionError  # (unreachable: _fail raises)


def _perturbers_from_parameters(params: Mapping[str, Any], unit: str,
                                folder: Path | None) -> tuple[Perturber, ...]:
    """Return the perturbers of ``perturbers.*`` (times in ``unit``, converted here)."""
    bodies = []
    for name in params.get('perturbers.names', []) or []:
        prefix = f'perturbers.{name}'
        get = {f: params.get(f'{prefix}.{f}', d) for f, d in _PERTURBER_OWN.items()}
        kind = _one_of(f'{prefix}.kind', get['kind'], PERTURBER_KINDS)
        if kind == 'ephemeris':
            for f in _ORBIT_FIELDS + _FLYBY_FIELDS:
                value = params.get(f'{prefix}.{f}')
                if f not in ('gm', 'radius') and value not in (None, 0.0,
                                                               getattr(_DEFAULT_ORBIT, f, 0.0)):
                    _fail(f'{prefix}.{f}', 'is used only with kind: kepler or flyby', value)
            time_unit = get['ephemeris_time_unit'] or unit
            _one_of(f'{prefix}.ephemeris_time_unit', time_unit, TIME_UNITS)
            path = _ephemeris_path(f'{prefix}.ephemeris_file', get['ephemeris_file'], folder)
            try:
                source: KeplerOrbit | Ephemeris = read_ephemeris(
                    path, epoch_jd=_finite(f'{prefix}.epoch_jd', get['epoch_jd']),
                    time_unit=time_unit)
            except ValueError as err:
                raise ScenarioError(f'{prefix}.ephemeris_file: {err}') from None
            gm, radius = params.get(f'{prefix}.gm', 0.0), params.get(f'{prefix}.radius', 0.0)
        else:
            for f in ('ephemeris_file', 'epoch_jd', 'ephemeris_time_unit'):
                if get[f] != _PERTURBER_OWN[f]:
                    _fail(f'{prefix}.{f}', 'is used only with kind: ephemeris', get[f])
            scaled = dict(params)
            if f'{prefix}.t_p' in scaled:
                scaled[f'{prefix}.t_p'] = _finite(f'{prefix}.t_p', scaled[f'{prefix}.t_p']) \
                    * TIME_UNITS[unit]
            orbit = _orbit_from_parameters(scaled, prefix, PERTURBER_KINDS, kind)
            assert orbit is not None  # (kepler and flyby give one)
            source, gm, radius = orbit, 0.0, orbit.radius
        try:
            bodies.append(Perturber(name, source, gm=gm, j2=get['j2'], radius=radius,
                                    pole=tuple(get['pole'])))
        except (TypeError, ValueError) as err:
            raise ScenarioError(str(err)) from None
    return tuple(bodies)


#: Unit and meaning of each ``perturbers.<name>.<field>`` (as PARAMETER_DOCS).
PERTURBER_DOCS: dict[str, tuple[str, str]] = {
    'kind': ('', 'kepler (elements gm, a, e, ... as orbit.*), flyby (gm, perigee, v_inf or '
             'v_perigee, ...) or ephemeris (ephemeris_file, gm)'),
    'ephemeris_file': ('', 'a JPL Horizons vector table or a plain t, x, y, z table: the '
                       "perturber's position relative to the asteroid [km], orbital frame; "
                       "relative paths: the params file's folder, then the package's config/"),
    'epoch_jd': ('d', 'Julian date (TDB) of t = 0, for a Horizons table'),
    'ephemeris_time_unit': ('', "unit of a plain table's t; '' = time_unit (yr with "
                            'values_in_years)'),
    'j2': ('', "the perturber's J2 (the Earth 1.0826e-3); 0 = a point mass"),
    'pole': ('', "the perturber's pole, orbital frame (its J2's axis)"),
    **{f: (unit, text.replace('(kepler)', '(kind kepler)').replace(
        '(kepler, flyby)', '(kind kepler, flyby)').replace('(flyby)', '(kind flyby)'))
       for f in _ORBIT_FIELDS + _FLYBY_FIELDS
       for unit, text in [PARAMETER_DOCS[f'orbit.{f}']]},
}


def _perturber_parameters(perturbers: Iterable[Perturber]) -> dict[str, Any]:
    """Return ``perturbers.*`` of ``perturbers`` (an ephemeris by its file, '' if it has none)."""
    params: dict[str, Any] = {'perturbers.names': [p.name for p in perturbers]}
    for body in perturbers:
        prefix = f'perturbers.{body.name}'
        source = body.source
        values: dict[str, Any] = {**_PERTURBER_OWN, 'j2': body.j2, 'pole': list(body.pole)}
        orbit = source if isinstance(source, KeplerOrbit) else _DEFAULT_ORBIT
        values.update({f: getattr(orbit, f) for f in _ORBIT_FIELDS})
        values.update(dict.fromkeys(_FLYBY_FIELDS, 0.0))
        if isinstance(source, Ephemeris):
            values.update(kind='ephemeris', gm=body.gm, radius=body.radius,
                          ephemeris_file=source.source, epoch_jd=source.epoch_jd,
                          ephemeris_time_unit=source.time_unit)
        else:
            values['kind'] = 'kepler'
        params.update({f'{prefix}.{f}': v for f, v in values.items()})
    return params


def _impacts_from_parameters(params: Mapping[str, Any]) -> tuple[Impact, ...]:
    start = list(params.get('impacts.start', []) or [])
    duration = list(params.get('impacts.duration', []) or [])
    torque = list(params.get('impacts.torque', []) or [])
    frame = list(params.get('impacts.frame', []) or [])
    n = len(start)
    if n > MAX_IMPACTS:
        _fail('impacts.start', f'at most {MAX_IMPACTS:,} scheduled impacts per run (MAX_IMPACTS, '
              'docs/ros.md "Limits of the inputs")', start)
    if len(duration) != n:
        _fail('impacts.duration', f'must have one entry per impacts.start ({n})', duration)
    if len(torque) != 3 * n:
        _fail('impacts.torque', f'must have 3 entries per impact ({3 * n})', torque)
    if not frame:
        frame = ['body'] * n
    if len(frame) != n:
        _fail('impacts.frame', f"must be empty (all 'body') or have one entry per impact ({n})",
              frame)
    impacts = []
    for k in range(n):
        try:
            impacts.append(Impact(start[k], duration[k], tuple(torque[3 * k: 3 * k + 3]),
                                  frame[k]))
        except ScenarioError as err:
            raise ScenarioError(str(err).replace('impact.', f'impacts[{k}].', 1)) from None
    return tuple(impacts)


def _flatten(mapping: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for key, value in mapping.items():
        name = f'{prefix}{key}'
        if isinstance(value, Mapping):
            flat.update(_flatten(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def load_scenario(path: str | Path, node: str = 'sim',
                  ignore: frozenset[str] = frozenset()) -> Scenario:
    """
    Read a scenario from a ROS 2 parameters YAML file (``--params-file`` format).

    The file is ``{node_name: {ros__parameters: {...}}}``; the section ``/**/<node>``, ``node`` or
    ``/<node>`` is used, else the wildcard ``/**``, else the only section. Nested keys are joined
    with dots as ROS does (``integrator: {rtol: 1e-10}`` is ``integrator.rtol``). Keys in
    ``ignore`` (a node's own, non-scenario parameters) are skipped.

    Raises ScenarioError for a file :func:`~.params_file.check_params_file` refuses (missing,
    not a regular file, too big, not UTF-8 YAML, no ``ros__parameters``), a missing section or
    invalid values.
    """
    document = check_params_file(path)
    try:
        return _scenario_from_document(document, node, ignore, path)
    except ScenarioError as err:
        raise ScenarioError(f'{path}: {err}') from None


def parse_scenario(text: str, node: str = 'sim', ignore: frozenset[str] = frozenset()) -> Scenario:
    """:func:`load_scenario` on the text of a parameters file."""
    return _scenario_from_document(parse_params_text(text), node, ignore)


def _scenario_from_document(document: Mapping[str, Any], node: str, ignore: frozenset[str],
                            path: str | Path | None = None) -> Scenario:
    """Return the scenario of the ``node`` section of a params file's checked document."""
    for key in (f'/**/{node}', node, f'/{node}', '/**'):
        if key in document:
            section = document[key]
            break
    else:
        if len(document) != 1:
            raise ScenarioError(f"no section for node {node!r} or '/**'")
        section = next(iter(document.values()))
    if not isinstance(section, Mapping) or not isinstance(section.get('ros__parameters'), Mapping):
        raise ScenarioError("the node section has no 'ros__parameters' mapping")
    params = {k: v for k, v in _flatten(section['ros__parameters']).items() if k not in ignore}
    return Scenario.from_parameters(params, path)


def dump_scenario(scenario: Scenario, node: str = 'sim') -> str:
    """
    Return the scenario as the text of a ROS 2 parameters file (inverse of :func:`parse_scenario`).

    Keyed ``/**/<node>``: the section applies to the node in any namespace (a plain ``sim:`` key
    means ``/sim`` only, and a namespaced simulator would silently run the defaults).
    """
    import yaml

    params = scenario.to_parameters()
    # The impacts' lists (60,000 scalars for 10,000 impacts, 0.45 s through PyYAML's Python
    # representer) are written by _block_sequence, in the text PyYAML gives (tested): dumped
    # empty, then the empty list's line replaced.
    lists = {key: params[key] for key in _IMPACT_LIST_KEYS if params[key]}
    if not all(isinstance(v, float) and math.isfinite(v) or v in IMPACT_FRAMES
               for values in lists.values() for v in values):
        lists = {}
    params.update({key: [] for key in lists})   # (one list each: a shared one is an alias)
    # libyaml's emitter when PyYAML has it: the same text, 3x faster
    dumper = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)
    text: str = yaml.dump({f'/**/{node}': {'ros__parameters': params}},
                          Dumper=dumper, sort_keys=False)
    for key, values in lists.items():
        text = text.replace(f'\n    {key}: []\n', f'\n    {key}:\n{_block_sequence(values)}', 1)
    return text


#: The parameters :func:`dump_scenario` writes without PyYAML's representer.
_IMPACT_LIST_KEYS = ('impacts.start', 'impacts.duration', 'impacts.torque', 'impacts.frame')


def _block_sequence(values: Sequence[float | str]) -> str:
    """
    Return the lines PyYAML's SafeDumper writes for a list of a ``ros__parameters`` key.

    Finite floats as its ``represent_float`` spells them (``repr``, with ``.0`` put before an
    exponent that has no decimal point: ``1.0e+17``); strings only plain words (the frames).
    """
    lines = []
    for v in values:
        if isinstance(v, str):
            lines.append(f'    - {v}\n')
            continue
        text = repr(v).lower()
        if '.' not in text and 'e' in text:
            text = text.replace('e', '.0e', 1)
        lines.append(f'    - {text}\n')
    return ''.join(lines)

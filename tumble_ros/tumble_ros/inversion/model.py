"""
The forward model of a tumbler's photometry: parameters -> magnitudes at a campaign's points.

A torque-free rigid tumbler with the spin state of the literature (``SpinObservables``: mode,
P_phi, P_psi, I1/I3, I2/I3, L's (lambda, beta), the phases (phi0, psi0) at the epoch, the sign
of theta0), a triaxial-ellipsoid shape (semi-axes (1, b/a, c/a) along the principal axes of
I1, I2, I3) or a fixed convex mesh, the scattering law S = S_LS + c S_L (Lommel-Seeliger plus
a Lambert term of weight c; Kaasalainen et al. 2001: c = 0.1) and a linear phase function
(``phase_slope`` [mag/rad] times the phase angle). Per lightcurve block an unknown magnitude
offset (the campaign's ``free_offset`` blocks each their own, the calibrated blocks one shared)
is solved linearly at every evaluation (weighted mean of the block's residuals), so it never
enters the nonlinear fit.

One code path with the runs: the state becomes a :class:`Scenario` (``scenario_fields``), the
attitude at the emission times comes from :func:`~tumble_ros.core.propagation.simulate.simulate`
(the compiled DOP853 loop), the brightness from ``core.photometry`` (``ellipsoid_mesh``,
``to_body``, the compiled ``scattering_sums``, ``reference_brightness``, ``magnitude``).

Frames and units: the scenario's orbital frame is the campaign's, ecliptic J2000, so (lambda,
beta) are ecliptic; t = 0 is the epoch ``epoch_jd`` [JD TDB] (default: the first emission
time); the emission time of a point is its ``jd_tdb`` minus the light time Delta / c unless the
campaign says it is corrected already. Parameter vector units: periods [h], angles [rad],
ratios [1], c [1], phase slope [mag/rad].
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Sequence

import numpy as np

from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.observables import SpinObservables
from tumble_ros.core.model.scenario import IntegratorSettings, Scenario
from tumble_ros.core.photometry.brightness import (magnitude, reference_brightness,
                                                   scattering_sums, to_body)
from tumble_ros.core.photometry.shape import ellipsoid_mesh, Mesh
from tumble_ros.core.propagation.simulate import simulate
from tumble_ros.core.torques.orbits import SPEED_OF_LIGHT
from tumble_ros.core.units import HOURS_PER_YEAR, KM_PER_AU
from tumble_ros.inversion.campaign import Campaign, CampaignError

__all__ = ['ModelOptions', 'TumblerParameters', 'ForwardModel', 'PARAMETER_UNITS',
           'SPIN_PARAMETERS', 'ModelError']

SECONDS_PER_DAY = 86400.0
DAYS_PER_YEAR = 365.25
#: Every parameter of the vector, in order, with its unit (the free ones are a subset).
PARAMETER_UNITS: dict[str, str] = {
    'precession_period': 'h', 'rotation_period': 'h', 'i1_i3': '', 'i2_i3': '',
    'pole_lambda': 'rad', 'pole_beta': 'rad', 'phi0': 'rad', 'psi0': 'rad',
    'axis_b_a': '', 'axis_c_a': '', 'lambert_weight': '', 'phase_slope': 'mag/rad'}
#: The spin parameters (always free unless named in ``ModelOptions.fixed``).
SPIN_PARAMETERS = tuple(list(PARAMETER_UNITS)[:8])
#: Bounds of the parameters that have them (others are unbounded: periods > 0 by the model).
_BOUNDS: dict[str, tuple[float, float]] = {
    'precession_period': (1e-3, np.inf), 'rotation_period': (1e-3, np.inf),
    'i1_i3': (0.02, 0.999), 'i2_i3': (0.02, 0.999), 'pole_beta': (-math.pi / 2, math.pi / 2),
    'axis_b_a': (0.1, 2.0), 'axis_c_a': (0.1, 2.0), 'lambert_weight': (0.0, 10.0)}


class ModelError(CampaignError):
    """A model that cannot be evaluated as asked (bad options or starting values)."""


@dataclass(frozen=True)
class ModelOptions:
    """
    What the model holds fixed and how finely it computes.

    ``mesh``: a fixed convex shape (body axes = the principal axes of I1, I2, I3); None: the
    triaxial ellipsoid (1, b/a, c/a), fitted, meshed with ``subdivisions`` (20 4^k facets).
    ``fit_lambert_weight``, ``fit_phase_slope``: free the law's Lambert weight c and the phase
    slope (default fixed at the start's: with a free offset per block the slope is only
    measured across blocks of different phase angles). ``fixed``: more parameter names held at
    the start's values. ``rtol``: the DOP853 tolerance of the propagation.
    """

    mesh: Mesh | None = None
    subdivisions: int = 3
    fit_lambert_weight: bool = False
    fit_phase_slope: bool = False
    fixed: tuple[str, ...] = ()
    rtol: float = 1e-10

    def __post_init__(self) -> None:
        unknown = [name for name in self.fixed if name not in PARAMETER_UNITS]
        if unknown:
            raise ModelError(f'fixed: unknown parameter {unknown[0]!r} (known: '
                             f"{', '.join(PARAMETER_UNITS)})")
        if not 0 <= self.subdivisions <= 5:
            raise ModelError(f'subdivisions: must be in [0, 5], got {self.subdivisions!r}')

    def free(self) -> tuple[str, ...]:
        """Return the names of the fitted parameters, in the vector's order."""
        held = set(self.fixed)
        if self.mesh is not None:
            held |= {'axis_b_a', 'axis_c_a'}
        if not self.fit_lambert_weight:
            held.add('lambert_weight')
        if not self.fit_phase_slope:
            held.add('phase_slope')
        return tuple(name for name in PARAMETER_UNITS if name not in held)


@dataclass(frozen=True)
class TumblerParameters:
    """
    One model: the spin state, the shape, the law, the phase function.

    ``spin``: the literature's state (periods in years there, ``SpinObservables``);
    ``axis_ratios`` (b/a, c/a) of the ellipsoid (ignored with a fixed mesh);
    ``lambert_weight`` c of S = S_LS + c S_L; ``phase_slope`` [mag/rad].
    """

    spin: SpinObservables
    axis_ratios: tuple[float, float] = (0.8, 0.6)
    lambert_weight: float = 0.1
    phase_slope: float = 0.0

    def vector(self) -> np.ndarray:
        """Return all parameters in :data:`PARAMETER_UNITS`' order and units."""
        s = self.spin
        return np.array([s.precession_period * HOURS_PER_YEAR, s.rotation_period * HOURS_PER_YEAR,
                         *s.inertia_ratios, *s.pole, *s.phases, *self.axis_ratios,
                         self.lambert_weight, self.phase_slope])

    @classmethod
    def from_vector(cls, values: Sequence[float] | np.ndarray, mode: str,
                    anti_aligned: bool) -> 'TumblerParameters':
        """Return the parameters of a full vector (ScenarioError for an impossible state)."""
        v = [float(x) for x in values]
        spin = SpinObservables(mode, v[0] / HOURS_PER_YEAR, v[1] / HOURS_PER_YEAR,
                               (v[2], v[3]), (v[4], v[5]), (v[6], v[7]), anti_aligned)
        return cls(spin, (v[8], v[9]), v[10], v[11])

    @classmethod
    def of(cls, mode: str, precession_period_h: float, rotation_period_h: float,
           inertia_ratios: tuple[float, float], pole: tuple[float, float],
           phases: tuple[float, float] = (0.0, 0.0), anti_aligned: bool = False,
           axis_ratios: tuple[float, float] = (0.8, 0.6), lambert_weight: float = 0.1,
           phase_slope: float = 0.0) -> 'TumblerParameters':
        """Return parameters from periods in hours (the literature's unit), angles [rad]."""
        spin = SpinObservables(mode, precession_period_h / HOURS_PER_YEAR,
                               rotation_period_h / HOURS_PER_YEAR, inertia_ratios, pole, phases,
                               anti_aligned)
        return cls(spin, axis_ratios, lambert_weight, phase_slope)

    def with_values(self, names: Sequence[str],
                    values: Sequence[float] | np.ndarray) -> 'TumblerParameters':
        """Return a copy with the named parameters set (ScenarioError if impossible)."""
        full = self.vector()
        index = list(PARAMETER_UNITS)
        for name, value in zip(names, values):
            full[index.index(name)] = value
        return TumblerParameters.from_vector(full, self.spin.mode, self.spin.anti_aligned)


def bounds(names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Return the (lower, upper) bounds of the named parameters."""
    pairs = [_BOUNDS.get(name, (-np.inf, np.inf)) for name in names]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


@dataclass
class ForwardModel:
    """
    The magnitudes a :class:`TumblerParameters` predicts at a campaign's points.

    Built once per campaign (emission times, unit vectors, distances, phase angles, offset
    groups); :meth:`magnitudes` is the model without offsets, :meth:`residuals` the weighted
    residuals with the offsets solved. ``epoch_jd`` [JD TDB]: t = 0 (at or before the first
    emission time).
    """

    campaign: Campaign
    options: ModelOptions = field(default_factory=ModelOptions)
    epoch_jd: float | None = None
    evaluations: int = 0

    def __post_init__(self) -> None:
        c = self.campaign
        r = np.linalg.norm(c.sun, axis=1)
        delta = np.linalg.norm(c.observer, axis=1)
        light_days = 0.0 if c.light_time_corrected else \
            delta * KM_PER_AU / SPEED_OF_LIGHT / SECONDS_PER_DAY
        emission = c.jd_tdb - light_days
        first = float(np.min(emission))
        if self.epoch_jd is None:
            self.epoch_jd = first
        if not math.isfinite(self.epoch_jd) or self.epoch_jd > first + 1e-9:
            raise ModelError(f'epoch_jd: must be at or before the first emission time '
                             f'{first:.6f}, got {self.epoch_jd!r}')
        self.t_years = np.maximum(emission - self.epoch_jd, 0.0) / DAYS_PER_YEAR
        self.order = np.argsort(self.t_years, kind='stable')
        self.sun_unit = c.sun / r[:, None]
        self.observer_unit = c.observer / delta[:, None]
        self.distance_term = 5.0 * np.log10(r * delta)
        self.phase = c.phase_angle()
        self.weights = 1.0 / c.sigma ** 2
        free = np.asarray(c.free_offset, dtype=bool)
        # offset groups: each free block its own, every calibrated block the shared one
        blocks = len(c.block_names)
        group_of_block = np.where(free, np.arange(blocks), blocks)
        _, self.group = np.unique(group_of_block[c.block], return_inverse=True)
        self.groups = int(self.group.max()) + 1
        self.group_weight = np.bincount(self.group, self.weights, self.groups)
        self._mesh_key: tuple[float, float] | None = None
        self._mesh: Mesh | None = None
        self._references = (1.0, 1.0)
        self._attitudes: tuple[SpinObservables, np.ndarray] | None = None

    # -- pieces ----------------------------------------------------------------------------
    def mesh(self, params: TumblerParameters) -> Mesh:
        """Return the mesh of the shape: the fixed one, or the ellipsoid's (cached)."""
        if self.options.mesh is not None:
            return self.options.mesh
        key = (float(params.axis_ratios[0]), float(params.axis_ratios[1]))
        if key != self._mesh_key:
            self._mesh = ellipsoid_mesh((1.0, *key), self.options.subdivisions)
            self._mesh_key = key
            self._references = (reference_brightness(self._mesh, 'lommel_seeliger'),
                                reference_brightness(self._mesh, 'lambert'))
        assert self._mesh is not None
        return self._mesh

    def references(self, params: TumblerParameters) -> tuple[float, float]:
        """Return B_ref of the Lommel-Seeliger and the Lambert law for the shape."""
        if self.options.mesh is not None and self._mesh_key is None:
            mesh = self.options.mesh
            self._references = (reference_brightness(mesh, 'lommel_seeliger'),
                                reference_brightness(mesh, 'lambert'))
            self._mesh_key = (math.nan, math.nan)
        self.mesh(params)
        return self._references

    def scenario(self, params: TumblerParameters) -> Scenario:
        """Return the torque-free scenario of the spin state, to the last emission time."""
        end = max(float(self.t_years.max()), 1e-9)
        return Scenario(**params.spin.scenario_fields(), orbit_rate=0.0, duration=end,
                        output_interval=end,
                        integrator=IntegratorSettings('dop853', self.options.rtol,
                                                      self.options.rtol * 1e-2))

    def quaternions(self, params: TumblerParameters) -> np.ndarray:
        """
        Return the attitudes (n, 4) body -> ecliptic at the emission times, point order.

        The last spin state's are kept: a change of the shape or the law alone reuses them.
        """
        if self._attitudes is not None and self._attitudes[0] == params.spin:
            return self._attitudes[1]           # (the shape's and the law's derivatives)
        times = self.t_years[self.order]
        run = simulate(self.scenario(params), times)
        if not run.success:
            raise ModelError(f'the propagation failed: {run.message}')
        q = np.empty_like(run.quaternion)
        q[self.order] = run.quaternion
        self._attitudes = (params.spin, q)
        return q

    # -- the model -------------------------------------------------------------------------
    def magnitudes(self, params: TumblerParameters) -> np.ndarray:
        """Return the model's magnitudes [mag], one a point, without the block offsets."""
        self.evaluations += 1
        q = self.quaternions(params)
        n = q.shape[0]
        turned = to_body(np.concatenate([q, q]),
                         np.concatenate([self.sun_unit, self.observer_unit]))
        sums = scattering_sums(turned[:n], turned[n:], self.mesh(params))
        c = params.lambert_weight
        ref_ls, ref_l = self.references(params)
        b = sums[:, 0] + c * sums[:, 1]
        with np.errstate(divide='ignore'):
            m = magnitude(np.maximum(b, 1e-300), ref_ls + c * ref_l)
        return m + self.distance_term + params.phase_slope * self.phase

    def offsets(self, model: np.ndarray) -> np.ndarray:
        """Return the weighted-mean offset of each group (data minus model) [mag]."""
        diff = self.campaign.magnitude - model
        return np.bincount(self.group, self.weights * diff, self.groups) / self.group_weight

    def fitted(self, params: TumblerParameters) -> np.ndarray:
        """Return the model's magnitudes with the solved offsets (n,) [mag]."""
        model = self.magnitudes(params)
        return model + self.offsets(model)[self.group]

    def residuals(self, params: TumblerParameters) -> np.ndarray:
        """Return (data - model - offset) / sigma (n,): the weighted residuals."""
        return (self.campaign.magnitude - self.fitted(params)) / self.campaign.sigma

    def block_offsets(self, params: TumblerParameters) -> np.ndarray:
        """Return each block's solved offset [mag] (calibrated blocks share one)."""
        offsets = self.offsets(self.magnitudes(params))
        block_group = np.zeros(len(self.campaign.block_names), dtype=np.int64)
        block_group[self.campaign.block] = self.group
        return np.asarray(offsets[block_group])

    def try_residuals(self, params: TumblerParameters | None) -> np.ndarray | None:
        """
        Return :meth:`residuals`, or None for no state, a body no mass has, a failed run.

        (The moments must obey the triangle inequality, I1/I3 + I2/I3 >= 1: the Scenario's
        check, which the fit meets as a wall.)
        """
        if params is None:
            return None
        try:
            return self.residuals(params)
        except (ModelError, ScenarioError):
            return None


def parameters_or_none(start: TumblerParameters, names: Sequence[str],
                       values: Sequence[float] | np.ndarray) -> TumblerParameters | None:
    """Return ``start`` with the named values set, or None for an impossible spin state."""
    try:
        return start.with_values(names, values)
    except ScenarioError:
        return None


def anti_aligned_twin(params: TumblerParameters) -> TumblerParameters:
    """Return the same parameters with theta0 on the other side of 90 deg."""
    return replace(params, spin=replace(params.spin, anti_aligned=not params.spin.anti_aligned))

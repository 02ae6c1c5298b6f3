"""
The global search: period candidates x modes x a grid of L's direction and phases, then fits.

1. **Candidates** (P_phi, P_psi): given by the caller, or from the two-period search
   (``analysis.periods.search_periods`` on the reduced magnitudes in hours, each free block's
   weighted mean removed): its pair, its mirrors and its first alternatives, each basis
   (f1 > f2) read as (P_phi, P_psi) = (1/f1, 1/f2), (1/f2, 1/f1), (1/(f1 - f2), 1/f2),
   (1/(f1 + f2), 1/f2) (Pravec et al. 2005: the lightcurve of a tumbler holds j f_phi + k f_psi,
   and which basis of the lattice the search names is not the spin's own). A candidate is kept
   in a mode (SAM, LAM) when a body of the starting inertia ratios (or of one of
   :data:`INERTIA_STARTS`) has it.
2. **Grid**: for each candidate and mode, chi^2 at every L direction of a Fibonacci sphere
   (``poles``), phases (phi0, psi0) on a ``phases`` x ``phases`` grid and both signs of theta0,
   the shape, ratios and law at the start's; the ``starts`` best grid points go on.
3. **Local fits** (``fit.fit_local``) of every free parameter from each; the same solution
   reached twice is kept once.
4. **Acceptance**: every solution with chi^2 <= chi^2_min + ``delta_sigmas`` sqrt(2 nu)
   chi^2_min / nu (the 1-sigma spread of a chi^2 of nu degrees of freedom, in the units of the
   best fit's reduced chi^2) is accepted; more than one accepted solution is reported as not
   unique (mirrors, period aliases), and the period search's alias flags are carried over.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
import time
from typing import Sequence, TextIO

import numpy as np

from tumble_ros.analysis.periods import (DAYS_IN_HOURS, PeriodSolution, Progress, search_periods,
                                         stderr_search_progress)
from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.inversion.campaign import Campaign
from tumble_ros.inversion.fit import CHI2_FAR, fit_local, InversionFit
from tumble_ros.inversion.model import ForwardModel, ModelError, ModelOptions, \
    TumblerParameters

__all__ = ['SearchSettings', 'Candidate', 'CandidateResult', 'InversionResult', 'invert',
           'period_candidates', 'stderr_progress', 'INERTIA_STARTS']

#: Inertia ratios (I1/I3, I2/I3) tried, in order, for a candidate the start's ratios do not
#: allow (the SAMs need P_psi / P_phi above a bound that the ratios set, the LAMs too).
INERTIA_STARTS = ((0.6, 0.9), (0.5, 0.8), (0.75, 0.95), (0.45, 0.6), (0.85, 0.97))


@dataclass(frozen=True)
class SearchSettings:
    """
    How wide the global search looks (defaults: ~10 min for 2,000 points, 6 candidates).

    ``periods``: (P_phi, P_psi) pairs [h] to try instead of the period search's; ``modes`` the
    modes tried; ``max_candidates`` the most period pairs; ``poles`` L directions of the grid;
    ``phases`` values of each of phi0, psi0; ``starts`` grid points fitted per candidate and
    mode; ``inertia_ratios``, ``axis_ratios``, ``lambert_weight`` the start's; ``max_nfev`` the
    local fits' iterations; ``delta_sigmas`` the acceptance threshold (module docstring);
    ``period_range`` [h] of the period search (None: from the sampling).
    """

    periods: tuple[tuple[float, float], ...] = ()
    modes: tuple[str, ...] = ('SAM', 'LAM')
    max_candidates: int = 6
    poles: int = 12
    phases: int = 3
    starts: int = 2
    inertia_ratios: tuple[float, float] = (0.6, 0.9)
    axis_ratios: tuple[float, float] = (0.8, 0.6)
    lambert_weight: float = 0.1
    max_nfev: int = 40
    delta_sigmas: float = 1.0
    period_range: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ('max_candidates', 'poles', 'phases', 'starts', 'max_nfev'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ModelError(f'{name}: must be an integer >= 1, got {value!r}')
        bad = [m for m in self.modes if m not in ('SAM', 'LAM')]
        if bad or not self.modes:
            raise ModelError(f'modes: each must be SAM or LAM, got {list(self.modes)!r}')
        for pair in self.periods:
            if len(pair) != 2 or not all(math.isfinite(p) and p > 0 for p in pair):
                raise ModelError(f'periods: each must be (P_phi, P_psi) > 0 [h], got {pair!r}')


@dataclass(frozen=True)
class Candidate:
    """A period pair [h] in a mode, with the inertia ratios that allow it and its origin."""

    label: str
    mode: str
    precession_period: float
    rotation_period: float
    inertia_ratios: tuple[float, float]


@dataclass(frozen=True)
class CandidateResult:
    """A candidate's best chi^2 on the grid and after the local fits (inf: none succeeded)."""

    candidate: Candidate
    chi2_grid: float
    chi2_fit: float


@dataclass(frozen=True)
class InversionResult:
    """
    The outcome of :func:`invert`.

    ``solutions`` every distinct local fit, by increasing chi^2; ``accepted`` those within the
    threshold (``threshold`` the chi^2 bound); ``candidates`` each pair's chi^2 (the period
    plane); ``periods`` the period search's solution (None when the pairs were given);
    ``warnings`` what could make the answer wrong, one line each; ``seconds`` the wall time.
    """

    solutions: tuple[InversionFit, ...]
    accepted: tuple[InversionFit, ...]
    threshold: float
    candidates: tuple[CandidateResult, ...]
    periods: PeriodSolution | None
    warnings: tuple[str, ...]
    seconds: float
    campaign_source: str = ''
    settings: SearchSettings = field(default_factory=SearchSettings)

    @property
    def best(self) -> InversionFit:
        """Return the solution of least chi^2."""
        return self.solutions[0]


def stderr_progress(after: float = 2.0, every: float = 5.0,
                    stream: TextIO | None = None) -> Progress:
    """Return a progress callback printing ``invert: STAGE, 40% (12 s)`` to stderr."""
    return stderr_search_progress(after, every, stream, label='invert')


# -- candidates ----------------------------------------------------------------------------
def _feasible(mode: str, pair: tuple[float, float],
              ratios: Sequence[tuple[float, float]]) -> tuple[float, float] | None:
    """Return the first inertia ratios whose bodies have this period pair in ``mode``."""
    for r in ratios:
        if r[0] + r[1] < 1.0:
            continue                    # (no mass distribution has these moments)
        try:
            TumblerParameters.of(mode, pair[0], pair[1], r, (0.0, 0.0))
        except ScenarioError:
            continue
        return r
    return None


def _readings(f1: float, f2: float) -> list[tuple[str, tuple[float, float]]]:
    """Return the (P_phi, P_psi) readings [h] of a lattice basis (f1, f2) [1/h]."""
    fa, fb = max(f1, f2), min(f1, f2)
    out = [('(P1, P2)', (1 / fa, 1 / fb)), ('(P2, P1)', (1 / fb, 1 / fa)),
           ('(1/(f1+f2), P2)', (1 / (fa + fb), 1 / fb))]
    if fa - fb > 1e-9 * fa:
        out.append(('(1/(f1-f2), P2)', (1 / (fa - fb), 1 / fb)))
    return out


def period_candidates(campaign: Campaign, settings: SearchSettings,
                      progress: Progress | None = None
                      ) -> tuple[list[Candidate], PeriodSolution | None]:
    """Return the candidates (module docstring, step 1) and the period search's solution."""
    ratios = (settings.inertia_ratios,) + INERTIA_STARTS
    solution = None
    pairs: list[tuple[str, tuple[float, float]]] = []
    if settings.periods:
        pairs = [(f'given {k + 1}', p) for k, p in enumerate(settings.periods)]
    else:
        solution = _period_search(campaign, settings, progress)
        bases = [('search', solution.p1, solution.p2)]
        bases += [(m.label, m.p1, m.p2) for m in solution.mirrors[:2]]
        bases += [(a.label, a.p1, a.p2) for a in solution.alternatives[:2]
                  if math.isfinite(a.p2)]
        for origin, p1, p2 in bases:
            if math.isfinite(p2):
                pairs += [(f'{origin} {how}', pair) for how, pair in _readings(1 / p1, 1 / p2)]
    out: list[Candidate] = []
    for label, pair in pairs:
        for mode in settings.modes:
            if any(c.mode == mode and abs(c.precession_period / pair[0] - 1) < 1e-4
                   and abs(c.rotation_period / pair[1] - 1) < 1e-4 for c in out):
                continue
            r = _feasible(mode, pair, ratios)
            if r is not None:
                out.append(Candidate(label, mode, float(pair[0]), float(pair[1]), r))
    return out[:settings.max_candidates * len(settings.modes)], solution


def _period_search(campaign: Campaign, settings: SearchSettings,
                   progress: Progress | None) -> PeriodSolution:
    """Run the two-period search on the reduced magnitudes, each free block's mean removed."""
    y = campaign.reduced_magnitude().copy()
    w = 1.0 / campaign.sigma ** 2
    for b, free in enumerate(campaign.free_offset):
        mask = campaign.block == b
        if free and mask.any():
            y[mask] -= np.average(y[mask], weights=w[mask])
    t_hours = (campaign.jd_tdb - campaign.jd_tdb[0]) * 24.0
    p_min, p_max = settings.period_range or (None, None)
    return search_periods(t_hours, y, campaign.sigma, p_min, p_max,
                          named_periods=DAYS_IN_HOURS, unit='h',
                          progress=(lambda s, f: progress(f'period search: {s}', f))
                          if progress else None)


# -- the grid and the fits ---------------------------------------------------------------
def fibonacci_sphere(n: int) -> list[tuple[float, float]]:
    """Return n directions (lambda, beta) [rad] spread evenly over the sphere."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    out = []
    for k in range(n):
        z = 1.0 - (2.0 * k + 1.0) / n
        out.append(((golden * k) % (2 * math.pi), math.asin(z)))
    return out


def _grid(model: ForwardModel, candidate: Candidate, settings: SearchSettings
          ) -> list[tuple[float, TumblerParameters]]:
    """Return (chi^2, parameters) of every grid point of a candidate, by increasing chi^2."""
    phases = [2 * math.pi * k / settings.phases for k in range(settings.phases)]
    out = []
    for pole in fibonacci_sphere(settings.poles):
        for phi in phases:
            for psi in phases:
                for anti in (False, True):
                    try:
                        params = TumblerParameters.of(
                            candidate.mode, candidate.precession_period,
                            candidate.rotation_period, candidate.inertia_ratios, pole,
                            (phi, psi), anti, settings.axis_ratios, settings.lambert_weight)
                    except ScenarioError:
                        continue
                    f = model.try_residuals(params)
                    if f is not None:
                        out.append((float(f @ f), params))
    return sorted(out, key=lambda item: item[0])


def _same(a: InversionFit, b: InversionFit) -> bool:
    """Whether two fits are one solution (mode, theta0's sign, periods, L within 2 deg)."""
    sa, sb = a.parameters.spin, b.parameters.spin
    if sa.mode != sb.mode or sa.anti_aligned != sb.anti_aligned:
        return False
    if abs(sa.precession_period / sb.precession_period - 1) > 1e-4 or \
            abs(sa.rotation_period / sb.rotation_period - 1) > 1e-3:
        return False
    return _angle(sa.pole, sb.pole) < math.radians(2.0)


def _angle(p: tuple[float, float], q: tuple[float, float]) -> float:
    """Return the angle [rad] between two directions (lambda, beta)."""
    u = np.array([math.cos(p[1]) * math.cos(p[0]), math.cos(p[1]) * math.sin(p[0]),
                  math.sin(p[1])])
    v = np.array([math.cos(q[1]) * math.cos(q[0]), math.cos(q[1]) * math.sin(q[0]),
                  math.sin(q[1])])
    return float(math.atan2(np.linalg.norm(np.cross(u, v)), float(u @ v)))


def invert(campaign: Campaign, settings: SearchSettings | None = None,
           options: ModelOptions | None = None, *, epoch_jd: float | None = None,
           progress: Progress | None = None) -> InversionResult:
    """
    Search the spin state and shape of ``campaign`` (module docstring) and return every answer.

    ``settings`` how wide (:class:`SearchSettings`), ``options`` the model's (free parameters,
    mesh), ``epoch_jd`` t = 0 [JD TDB], ``progress(stage, fraction)`` called as it goes
    (:func:`stderr_progress` prints it). ModelError when no candidate can be fitted.
    """
    began = time.perf_counter()
    settings = settings or SearchSettings()
    report = progress or (lambda stage, fraction: None)
    model = ForwardModel(campaign, options or ModelOptions(), epoch_jd)
    candidates, periods = period_candidates(campaign, settings, report)
    if not candidates:
        raise ModelError('no period pair of the search is a SAM or LAM of any inertia ratios '
                         'tried: give --periods')
    fits: list[InversionFit] = []
    results = []
    for k, candidate in enumerate(candidates):
        name = (f'{candidate.mode} P_phi {candidate.precession_period:.5g} h, P_psi '
                f'{candidate.rotation_period:.5g} h ({candidate.label})')
        report(f'grid {k + 1}/{len(candidates)}', k / len(candidates))
        grid = _grid(model, candidate, settings)
        best_fit = math.inf
        for rank, (_, start) in enumerate(grid[:settings.starts]):
            report(f'fit {k + 1}/{len(candidates)}', (k + (rank + 1) / (settings.starts + 1))
                   / len(candidates))
            try:
                fit = fit_local(campaign, start, max_nfev=settings.max_nfev, model=model,
                                label=name)
            except ModelError:
                continue
            best_fit = min(best_fit, fit.chi2)
            fits.append(fit)
        results.append(CandidateResult(candidate, grid[0][0] if grid else math.inf, best_fit))
    if not fits:
        raise ModelError('no local fit succeeded from any candidate')
    solutions = _distinct(sorted(fits, key=lambda f: f.chi2))
    threshold = _threshold(solutions[0], settings.delta_sigmas)
    accepted = tuple(f for f in solutions if f.chi2 <= threshold)
    report('done', 1.0)
    return InversionResult(tuple(solutions), accepted, threshold, tuple(results), periods,
                           _result_warnings(accepted, periods), time.perf_counter() - began,
                           campaign.source, settings)


def _distinct(fits: list[InversionFit]) -> list[InversionFit]:
    """Return the fits (sorted by chi^2) without those that repeat a better one."""
    out: list[InversionFit] = []
    for fit in fits:
        if not any(_same(fit, kept) for kept in out):
            out.append(fit)
    return out


def _threshold(best: InversionFit, delta_sigmas: float) -> float:
    """Return the chi^2 bound of acceptance (module docstring, step 4)."""
    nu = max(best.dof, 1)
    reduced = best.chi2 / nu
    return best.chi2 + delta_sigmas * math.sqrt(2.0 * nu) * max(reduced, 1e-300)


def _result_warnings(accepted: tuple[InversionFit, ...],
                     periods: PeriodSolution | None) -> tuple[str, ...]:
    """Return what could make the inversion wrong, one line each."""
    out = []
    if len(accepted) > 1:
        out.append(f'not unique: {len(accepted)} solutions within the chi2 threshold (mirror '
                   'poles, period aliases or other modes: see the accepted solutions)')
    best = accepted[0]
    if best.dof > 0 and not 1.0 / CHI2_FAR <= best.chi2_reduced <= CHI2_FAR:
        out.append(f'the best fit has chi2/nu = {best.chi2_reduced:.3g}, far from 1')
    if periods is not None:
        out += [f'period search: {w}' for w in periods.warnings]
        if periods.aliases:
            out.append(f"period search: {', '.join(periods.aliases)} near a sampling alias")
    return tuple(out)


def with_label(fit: InversionFit, label: str) -> InversionFit:
    """Return ``fit`` relabelled."""
    return replace(fit, label=label)

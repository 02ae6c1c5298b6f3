"""
What a recording shows.

Counts, duration, comparator error, invariant drift, impacts, dominant frequencies of wx
against the theory's lines, and an aliasing check.

    from tumble_ros.analysis import load_recording, analyze, format_summary, summary_to_dict
    summary = analyze(load_recording("run.mcap"))
    print(format_summary(summary))          # text
    summary_to_dict(summary)                # JSON-safe dict (NaN/inf -> None)

How each number is computed is documented in docs/analysis.md; the docstrings below say it
briefly. Units: years, rad/yr, inertia normalised.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
import math

import numpy as np

from tumble_ros.core import jacobi_integral, make_model, ModelNotApplicable, Scenario
from tumble_ros.core.analytic import COS_THETA_TOL, SYMMETRY_TOL
from tumble_ros.core.rotation import euler_to_matrix, quaternion_to_matrix

from .recording import (ANGULAR_VELOCITY, ATTITUDE, ERROR, ERROR_NORM, EULER_ANGLES, ImpactRecord,
                        MODEL_ANGULAR_VELOCITY, Recording, ROOT_NAMESPACE, SCENARIO, topic_name)

__all__ = [
    'AliasingCheck', 'AnalysisSummary', 'ErrorStats', 'ImpactSummary', 'InvariantDrift',
    'JacobiSegment', 'Peak', 'Sampling', 'Spectrum', 'TheoryLine',
    'analyze', 'check_aliasing', 'comparator_errors', 'format_summary', 'impact_intervals',
    'impact_summaries', 'jacobi_drift', 'sampling', 'spectrum', 'summary_to_dict',
    'theory_lines',
]

#: Spectral window (numpy.blackman): sidelobes below -58 dB, main lobe +-3 bins.
WINDOW = 'blackman'
#: Peaks weaker than this fraction of the strongest are not reported (well above the
#: Blackman window's sidelobes, 1.3e-3).
PEAK_THRESHOLD = 5e-3
#: Intervals within this relative tolerance of the median count as uniform sampling.
UNIFORM_TOL = 1e-6


def _finite_or_none(x):
    return x if x is not None and math.isfinite(x) else None


# -- sampling ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Sampling:
    """The ``/angular_velocity`` time axis."""

    n: int
    t_first: float
    t_last: float
    duration: float          # t_last - t_first [yr]
    dt: float | None         # median interval [yr] (None for one sample)
    dt_min: float | None
    dt_max: float | None
    uniform: bool            # every interval within UNIFORM_TOL of the median
    gaps: int                # intervals longer than 1.5 * dt
    duplicates: int          # repeated stamps


def sampling(t: np.ndarray) -> Sampling:
    t = np.asarray(t, dtype=float)
    unique = np.unique(t)
    d = np.diff(unique)
    if len(d) == 0:
        return Sampling(len(t), float(t[0]), float(t[-1]), float(t[-1] - t[0]), None, None, None,
                        True, 0, len(t) - len(unique))
    dt = float(np.median(d))
    uniform = bool(np.all(np.abs(d - dt) <= UNIFORM_TOL * dt))
    return Sampling(len(t), float(unique[0]), float(unique[-1]), float(unique[-1] - unique[0]),
                    dt, float(d.min()), float(d.max()), uniform, int(np.sum(d > 1.5 * dt)),
                    len(t) - len(unique))


# -- comparator -------------------------------------------------------------------------------

@dataclass(frozen=True)
class ErrorStats:
    """
    Max and RMS of the comparator's error, absolute and relative.

    Absolute: |w_numeric - w_model| (rad/yr); relative: |error| / |w_numeric|.
    """

    models: tuple[str, ...]
    source: str              # the topic the norms come from
    n: int
    max_abs: float
    t_max_abs: float
    rms_abs: float
    max_rel: float | None
    t_max_rel: float | None
    rms_rel: float | None
    infinite_rel: int        # samples with |w_numeric| = 0 (relative error infinite), left out
    max_component: tuple[float, float, float] | None   # max |error_i|, if the vectors are known


def _match(t_a: np.ndarray, t_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the indices (ia, ib) of the samples of a and b at the same time (same stamp)."""
    _, ia, ib = np.intersect1d(t_a, t_b, assume_unique=False, return_indices=True)
    return ia, ib


def comparator_errors(rec: Recording) -> tuple[ErrorStats | None, str | None]:
    """
    (stats, None) or (None, why there are none).

    Sources in order of preference: ``/comparison/error_norm`` (norm and relative as the
    comparator computed them), ``/comparison/error`` (norm of the vector; relative to
    |w_numeric| at the same stamp), ``/comparison/model_angular_velocity`` (error = w - model
    at the same stamps).
    """
    models: tuple[str, ...] = rec.error_models
    if not models and rec.comparator_status is not None:
        name = rec.comparator_status.values.get('model')
        models = (name,) if name else ()
    vectors = None
    if len(rec.error_norm):
        t, norm, rel = rec.norm_t, rec.error_norm, rec.error_relative
        source = rec.topic(ERROR_NORM)
        if len(rec.error_t):
            vectors = rec.error
    elif len(rec.error_t):
        t, vectors, source = rec.error_t, rec.error, rec.topic(ERROR)
        norm = np.linalg.norm(vectors, axis=1)
        rel = np.full(len(t), np.nan)
        ia, ib = _match(t, rec.t)
        rel[ia] = norm[ia] / np.linalg.norm(rec.omega[ib], axis=1)
    elif len(rec.model_t):
        ia, ib = _match(rec.model_t, rec.t)
        if len(ia) == 0:
            return None, (f'{rec.topic(MODEL_ANGULAR_VELOCITY)} has no sample at a stamp of '
                          f'{rec.topic(ANGULAR_VELOCITY)}')
        t = rec.t[ib]
        vectors = rec.omega[ib] - rec.model_omega[ia]
        source = f'{rec.topic(ANGULAR_VELOCITY)} - {rec.topic(MODEL_ANGULAR_VELOCITY)}'
        norm = np.linalg.norm(vectors, axis=1)
        with np.errstate(divide='ignore', invalid='ignore'):
            rel = norm / np.linalg.norm(rec.omega[ib], axis=1)
    else:
        reason = f'no comparator topics ({rec.topic("/comparison/*")}) in the recording'
        if rec.comparator_status is not None:
            reason = (f'the comparator published no errors; its last status: '
                      f'{rec.comparator_status.level}: {rec.comparator_status.message}')
        return None, reason
    finite = np.isfinite(norm)
    if not finite.any():
        return None, f'{source}: no finite error value'
    k = int(np.nanargmax(np.where(finite, norm, np.nan)))
    rel_ok = np.isfinite(rel)
    infinite = int(np.sum(np.isinf(rel)))
    max_rel = t_max_rel = rms_rel = None
    if rel_ok.any():
        j = int(np.nanargmax(np.where(rel_ok, rel, np.nan)))
        max_rel, t_max_rel = float(rel[j]), float(t[j])
        rms_rel = float(np.sqrt(np.mean(rel[rel_ok] ** 2)))
    comp = None
    if vectors is not None and len(vectors):
        comp = tuple(float(v) for v in np.nanmax(np.abs(vectors), axis=0))
    return ErrorStats(
        models=models, source=source, n=len(t), max_abs=float(norm[k]), t_max_abs=float(t[k]),
        rms_abs=float(np.sqrt(np.mean(norm[finite] ** 2))), max_rel=max_rel, t_max_rel=t_max_rel,
        rms_rel=rms_rel, infinite_rel=infinite, max_component=comp), None


# -- invariant --------------------------------------------------------------------------------

@dataclass(frozen=True)
class JacobiSegment:
    """The Jacobi integral over one segment between impacts."""

    index: int
    t_start: float
    t_end: float
    n: int
    j0: float                # J at the segment's first sample
    max_drift: float         # max |J - j0|
    rel_drift: float | None  # max_drift / |j0| (None if j0 = 0)


@dataclass(frozen=True)
class InvariantDrift:
    name: str
    attitude_source: str
    segments: tuple[JacobiSegment, ...]
    excluded: int            # samples inside a pulse (J is not conserved there)

    @property
    def worst_rel(self) -> float | None:
        values = [s.rel_drift for s in self.segments if s.rel_drift is not None]
        return max(values) if values else None


def impact_intervals(rec: Recording) -> list[tuple[float, float]]:
    """
    Return [(start, end)] of every pulse, merged and sorted.

    The pulses are the recorded events and the scenario's scheduled impacts.
    """
    intervals = {(i.start, i.end) for i in rec.impacts}
    if rec.scenario is not None:
        intervals |= {(i.start, i.end) for i in rec.scenario.impacts}
    merged: list[tuple[float, float]] = []
    for start, end in sorted(intervals):
        if merged and start <= merged[-1][1] * (1 + 1e-12):
            merged[-1] = (merged[-1][0], max(end, merged[-1][1]))
        else:
            merged.append((start, end))
    return merged


def _attitude_matrices(rec: Recording) -> tuple[np.ndarray, np.ndarray, str] | None:
    """Return (indices into rec.t, C body->orbital (k, 3, 3), source) at the omega stamps."""
    if len(rec.quaternion_t):
        ia, ib = _match(rec.t, rec.quaternion_t)
        if len(ia):
            q = rec.quaternion[ib].T                 # (4, k): quaternion_to_matrix broadcasts
            c = np.moveaxis(quaternion_to_matrix(q), -1, 0)
            return ia, c, rec.topic(ATTITUDE)
    if len(rec.euler_t):
        ia, ib = _match(rec.t, rec.euler_t)
        if len(ia):
            c = np.stack([euler_to_matrix(*e).T for e in rec.euler[ib]])
            return ia, c, rec.topic(EULER_ANGLES)
    return None


def jacobi_drift(rec: Recording) -> tuple[InvariantDrift | None, str | None]:
    """
    Return the drift of the Jacobi integral per segment between impacts.

    J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' (tumble_ros.core.jacobi_integral) at every sample
    that has both w and the attitude, split into segments at the impacts (samples inside a
    pulse are left out); per segment max |J - J(first)|.
    """
    if rec.scenario is None:
        why = f'no {rec.topic(SCENARIO)} in the recording (inertia and orbit rate unknown)'
        if rec.scenario_error:
            why = f'{rec.topic(SCENARIO)} could not be parsed: {rec.scenario_error}'
        return None, why
    found = _attitude_matrices(rec)
    if found is None:
        return None, (f'no attitude at the stamps of {rec.topic(ANGULAR_VELOCITY)} '
                      f'(neither {rec.topic(ATTITUDE)} nor {rec.topic(EULER_ANGLES)})')
    idx, c, source = found
    t, w = rec.t[idx], rec.omega[idx]
    j = jacobi_integral(t, w, c, rec.scenario.inertia, rec.scenario.orbit_rate)
    intervals = impact_intervals(rec)
    inside = np.zeros(len(t), dtype=bool)
    segment = np.zeros(len(t), dtype=int)
    for start, end in intervals:
        inside |= (t > start) & (t < end)
        segment += t >= end
    segments = []
    for k in range(len(intervals) + 1):
        sel = (segment == k) & ~inside
        if not sel.any():
            continue
        js, ts = j[sel], t[sel]
        drift = float(np.max(np.abs(js - js[0])))
        segments.append(JacobiSegment(
            index=k, t_start=float(ts[0]), t_end=float(ts[-1]), n=int(sel.sum()),
            j0=float(js[0]), max_drift=drift,
            rel_drift=drift / abs(float(js[0])) if js[0] != 0 else None))
    return InvariantDrift('Jacobi integral', source, tuple(segments), int(inside.sum())), None


# -- impacts ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class ImpactSummary:
    """An impact event and the jump of the recorded w across it."""

    event: ImpactRecord
    t_before: float | None   # last sample at or before the pulse start
    t_after: float | None    # first sample at or after the pulse end
    sampled_jump: tuple[float, float, float] | None   # w(t_after) - w(t_before)


def impact_summaries(rec: Recording) -> list[ImpactSummary]:
    out = []
    for event in rec.impacts:
        i = int(np.searchsorted(rec.t, event.start, side='right')) - 1
        k = int(np.searchsorted(rec.t, event.end, side='left'))
        if 0 <= i < rec.n and k < rec.n:
            jump = tuple(float(v) for v in rec.omega[k] - rec.omega[i])
            out.append(ImpactSummary(event, float(rec.t[i]), float(rec.t[k]), jump))
        else:
            out.append(ImpactSummary(event, None, None, None))
    return out


# -- theory lines and aliasing ------------------------------------------------------------------

@dataclass(frozen=True)
class TheoryLine:
    """A frequency [rad/yr] at which the theory expects wx to oscillate."""

    name: str
    omega: float
    meaning: str


def _symmetric(scenario: Scenario) -> bool:
    ix, iy, _ = scenario.inertia
    return abs(ix - iy) <= SYMMETRY_TOL * max(abs(ix), abs(iy))


def theory_lines(scenario: Scenario | None, omega: np.ndarray | None = None
                 ) -> tuple[list[TheoryLine], str]:
    """
    Return the frequencies the theory expects in wx and a one-line description of their basis.

    Symmetric body (Ix = Iy), from the scenario's inputs a = (Iz - Ix)/Ix, w0 = omega0[2],
    ws = orbit_rate, theta0 = euler0[2] (docs/analytic.md):

    - wE = |a w0|, the free (nutation) term of every linearised model;
    - the paper's forced lines |wE +- wA|, wA = 2 (ws + (w0 + wE)/cos theta0) (ERRATA 6),
      present if the body precessed as the paper assumes;
    - the fast-spin forced lines |w0| and |w0 -+ 2 ws|, and the nutation with the tidal
      shift |a w0 + dbar|, dbar = S (3 cos^2 theta0 - 1)/2, S = (3/2) ws^2 a/((1 + a) w0).

    Without torque (ws = 0) only wE (symmetric) or the Euler-Poinsot frequency 2 pi/period
    (asymmetric, ``torque_free_exact``). Asymmetric body with torque: an estimate, the
    Euler-equation rate max_i |Ij - Ik|/Ii * max|w| and the forcing |w| + 2 ws.
    """
    if scenario is None:
        return [], 'no scenario: the expected frequencies are unknown'
    ix, iy, iz = scenario.inertia
    ws = scenario.orbit_rate
    w0 = scenario.omega0[2]
    theta = scenario.euler0[2]
    lines: list[TheoryLine] = []
    if _symmetric(scenario):
        a = (iz - ix) / ix
        w_e = a * w0
        basis = (f'symmetric body: a = {a:.6g}, w0 = {w0:.6g} rad/yr, ws = {ws:.6g} rad/yr, '
                 f'theta0 = {theta:.6g} rad (scenario inputs)')
        lines.append(TheoryLine('wE', abs(w_e), 'free nutation wE = a w0'))
        if ws == 0.0:
            return lines, basis + '; no torque: wE only (exact)'
        if abs(math.cos(theta)) >= COS_THETA_TOL:
            w_a = 2.0 * (ws + (w0 + w_e) / math.cos(theta))
            lines.append(TheoryLine('|wA-wE|', abs(w_e - w_a),
                                    f"paper's forced term, wA = {w_a:.6g} rad/yr"))
            lines.append(TheoryLine('|wA+wE|', abs(w_e + w_a),
                                    f"paper's forced term, wA = {w_a:.6g} rad/yr"))
        lines.append(TheoryLine('|w0|', abs(w0), 'fast-spin forced term (spin)'))
        lines.append(TheoryLine('|w0-2ws|', abs(w0 - 2 * ws), 'fast-spin forced term'))
        lines.append(TheoryLine('|w0+2ws|', abs(w0 + 2 * ws), 'fast-spin forced term'))
        if w0 != 0.0:
            s = 1.5 * ws * ws * a / ((1.0 + a) * w0)
            dbar = s * (3.0 * math.cos(theta) ** 2 - 1.0) / 2.0
            lines.append(TheoryLine('|wE+dbar|', abs(w_e + dbar),
                                    f'fast-spin nutation with the tidal shift dbar = {dbar:.4g}'))
        return lines, basis
    moments = (ix, iy, iz)
    basis = f'asymmetric body: inertia {tuple(moments)}, ws = {ws:.6g} rad/yr'
    if ws == 0.0:
        try:
            model = make_model('torque_free_exact', scenario)
        except ModelNotApplicable as err:
            return [], basis + f'; no torque-free frequency: {err}'
        period = model.period
        if math.isfinite(period) and period > 0:
            lines.append(TheoryLine('Euler-Poinsot', 2 * math.pi / period,
                                    f'torque-free period {period:.6g} yr ({model.mode})'))
        return lines, basis + '; no torque: Euler-Poinsot motion (exact)'
    wmax = float(np.max(np.linalg.norm(omega, axis=1))) if omega is not None and len(omega) \
        else float(np.linalg.norm(scenario.omega0))
    rate = max(abs(moments[(i + 1) % 3] - moments[(i + 2) % 3]) / moments[i] for i in range(3))
    lines.append(TheoryLine('nutation (estimate)', rate * wmax,
                            'max |Ij - Ik|/Ii * max|w| (no linear theory for Ix != Iy)'))
    lines.append(TheoryLine('|w|+2ws (estimate)', wmax + 2 * ws, 'forcing, upper estimate'))
    return lines, basis + '; estimates only'


@dataclass(frozen=True)
class AliasingCheck:
    """pi/dt (the Nyquist rate of the sampling) against the fastest expected line."""

    dt: float | None
    nyquist: float | None                    # pi / dt [rad/yr]
    fastest: TheoryLine | None
    aliased: tuple[tuple[TheoryLine, float], ...]   # (line, where it appears: its alias) [rad/yr]
    warning: str | None


def _alias(omega: float, nyquist: float) -> float:
    period = 2.0 * nyquist
    return abs(omega - period * round(omega / period))


def check_aliasing(samp: Sampling, lines: list[TheoryLine]) -> AliasingCheck:
    """
    Check the sampling against the expected lines.

    WARNING when pi/dt is below any expected line (the fastest decides); each aliased line is
    listed with the frequency it masquerades as.
    """
    if samp.dt is None or not lines:
        return AliasingCheck(samp.dt, None, None, (), None)
    nyquist = math.pi / samp.dt
    fastest = max(lines, key=lambda line: line.omega)
    aliased = tuple((line, _alias(line.omega, nyquist)) for line in lines
                    if line.omega > nyquist)
    warning = None
    if aliased:
        listing = '; '.join(f'{line.name} = {line.omega:.4g} rad/yr (appears at '
                            f'{alias:.4g})' for line, alias in aliased)
        warning = (f'sampling interval dt = {samp.dt:.4g} yr (Nyquist pi/dt = {nyquist:.4g} '
                   f'rad/yr) aliases {listing}: the spectrum and any slow amplitude change in '
                   f'the plots can be aliasing (ERRATA.md, last section); sample at dt < '
                   f'pi/{fastest.omega:.4g} = {math.pi / fastest.omega:.3g} yr, several times '
                   f'finer for plots')
    return AliasingCheck(samp.dt, nyquist, fastest, aliased, warning)


# -- spectrum ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Peak:
    omega: float             # [rad/yr], refined between bins
    amplitude: float         # estimated amplitude of the sinusoid [rad/yr]
    nearest: str | None      # the theory line whose apparent frequency is nearest
    nearest_omega: float | None    # that line's frequency [rad/yr]
    offset: float | None     # omega - the line's apparent frequency [rad/yr]
    nearest_aliased: bool = False  # the line lies above pi/dt: its apparent frequency is its alias

    @property
    def period(self) -> float:
        return 2 * math.pi / self.omega if self.omega > 0 else math.inf


@dataclass(frozen=True)
class Spectrum:
    """Amplitude spectrum of one component (mean removed, Blackman window, rfft)."""

    component: str
    n: int
    dt: float
    resampled: bool          # linearly interpolated onto a uniform grid first
    window: str
    resolution: float        # bin spacing 2 pi/(n dt) [rad/yr]
    nyquist: float           # pi/dt [rad/yr]
    peaks: tuple[Peak, ...]
    omega_axis: np.ndarray = field(repr=False, metadata={'json': False})
    amplitude: np.ndarray = field(repr=False, metadata={'json': False})


def _uniform(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, float, bool]:
    t, first = np.unique(t, return_index=True)
    x = x[first]
    d = np.diff(t)
    dt = float(np.median(d))
    if np.all(np.abs(d - dt) <= UNIFORM_TOL * dt):
        return x, dt, False
    grid = t[0] + dt * np.arange(int(math.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1)
    return np.interp(grid, t, x), dt, True


def spectrum(t, x, lines: list[TheoryLine] = (), *, component: str = 'wx', n_peaks: int = 5,
             threshold: float = PEAK_THRESHOLD) -> Spectrum | None:
    """
    Return the dominant frequencies of ``x(t)``.

    They are the ``n_peaks`` strongest local maxima of the windowed amplitude spectrum above
    ``threshold`` times the strongest, at least 3 bins apart, each refined by a parabola through
    the log amplitudes of its bin and the two neighbours and matched to the theory line whose
    apparent frequency (the line itself, or its alias if it lies above pi/dt) is nearest. None for
    fewer than 8 distinct samples.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if len(np.unique(t)) < 8:
        return None
    y, dt, resampled = _uniform(t, x)
    n = len(y)
    window = np.blackman(n)
    spec = np.fft.rfft((y - y.mean()) * window)
    amp = 2.0 * np.abs(spec) / window.sum()
    omega_axis = 2 * math.pi * np.fft.rfftfreq(n, dt)
    resolution = 2 * math.pi / (n * dt)
    candidates = [k for k in range(1, len(amp))
                  if amp[k] > amp[k - 1] and (k + 1 == len(amp) or amp[k] >= amp[k + 1])]
    candidates.sort(key=lambda k: -amp[k])
    chosen: list[int] = []
    top = amp[candidates[0]] if candidates else 0.0
    for k in candidates:
        if top <= 0 or amp[k] < threshold * top or len(chosen) >= n_peaks:
            break
        if all(abs(k - c) >= 3 for c in chosen):
            chosen.append(k)
    nyquist = math.pi / dt
    # where each line shows up in a spectrum sampled at dt (its alias above the Nyquist rate)
    apparent = [(line, line.omega if line.omega <= nyquist else _alias(line.omega, nyquist))
                for line in lines]
    peaks = []
    for k in chosen:
        shift = 0.0
        if 0 < k < len(amp) - 1 and min(amp[k - 1], amp[k], amp[k + 1]) > 0:
            a, b, c = np.log(amp[k - 1]), np.log(amp[k]), np.log(amp[k + 1])
            denom = a - 2 * b + c
            if denom < 0:
                shift = float(np.clip(0.5 * (a - c) / denom, -0.5, 0.5))
        w = float(omega_axis[k] + shift * resolution)
        if lines:
            line, seen = min(apparent, key=lambda item: abs(item[1] - w))
            peaks.append(Peak(w, float(amp[k]), line.name, line.omega, w - seen,
                              line.omega > nyquist))
        else:
            peaks.append(Peak(w, float(amp[k]), None, None, None))
    return Spectrum(component, n, dt, resampled, WINDOW, resolution, nyquist,
                    tuple(peaks), omega_axis, amp)


# -- the whole summary ------------------------------------------------------------------------

@dataclass(frozen=True)
class AnalysisSummary:
    path: str
    finalised: bool
    problem: str | None
    topics: dict[str, tuple[str, int]]
    seconds_per_year: float
    seconds_per_year_source: str
    sampling: Sampling
    scenario: dict | None                    # the scenario's parameters (flat, as ROS params)
    scenario_error: str | None
    final_status: str | None                 # 'FINISHED at t = 2 yr: reached duration'
    comparator: ErrorStats | None
    comparator_note: str | None
    invariant: InvariantDrift | None
    invariant_note: str | None
    impacts: tuple[ImpactSummary, ...]
    theory_basis: str
    theory: tuple[TheoryLine, ...]
    spectrum: Spectrum | None
    aliasing: AliasingCheck
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    namespace: str = ROOT_NAMESPACE          # the ROS namespace whose topics were analysed


def analyze(rec: Recording, *, n_peaks: int = 5) -> AnalysisSummary:
    """Everything the summary reports, computed from a loaded recording."""
    warnings: list[str] = []
    notes: list[str] = []
    if not rec.finalised:
        warnings.append(f'the file is truncated ({rec.problem}): analysed the messages of its '
                        f'complete chunks only')
    for topic, why in rec.skipped.items():
        notes.append(f'{topic} skipped: {why}')
    samp = sampling(rec.t)
    if samp.duplicates:
        warnings.append(f'{samp.duplicates} repeated stamps on {rec.topic(ANGULAR_VELOCITY)} '
                        f'(two runs in one file?)')
    if samp.gaps:
        notes.append(f'{samp.gaps} gaps longer than 1.5 dt in {rec.topic(ANGULAR_VELOCITY)}')
    if rec.seconds_per_year_source == 'default':
        notes.append(f'no {rec.topic(SCENARIO)}: seconds_per_year = 1 assumed')
    if rec.scenario_error:
        warnings.append(f'{rec.topic(SCENARIO)} could not be parsed: {rec.scenario_error}')

    final_status = None
    if rec.status:
        last = rec.status[-1]
        final_status = f'{last.state} at t = {last.t:.6g} yr' + (f': {last.message}'
                                                                 if last.message else '')
        for s in rec.status:
            if s.state == 'DIVERGED':
                warnings.append(f'the simulation DIVERGED at t = {s.t:.6g} yr: {s.message}')
        if last.state in ('RUNNING', 'PAUSED'):
            notes.append(f'the recording ends before the simulator finished (last status '
                         f'{last.state})')

    comparator, comparator_note = comparator_errors(rec)
    invariant, invariant_note = jacobi_drift(rec)
    lines, basis = theory_lines(rec.scenario, rec.omega)
    spec = spectrum(rec.t, rec.omega[:, 0], lines, n_peaks=n_peaks)
    if spec is not None and spec.resampled:
        notes.append('wx was linearly interpolated onto a uniform grid for the spectrum '
                     '(uneven sampling)')
    aliasing = check_aliasing(samp, lines)
    if aliasing.warning:
        warnings.append(aliasing.warning)
    return AnalysisSummary(
        path=str(rec.path), finalised=rec.finalised, problem=rec.problem, topics=rec.topics,
        seconds_per_year=rec.seconds_per_year,
        seconds_per_year_source=rec.seconds_per_year_source, sampling=samp,
        scenario=rec.scenario.to_parameters() if rec.scenario is not None else None,
        scenario_error=rec.scenario_error, final_status=final_status,
        comparator=comparator, comparator_note=comparator_note,
        invariant=invariant, invariant_note=invariant_note, impacts=tuple(impact_summaries(rec)),
        theory_basis=basis, theory=tuple(lines), spectrum=spec, aliasing=aliasing,
        warnings=tuple(warnings), notes=tuple(notes), namespace=rec.namespace)


# -- rendering --------------------------------------------------------------------------------

def _g(x, digits: int = 6) -> str:
    if x is None:
        return '-'
    return f'{x:.{digits}g}'


def _v(v, digits: int = 6) -> str:
    return '(' + ', '.join(_g(x, digits) for x in v) + ')'


def format_summary(s: AnalysisSummary) -> str:
    """Return the summary as text (one WARNING: line per warning, at the end)."""
    out = [f'recording: {s.path}']
    if s.namespace != ROOT_NAMESPACE:
        out.append(f'namespace: {s.namespace}')
    state = 'finalised' if s.finalised else f'TRUNCATED ({s.problem})'
    total = sum(count for _, count in s.topics.values())
    out.append(f'file: {state}, {len(s.topics)} topics, {total} messages')
    width = max((len(name) for name in s.topics), default=0)
    twidth = max((len(t) for t, _ in s.topics.values()), default=0)
    for name, (type_name, count) in sorted(s.topics.items()):
        out.append(f'  {name:<{width}}  {type_name:<{twidth}}  {count:>9}')
    p = s.sampling
    dt = (f'dt = {_g(p.dt)} yr' + (' (uniform)' if p.uniform else
                                   f' (median; {_g(p.dt_min)} .. {_g(p.dt_max)})')
          if p.dt is not None else 'one sample')
    out.append(f'simulated time: {p.n} samples of {topic_name(s.namespace, ANGULAR_VELOCITY)}, '
               f't = {_g(p.t_first)} .. '
               f'{_g(p.t_last)} yr, duration {_g(p.duration)} yr, {dt}')
    source = s.seconds_per_year_source
    out.append(f'time base: seconds_per_year = {_g(s.seconds_per_year)} '
               f'({"default" if source == "default" else f"from {source}"})')
    if s.scenario is not None:
        sc = s.scenario
        out.append(f"scenario: inertia {_v(sc['inertia'])}, orbit_rate {_g(sc['orbit_rate'])} "
                   f"rad/yr, omega0 {_v(sc['omega0'])} rad/yr, euler0 {_v(sc['euler0'])} rad, "
                   f"duration {_g(sc['duration'])} yr, output_interval "
                   f"{_g(sc['output_interval'])} yr, {sc['integrator.method']}, "
                   f"{len(sc['impacts.start'])} scheduled impact(s)")
    else:
        out.append('scenario: none' + (f' ({s.scenario_error})' if s.scenario_error else
                                       f' (no {topic_name(s.namespace, SCENARIO)} topic)'))
    if s.final_status:
        out.append(f'simulator status: {s.final_status}')

    if s.comparator is not None:
        c = s.comparator
        models = ', '.join(repr(m) for m in c.models) or 'unknown'
        out.append(f'comparator error (model {models}; {c.n} samples from {c.source}):')
        out.append(f'  |w - w_model|: max {_g(c.max_abs)} rad/yr at t = {_g(c.t_max_abs)} yr, '
                   f'RMS {_g(c.rms_abs)} rad/yr')
        if c.max_rel is not None:
            out.append(f'  relative |w - w_model|/|w|: max {_g(c.max_rel)} at t = '
                       f'{_g(c.t_max_rel)} yr, RMS {_g(c.rms_rel)}'
                       + (f' ({c.infinite_rel} samples with |w| = 0 left out)'
                          if c.infinite_rel else ''))
        if c.max_component is not None:
            out.append(f'  max |error| per component (x, y, z): {_v(c.max_component)} rad/yr')
    else:
        out.append(f'comparator error: none ({s.comparator_note})')

    if s.invariant is not None:
        inv = s.invariant
        out.append(f"invariant drift: {inv.name} J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' "
                   f'(attitude from {inv.attitude_source}), per segment between impacts:')
        for seg in inv.segments:
            out.append(f'  segment {seg.index}: t = {_g(seg.t_start)} .. {_g(seg.t_end)} yr, '
                       f'{seg.n} samples, J0 = {_g(seg.j0, 10)}, max |J - J0| = '
                       f'{_g(seg.max_drift, 3)} (relative {_g(seg.rel_drift, 3)})')
        if inv.excluded:
            out.append(f'  ({inv.excluded} samples inside a pulse left out)')
    else:
        out.append(f'invariant drift: not computed ({s.invariant_note})')

    if s.impacts:
        out.append(f'impacts: {len(s.impacts)}')
        for imp in s.impacts:
            e = imp.event
            out.append(f'  #{e.id}: {e.frame} torque {_v(e.torque)} on [{_g(e.start, 10)}, '
                       f'{_g(e.end, 10)}] yr ({_g(e.duration, 3)} yr): delta_omega '
                       f'{_v(e.delta_omega)} rad/yr, |delta_omega| = '
                       f'{_g(math.hypot(*e.delta_omega))}')
            if imp.sampled_jump is not None:
                out.append(f'      recorded w jump between the samples at t = '
                           f'{_g(imp.t_before)} and {_g(imp.t_after)} yr: '
                           f'{_v(imp.sampled_jump)} rad/yr (includes the free motion between)')
    else:
        out.append('impacts: none recorded')

    out.append(f'expected frequencies: {s.theory_basis}')
    for line in s.theory:
        out.append(f'  {line.name:<20} {line.omega:12.6g} rad/yr  (period '
                   f'{_g(2 * math.pi / line.omega if line.omega else math.inf, 4)} yr)  '
                   f'{line.meaning}')
    sp = s.spectrum
    if sp is not None:
        out.append(f'dominant frequencies of {sp.component}: {sp.window} window, {sp.n} samples'
                   f'{" (resampled)" if sp.resampled else ""}, dt = {_g(sp.dt)} yr, resolution '
                   f'{_g(sp.resolution, 4)} rad/yr, Nyquist pi/dt = {_g(sp.nyquist, 6)} rad/yr')
        for k, peak in enumerate(sp.peaks, 1):
            match = ''
            if peak.nearest:
                alias = (f' aliased to {_g(peak.omega - peak.offset)}' if peak.nearest_aliased
                         else '')
                match = (f', nearest line {peak.nearest} = {_g(peak.nearest_omega)}{alias} '
                         f'(offset {peak.offset:+.3g})')
            out.append(f'  {k}. {peak.omega:12.6g} rad/yr (period {_g(peak.period, 4)} yr), '
                       f'amplitude {_g(peak.amplitude, 4)} rad/yr{match}')
        if not sp.peaks:
            out.append('  no peak (constant signal)')
    else:
        out.append('dominant frequencies: fewer than 8 samples, no spectrum')
    al = s.aliasing
    if al.nyquist is not None and al.fastest is not None and not al.aliased:
        out.append(f'aliasing: none expected: Nyquist pi/dt = {_g(al.nyquist)} rad/yr > fastest '
                   f'expected line {al.fastest.name} = {_g(al.fastest.omega)} rad/yr')
    elif al.nyquist is None or al.fastest is None:
        out.append('aliasing: not checked (no expected frequencies or a single sample)')
    for note in s.notes:
        out.append(f'note: {note}')
    for warning in s.warnings:
        out.append(f'WARNING: {warning}')
    return '\n'.join(out)


def _jsonable(value):
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out = {}
        for f in dataclasses.fields(value):
            if f.metadata.get('json', True):
                out[f.name] = _jsonable(getattr(value, f.name))
        for name in ('duration', 'period', 'worst_rel'):
            attr = getattr(type(value), name, None)
            if isinstance(attr, property):
                out[name] = _jsonable(getattr(value, name))
        return out
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        return _finite_or_none(float(value))
    if isinstance(value, np.integer):
        return int(value)
    return value


def summary_to_dict(s: AnalysisSummary) -> dict:
    """
    Return the summary as plain JSON types; non-finite numbers become None.

    ``topics`` maps each name to {"type", "count"}.
    """
    out = _jsonable(s)
    out['topics'] = {name: {'type': t, 'count': n} for name, (t, n) in s.topics.items()}
    return out

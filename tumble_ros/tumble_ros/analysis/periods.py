"""
Periods from a lightcurve: the two-period Fourier series of Pravec et al. 2005 (ROS-free, numpy).

A tumbler's lightcurve is doubly periodic: it holds the frequencies j f1 + k f2 of two basic
frequencies f1 = 1/P1, f2 = 1/P2 (Pravec et al. 2005, Icarus 173, 108, "Tumbling asteroids").
The model of order m is

    F(t) = C0 + sum_{j=0..m} sum_{k=-m..m} [C_jk cos(2 pi (j f1 + k f2) t)
                                            + S_jk sin(2 pi (j f1 + k f2) t)]

over (j, k) != (0, 0), k > 0 when j = 0; it is linear in C, S and fitted by weighted least
squares at every (f1, f2) of a grid; the trial with the least RMS residual wins. A principal-axis
rotator needs only f1 and its harmonics (the 1-period series of Harris et al. 1989).

The search (docs/analysis.md, "Periods from a lightcurve"):

* a 1-period scan over [1/period_max, 1/period_min] in steps of 1/(OVERSAMPLE m T) (T the data
  span) gives the candidates for f1: its TOP_PEAKS deepest minima and half of each (the
  strongest signal of an elongated body is the second harmonic);
* the 2-period grid: f1 within +-WINDOW steps of each candidate, f2 over the whole range; the
  normal equations of every trial are assembled from the sums sum_i w_i exp(2 pi i (a f1 +
  b f2) t_i), |a|, |b| <= 2m, computed for a chunk of the grid by one real matrix product
  (the powers of exp(2 pi i f t) by recurrence, b and -b from the same four real products; no
  design matrix per trial); each trial's RSS is the last Cholesky pivot of its augmented
  normal matrix (no solve), degenerate trials (:func:`_degenerate`) are not computed;
* refinement: Nelder-Mead on the exact least-squares RMS from the best grid point;
* the order m minimises the BIC N ln(RSS/N) + p ln N (p: the coefficients and the
  frequencies): the grid is searched at the orders 1 to ``start_order`` (3), the pair of least
  BIC kept, the order then chosen at it among 1 to MAX_ORDER (and the pair refined at that
  order; the grid is not searched again, which bounds the cost): a low order finds the basis
  of the lattice, where a high order also fits bases of a finer lattice holding it (f2 / 3);
* one period or two: the BIC of the best 1-period fit (order chosen by the same rule) against
  the 2-period one; two periods only if the latter's is lower by more than BIC_MARGIN;
* uncertainties: the formal 1-sigma of the frequencies from the covariance of the nonlinear
  least-squares problem (coefficients and frequencies together) at the minimum, scaled by the
  residual variance;
* mirror solutions: other bases of the same lattice of frequencies ((f1 - f2, f2), (f1 + f2,
  f2), (f1, f1 - f2), (f2, f1), ...) with the RMS of their own fit at the same order: at a finite
  order they differ, and the reader sees how close they come.

Times in any unit (hours for the command line), frequencies in its inverse.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
import math
import sys
import time
from typing import TextIO

import numpy as np
from scipy.optimize import minimize

__all__ = ['Alternative', 'Harmonic', 'MirrorSolution', 'PeriodSolution', 'Progress',
           'campaign_times', 'combination', 'fit_series', 'format_periods', 'harmonics',
           'sampling_periods', 'search_periods', 'stderr_search_progress', 'BIC_MARGIN',
           'DAYS_IN_HOURS', 'GRID_BUDGET', 'MAX_FREQUENCIES', 'MAX_MAGNITUDE', 'MAX_ORDER',
           'MAX_SIGMA', 'MIN_SIGMA', 'OVERSAMPLE', 'ROTATION_RANGE', 'TOP_PEAKS', 'TREND_RATIO',
           'WINDOW', 'WINDOW_PEAK']

#: grid steps per 1/(m T) in f (T the span, m the order)
OVERSAMPLE = 3
#: 1-period minima taken as candidates for f1 (each also halved)
TOP_PEAKS = 2
#: the f1 window about each candidate, in grid steps either side
WINDOW = 4
#: the highest order tried
MAX_ORDER = 5
#: two periods only when their BIC is lower than one period's by more than this
BIC_MARGIN = 10.0
#: elements of a grid chunk (pairs x trig sums) held at once: also what bounds one numpy call,
#: hence how soon a signal (Ctrl-C) is served during a search (docs/analysis.md)
_CHUNK = 1_000_000
#: the largest |magnitude| searched [mag]: beyond any object's (the Sun is -26.7)
MAX_MAGNITUDE = 100.0
#: the errors accepted [mag]: > 0 (weights 1/sigma^2, which overflow near 1e-154), and no
#: photometry is better than ~1e-4 mag
MIN_SIGMA = 1e-6
MAX_SIGMA = 100.0
#: the 2-period grid's trials at order 3 that the default period range allows (its short end is
#: raised to hold them): ~5 s CPU at ~1,000 points (docs/analysis.md)
GRID_BUDGET = 60_000
#: the most trial frequencies of a period range (an explicit one beyond it is refused)
MAX_FREQUENCIES = 200_000
#: a smooth trend (quadratic in time) whose range is more than this times the spread of the
#: rest is a geometry (distance, phase angle) or a period longer than the span: warned about
TREND_RATIO = 3.0
#: the largest range of magnitudes a rotation makes [mag]: 2.5 log10 of an elongation of 10
#: (the largest lightcurve amplitudes observed are ~2 mag); beyond it the geometry dominates
ROTATION_RANGE = 2.5
#: the spectral window's peaks above this (1 at f = 0) are periodicities of the sampling
WINDOW_PEAK = 0.5
#: the periodicities a ground campaign's sampling has, in hours: the solar and sidereal days
DAYS_IN_HOURS = (('solar day', 24.0), ('sidereal day', 23.9344696))
#: alternatives listed (aliases of the pair, the grid's other minima, one period)
_ALTERNATIVES = 10


@dataclass(frozen=True)
class Harmonic:
    """One term of the fit: frequency j f1 + k f2 [1/time], amplitude sqrt(C^2 + S^2) [mag]."""

    j: int
    k: int
    frequency: float
    amplitude: float


@dataclass(frozen=True)
class MirrorSolution:
    """Another basis (f1', f2') of the lattice: its label, periods [time], fit RMS [mag]."""

    label: str
    p1: float
    p2: float
    rms: float


@dataclass(frozen=True)
class Alternative:
    """
    Another solution the search weighed, refitted at the solution's order.

    ``label`` where it comes from (an alias of the pair, another minimum of the grid, one
    period); ``p1``, ``p2`` [time] (``p2`` NaN for one period); ``rms`` [mag]; ``chi2`` the
    reduced chi-square (NaN without errors); ``aliases`` which of its periods sit within the
    resolution of a sampling periodicity.
    """

    label: str
    p1: float
    p2: float
    rms: float
    chi2: float
    aliases: tuple[str, ...] = ()


@dataclass(frozen=True)
class PeriodSolution:
    """
    The result of :func:`search_periods`.

    ``p1``, ``p2`` [time unit of t] with their 1-sigma ``p1_sigma``, ``p2_sigma`` (``p2`` and
    ``p2_sigma`` NaN when ``two_periods`` is False); ``order`` m; ``rms`` [mag] the weighted RMS
    residual; ``rms_one`` of the best 1-period fit; ``bic_one``, ``bic_two``; ``harmonics`` by
    decreasing amplitude; ``mirrors`` other bases of the lattice; ``n`` points, ``span`` [time].
    ``chi2`` the reduced chi-square (NaN without errors); ``alternatives`` the other solutions
    weighed, by increasing chi-square (RMS); ``sampling`` the sampling's periodicities (name,
    period [time]); ``aliases`` which of ``p1``, ``p2`` sit on one; ``period_range`` the
    periods searched [time] and ``range_note`` how they were chosen; ``warnings`` what could
    make the periods wrong, one line each; ``reduction`` what was done to the magnitudes
    before the search (set by the caller: :mod:`.lightcurve`).
    """

    two_periods: bool
    p1: float
    p1_sigma: float
    p2: float
    p2_sigma: float
    order: int
    rms: float
    rms_one: float
    bic_one: float
    bic_two: float
    harmonics: tuple[Harmonic, ...]
    mirrors: tuple[MirrorSolution, ...]
    n: int
    span: float
    coefficients: tuple[float, ...]
    t0: float
    mean: float
    chi2: float = math.nan
    alternatives: tuple[Alternative, ...] = ()
    sampling: tuple[tuple[str, float], ...] = ()
    aliases: tuple[str, ...] = ()
    period_range: tuple[float, float] = (math.nan, math.nan)
    range_note: str = ''
    warnings: tuple[str, ...] = ()
    reduction: str = ''

    def model(self, t: np.ndarray) -> np.ndarray:
        """Return the fitted lightcurve at times ``t`` [mag] (unit and origin of the data)."""
        f2 = 0.0 if not self.two_periods else 1.0 / self.p2
        terms = _terms(self.order, self.two_periods)
        design = _design(np.asarray(t, dtype=float) - self.t0, 1.0 / self.p1, f2, terms)
        return self.mean + design @ np.asarray(self.coefficients)


def harmonics(order: int, two_periods: bool = True) -> list[tuple[int, int]]:
    """Return the (j, k) of the series of ``order`` (k = 0 throughout for one period)."""
    if not two_periods:
        return [(j, 0) for j in range(1, order + 1)]
    return ([(0, k) for k in range(1, order + 1)]
            + [(j, k) for j in range(1, order + 1) for k in range(-order, order + 1)])


def _terms(order: int, two_periods: bool) -> np.ndarray:
    return np.array(harmonics(order, two_periods), dtype=int).reshape(-1, 2)


def _design(t: np.ndarray, f1: float, f2: float, terms: np.ndarray) -> np.ndarray:
    """[1, cos, sin, cos, sin, ...] columns of the series at (f1, f2), shape (n, 1 + 2K)."""
    phase = 2.0 * np.pi * np.outer(t, terms[:, 0] * f1 + terms[:, 1] * f2)
    out = np.empty((t.size, 1 + 2 * len(terms)))
    out[:, 0] = 1.0
    out[:, 1::2] = np.cos(phase)
    out[:, 2::2] = np.sin(phase)
    return out


def fit_series(t: np.ndarray, y: np.ndarray, w: np.ndarray, f1: float, f2: float,
               order: int, two_periods: bool = True) -> tuple[float, np.ndarray]:
    """Weighted least squares at (f1, f2): (RSS = sum w r^2, coefficients [C0, C, S, ...])."""
    design = _design(t, f1, f2 if two_periods else 0.0, _terms(order, two_periods))
    weighted = design * w[:, None]
    normal = design.T @ weighted
    normal[np.diag_indices_from(normal)] *= 1.0 + 1e-12       # degenerate pairs stay solvable
    try:
        coef = np.linalg.solve(normal, weighted.T @ y)
    except np.linalg.LinAlgError:
        sw = np.sqrt(w)
        coef = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)[0]
    r = (y - design @ coef) * np.sqrt(w)
    return float(r @ r), coef


def _powers(f: np.ndarray, t: np.ndarray, top: int) -> np.ndarray:
    """
    Return exp(2 pi i a f t) for a = 0..top, shape (f.size, top + 1, t.size).

    One complex exponential per (f, t); the powers by the recurrence z^a = z^(a-1) z (angle
    addition: cos and sin of a x from those of (a - 1) x and x), rounding ~a eps.
    """
    z = np.exp(2j * np.pi * np.outer(f, t))
    out = np.empty((f.size, top + 1, t.size), dtype=complex)
    out[:, 0] = 1.0
    for a in range(1, top + 1):
        out[:, a] = z if a == 1 else out[:, a - 1] * z
    return out


def _stack_parts(values: np.ndarray) -> np.ndarray:
    """Real and imaginary parts stacked on a new first axis, contiguous."""
    return np.stack([values.real, values.imag])


@lru_cache(maxsize=8)
def _normal_tables(m: int) -> tuple[np.ndarray, ...]:
    """
    Where each lower-triangle entry of a trial's augmented normal matrix comes from.

    The design's columns: 1, then cos and sin of 2 pi v.(f1, f2) t for each term v = (j, k);
    the augmented matrix [[A^T W A, A^T W y], [y^T W A, y^T W y]] has P = 2K + 2 rows. Its
    entries are linear in S(a, b) = sum_i w_i exp(2 pi i (a f1 + b f2) t_i) (|a|, |b| <= 2m)
    and R(j, k) = sum_i w_i y_i exp(2 pi i (j f1 + k f2) t_i):

        cos_p cos_q = (Re S(p - q) + Re S(p + q)) / 2
        sin_p sin_q = (Re S(p - q) - Re S(p + q)) / 2
        cos_p sin_q = (Im S(p + q) - Im S(p - q)) / 2
        sin_p cos_q = (Im S(p + q) + Im S(p - q)) / 2

    S(-a, -b) = conj S(a, b), so only a >= 0 is summed. The sums of a chunk of trials are held
    as rows of a real array: Re then Im, each over (row r, b + 2m), r = a for S (a = 0..2m),
    r = 2m + 1 + j for R (j = 0..m). Returns (position p P + q of the lower triangle, q <= p,
    index and factor of the first term, of the second, the diagonal's positions, P).
    """
    terms = _terms(m, True)
    jk = np.vstack([[0, 0], np.repeat(terms, 2, axis=0)])
    is_sin = np.r_[False, np.tile([False, True], len(terms))]
    cols, width = 4 * m + 1, (3 * m + 2) * (4 * m + 1)

    def s_index(v: np.ndarray, imag: bool) -> tuple[int, float]:
        a, b, sign = int(v[0]), int(v[1]), 1.0
        if a < 0 or (a == 0 and b < 0):
            a, b, sign = -a, -b, (-1.0 if imag else 1.0)
        return int(imag) * width + a * cols + b + 2 * m, sign

    size = jk.shape[0] + 1
    rows: list[tuple[int, int, float, int, float]] = []
    for p in range(size - 1):
        for q in range(p + 1):
            sin_p, sin_q = bool(is_sin[p]), bool(is_sin[q])
            (i_minus, s_minus), (i_plus, s_plus) = (s_index(jk[p] - jk[q], sin_p != sin_q),
                                                    s_index(jk[p] + jk[q], sin_p != sin_q))
            if sin_p == sin_q:
                c_minus, c_plus = 0.5, (-0.5 if sin_p else 0.5)
            else:
                c_minus, c_plus = (0.5 if sin_p else -0.5), 0.5
            rows.append((p * size + q, i_minus, c_minus * s_minus, i_plus, c_plus * s_plus))
    for q in range(size - 1):        # the last row: A^T W y
        r_index = (int(is_sin[q]) * width + (2 * m + 1 + int(jk[q, 0])) * cols
                   + int(jk[q, 1]) + 2 * m)
        rows.append(((size - 1) * size + q, r_index, 1.0, 0, 0.0))
    table = np.array(sorted(rows))
    return (table[:, 0].astype(int), table[:, 1].astype(int), table[:, 2],
            table[:, 3].astype(int), table[:, 4], np.arange(size - 1) * (size + 1),
            np.array(size))


def _grid_rss(t: np.ndarray, y: np.ndarray, w: np.ndarray, f1s: np.ndarray, f2s: np.ndarray,
              order: int, span: float | None = None,
              tick: Callable[[int, int], None] | None = None) -> np.ndarray:
    """
    Weighted RSS at every (f1s[i], f2s[j]) by the normal equations, shape (n1, n2).

    The sums S, R of a chunk of trials come from real matrix products of the parts of
    w e^(2 pi i a f1 t) (shared by every f2) and of e^(2 pi i b f2 t), b >= 0: (Lr + i Li)
    (Er +- i Ei) gives b and -b from the same four products. Each trial's augmented normal
    matrix (:func:`_normal_tables`) is factored by Cholesky, whose last pivot squared is the
    Schur complement y^T W y - b^T N^-1 b: the RSS, no solve. A ridge of 1e-10 of the largest
    diagonal entry keeps near-degenerate trials solvable (it raises their RSS by ~ridge |x|^2:
    up to ~20 % at condition numbers 1e10-1e14, parts in 1e9 at well-determined ones); a chunk
    whose factorisation still fails is solved by LU. With ``span`` [time], trials where two
    terms share a frequency within 1/span (:func:`_degenerate`) are not computed: +inf.
    ``tick(done, total)`` is called after each chunk of f2 (progress).
    """
    m = order
    pos, i_minus, c_minus, i_plus, c_plus, diag, size_arr = _normal_tables(m)
    size = int(size_arr)
    rows, cols = 3 * m + 2, 4 * m + 1
    e1 = _powers(f1s, t, 2 * m)                                          # n1, a, N
    # real and imaginary parts of w e^(a f1) (a = 0..2m) and w y e^(j f1) (j = 0..m)
    left_s = _stack_parts(e1 * w)                                        # 2, n1, 2m+1, N
    left_r = _stack_parts(e1[:, :m + 1] * (w * y))                       # 2, n1, m+1, N
    yy = float(np.sum(w * y * y))
    n1 = f1s.size
    out = np.full((n1, f2s.size), np.inf)
    # a chunk holds at most _CHUNK matrix entries and _CHUNK of the f2 exponentials' parts
    step = max(1, min(_CHUNK // (n1 * size * size), _CHUNK // (2 * (2 * m + 1) * t.size)))
    for lo in range(0, f2s.size, step):
        f2 = f2s[lo:lo + step]
        n2 = f2.size
        keep = (np.ones(n1 * n2, dtype=bool) if span is None
                else ~_degenerate(f1s[:, None], f2[None, :], m, span).ravel())
        if not keep.any():
            continue
        right = _stack_parts(_powers(f2, t, 2 * m).transpose(1, 0, 2))     # 2, b, n2, N
        right = np.ascontiguousarray(right.transpose(1, 0, 2, 3))          # b, 2, n2, N
        x = np.empty((2, rows, cols, n1, n2))
        for first, block, top in ((0, left_s, 2 * m), (2 * m + 1, left_r, m)):
            # (Lr + i Li)(Er +- i Ei) from the four real products: b and -b in one
            prod = (block.reshape(-1, t.size) @ right[:top + 1].reshape(-1, t.size).T)
            prod = prod.reshape(2, n1, block.shape[2], top + 1, 2, n2)
            rr, ii = prod[0, ..., 0, :], prod[1, ..., 1, :]
            ri, ir = prod[0, ..., 1, :], prod[1, ..., 0, :]
            cut = slice(first, first + block.shape[2])
            pos_b = slice(2 * m, 2 * m + top + 1)
            neg_b = slice(2 * m, 2 * m - top - 1 if 2 * m - top - 1 >= 0 else None, -1)
            x[0, cut, pos_b] = (rr - ii).transpose(1, 2, 0, 3)
            x[1, cut, pos_b] = (ri + ir).transpose(1, 2, 0, 3)
            x[0, cut, neg_b] = (rr + ii).transpose(1, 2, 0, 3)
            x[1, cut, neg_b] = (ir - ri).transpose(1, 2, 0, 3)
        x = x.reshape(2 * rows * cols, n1 * n2)[:, keep]
        # the lower triangles, trials last (whole rows gathered), read by Cholesky as (trial,
        # P, P): it uses only the lower triangle and the diagonal (numpy.linalg.cholesky)
        lower = np.take(x, i_minus, axis=0)
        lower *= c_minus[:, None]
        lower += np.take(x, i_plus, axis=0) * c_plus[:, None]
        g = np.empty((size * size, x.shape[1]))
        g[pos] = lower
        g[diag] += 1e-10 * g[diag].max(axis=0)
        g[-1] = yy
        normal = g.reshape(size, size, -1).transpose(2, 0, 1)
        try:
            rss = np.linalg.cholesky(normal)[:, -1, -1] ** 2
        except np.linalg.LinAlgError:        # not numerically positive definite: LU
            normal = np.tril(normal) + np.swapaxes(np.tril(normal, -1), 1, 2)
            b = normal[:, -1, :-1]
            coef = np.linalg.solve(normal[:, :-1, :-1], b[..., None])[..., 0]
            rss = yy - np.einsum('...i,...i->...', coef, b)
        found = np.full(n1 * n2, np.inf)
        found[keep] = rss
        out[:, lo:lo + n2] = found.reshape(n1, n2)
        if tick is not None:
            tick(lo + n2, f2s.size)
    return np.maximum(out, 0.0)


def _scan_one(t: np.ndarray, y: np.ndarray, w: np.ndarray, fs: np.ndarray,
              order: int) -> np.ndarray:
    """Weighted RSS of the 1-period series at every frequency of ``fs`` (vectorised)."""
    n_col = 1 + 2 * order
    harm = np.arange(1, order + 1)
    out = np.empty(fs.size)
    step = max(1, _CHUNK // (n_col * max(t.size, 1)))
    sw = np.sqrt(w)
    for lo in range(0, fs.size, step):
        f = fs[lo:lo + step]
        phase = 2.0 * np.pi * f[:, None, None] * harm[None, None, :] * t[None, :, None]
        design = np.concatenate([np.ones(phase.shape[:2] + (1,)), np.cos(phase),
                                 np.sin(phase)], axis=2) * sw[None, :, None]
        normal = np.einsum('fni,fnj->fij', design, design)
        rhs = np.einsum('fni,n->fi', design, y * sw)
        normal += 1e-12 * np.eye(n_col) * normal[:, :1, :1]
        x = np.linalg.solve(normal, rhs[..., None])[..., 0]
        out[lo:lo + f.size] = np.sum(w * y * y) - np.einsum('fi,fi->f', x, rhs)
    return np.maximum(out, 0.0)


def _bic(rss: float, n: int, n_par: int) -> float:
    return n * math.log(max(rss, 1e-300) / n) + n_par * math.log(n)


def _degenerate(f1: np.ndarray, f2: np.ndarray, order: int, span: float) -> np.ndarray:
    """
    Whether two terms of the series share a frequency within the resolution 1/span.

    That is a f1 + b f2 ~ 0 for some (a, b) != 0 with |a|, |b| <= order: f1/f2 near a ratio of
    small integers, where the lattice degenerates into one period's harmonics (the same
    frequency twice is one period, not two) and the fit uses unresolved pairs of frequencies.
    """
    out = np.zeros(np.broadcast(f1, f2).shape, dtype=bool)
    for a in range(0, order + 1):
        for b in range(-order, order + 1):
            if (a, b) != (0, 0) and (a > 0 or b > 0):
                out |= np.abs(a * f1 + b * f2) < 1.0 / span
    return out


def _local_minima(values: np.ndarray, count: int) -> np.ndarray:
    inner = np.flatnonzero((values[1:-1] <= values[:-2]) & (values[1:-1] <= values[2:])) + 1
    return inner[np.argsort(values[inner])][:count]


def _refine(objective, start: np.ndarray, scale: np.ndarray, maxiter: int = 400) -> np.ndarray:
    result = minimize(lambda u: objective(start + u * scale), np.zeros(start.size),
                      method='Nelder-Mead',
                      options={'xatol': 1e-4, 'fatol': 1e-12, 'maxiter': maxiter})
    return start + result.x * scale


def _sigma(t: np.ndarray, y: np.ndarray, w: np.ndarray, freqs: np.ndarray,
           coef: np.ndarray, order: int, two: bool, rss: float) -> np.ndarray:
    """1-sigma of the frequencies from the nonlinear least-squares covariance."""
    terms = _terms(order, two)
    f2 = freqs[1] if two else 0.0
    design = _design(t, freqs[0], f2, terms)
    cos_c, sin_c = coef[1::2], coef[2::2]
    # dF/dnu for nu = j f1 + k f2: 2 pi t (-C sin + S cos)
    d_nu = 2.0 * np.pi * t[:, None] * (-cos_c * design[:, 2::2] + sin_c * design[:, 1::2])
    jac = [d_nu @ terms[:, 0]] + ([d_nu @ terms[:, 1]] if two else [])
    full = np.column_stack([design] + jac) * np.sqrt(w)[:, None]
    dof = max(t.size - full.shape[1], 1)
    cov = np.linalg.pinv(full.T @ full) * (rss / dof)
    return np.sqrt(np.abs(np.diag(cov)[-len(jac):]))


def combination(frequency: float, f_a: float, f_b: float, largest: int = 4,
                rel_tol: float = 0.01) -> tuple[int, int] | None:
    """Return (a, b), |a|, |b| <= ``largest``, |f - (a f_a + b f_b)| <= rel_tol f, or None."""
    found = [(abs(a) + abs(b), abs(frequency - (a * f_a + b * f_b)), (a, b))
             for a in range(-largest, largest + 1) for b in range(-largest, largest + 1)
             if (a, b) != (0, 0)
             and abs(frequency - (a * f_a + b * f_b)) <= rel_tol * abs(frequency)]
    return min(found)[2] if found else None


def _mirrors(t, y, w, f1, f2, order) -> tuple[MirrorSolution, ...]:
    bases = {'(f1 - f2, f2)': (f1 - f2, f2), '(f1 + f2, f2)': (f1 + f2, f2),
             '(f1, f1 - f2)': (f1, f1 - f2), '(f2, f1)': (f2, f1),
             '(f1 - 2 f2, f2)': (f1 - 2.0 * f2, f2), '(f1, f1 + f2)': (f1, f1 + f2)}
    out = []
    for label, (g1, g2) in bases.items():
        g1, g2 = abs(g1), abs(g2)
        if min(g1, g2) <= 0.0:
            continue
        rss, _ = fit_series(t, y, w, g1, g2, order)
        out.append(MirrorSolution(label, 1.0 / g1, 1.0 / g2, math.sqrt(rss / np.sum(w))))
    return tuple(sorted(out, key=lambda s: s.rms))


def _validate(t, y, sigma) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """(t, y, weights of mean 1, span, mean of 1/sigma^2 or NaN); ValueError naming the input."""
    t = np.asarray(t, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if t.size != y.size:
        raise ValueError(f'magnitude: need one per time ({t.size}), got {y.size}')
    if t.size < 20:
        raise ValueError(f't: need at least 20 points, got {t.size}')
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError('t, magnitude: must be finite')
    if np.max(np.abs(y)) > MAX_MAGNITUDE:
        raise ValueError(f'magnitude: {y[np.argmax(np.abs(y))]:g} is not a magnitude '
                         f'(|mag| <= {MAX_MAGNITUDE:g})')
    scale = math.nan
    w = np.ones(t.size)
    if sigma is not None:
        s = np.asarray(sigma, dtype=float).ravel()
        if (s.size != t.size or not np.all(np.isfinite(s)) or np.any(s < MIN_SIGMA)
                or np.any(s > MAX_SIGMA)):
            raise ValueError(f'sigma: need {t.size} finite errors in [{MIN_SIGMA:g}, '
                             f'{MAX_SIGMA:g}] mag, got {s.size} (min '
                             f'{np.min(s) if s.size else "none"})')
        inverse = 1.0 / s ** 2
        scale = float(inverse.mean())
        w = inverse / scale
    span = float(t.max() - t.min())
    if span <= 0.0:
        raise ValueError(f't: the span must be > 0, got {span}')
    return t, y, w, span, scale


def _period_range(t: np.ndarray, span: float, period_min: float | None,
                  period_max: float | None, start_order: int,
                  unit: str) -> tuple[float, float, str]:
    """
    Return the periods searched [time] and how they were chosen; ValueError for too many.

    Default: the span down to 4 median sampling steps, that short end raised where the
    2-period grid would hold more than GRID_BUDGET trials at order 3 (its f2 axis holds
    (1/P_min - 1/P_max) OVERSAMPLE 3 span frequencies, each with up to 2 TOP_PEAKS
    (2 WINDOW + 1) values of f1).
    """
    p_max = span if period_max is None else float(period_max)
    shortest = 4.0 * float(np.median(np.diff(np.sort(t))))
    note = 'as given' if period_max is not None else 'P_min as given, to the span'
    if period_min is not None:
        p_min = float(period_min)
    else:
        # (two f2 fewer: np.arange's end and rounding)
        room = ((GRID_BUDGET / (2 * TOP_PEAKS * (2 * WINDOW + 1)) - 2.0)
                / (OVERSAMPLE * 3 * span))
        p_min = max(shortest, 1.0 / (1.0 / p_max + room)) if p_max > 0.0 else shortest
        note = ('the default: ' + ('the span' if period_max is None else 'P_max as given')
                + f' down to 4 median sampling steps ({shortest:.3g}{unit})'
                + (f', raised to {p_min:.3g}{unit} to hold the 2-period grid to '
                   f'{GRID_BUDGET:,} trials (--period-range searches others)'
                   if p_min > shortest else ''))
    if not (0.0 < p_min < p_max):
        raise ValueError(f'period_min, period_max: need 0 < min < max, got {p_min:g}, '
                         f'{p_max:g} (span {span:g}{unit})')
    count = (1.0 / p_min - 1.0 / p_max) * OVERSAMPLE * start_order * span
    if count > MAX_FREQUENCIES:
        raise ValueError(f'period_min, period_max: {p_min:g} to {p_max:g}{unit} over a span '
                         f'of {span:g}{unit} is {count:,.0f} trial frequencies, more than '
                         f'{MAX_FREQUENCIES:,} (MAX_FREQUENCIES): narrow the range')
    return p_min, p_max, note


def _window(t: np.ndarray, w: np.ndarray, fs: np.ndarray) -> np.ndarray:
    """Return the spectral window |sum w exp(2 pi i f t)| / sum w at ``fs`` (1 at f = 0)."""
    out = np.empty(fs.size)
    step = max(1, _CHUNK // max(t.size, 1))
    for lo in range(0, fs.size, step):
        out[lo:lo + step] = np.abs(np.exp(2j * np.pi * np.outer(fs[lo:lo + step], t)) @ w)
    return out / np.sum(w)


def sampling_periods(t: np.ndarray, w: np.ndarray, span: float, f_max: float,
                     named: tuple[tuple[str, float], ...] = ()
                     ) -> tuple[tuple[str, float], ...]:
    """
    Return the periodicities of the sampling, (name, period [time]), strongest first.

    The spectral window W(f) = |sum w_i exp(2 pi i f t_i)| / sum w_i (1 at f = 0) over
    [1.5/span, f_max] in steps of 1/(3 span): its local maxima above WINDOW_PEAK that are not
    a multiple of a stronger one (nightly sampling: 1/day; regular gaps: their period). A peak
    within 1/span of a ``named`` period takes its name; the named ones are listed in any case
    (a ground campaign's day is a risk whatever the window shows).
    """
    fs = np.arange(1.5 / span, f_max, 1.0 / (3.0 * span))
    out: list[tuple[str, float]] = []
    if fs.size >= 3:
        window = _window(t, w, fs)
        inner = np.flatnonzero((window[1:-1] >= window[:-2]) & (window[1:-1] >= window[2:])
                               & (window[1:-1] > WINDOW_PEAK)) + 1
        kept: list[float] = []
        for i in inner[np.argsort(-window[inner])]:
            f = float(fs[i])
            if any(abs(f / g - round(f / g)) * g < 1.0 / span for g in kept if f > g):
                continue
            kept.append(f)
            out.append(next(((label, p) for label, p in named
                             if abs(f - 1.0 / p) < 1.0 / span),
                            (f'window peak {window[i]:.2f}', 1.0 / f)))
    for label, p in named:
        if label not in {name for name, _ in out}:
            out.append((label, p))
    return tuple(out)


#: multiples of a sampling frequency a period is checked against, with their text
_ALIAS_RATIOS = ((1.0, '{}'), (2.0, '{} / 2'), (3.0, '{} / 3'), (0.5, '2 x {}'))


def _aliases(periods: dict[str, float], sampling: tuple[tuple[str, float], ...],
             span: float) -> tuple[str, ...]:
    """'P2 on 1 solar day' for each period within 1/span of a multiple of a sampling frequency."""
    out = []
    for label, p in periods.items():
        if not math.isfinite(p):
            continue
        for name, ps in sampling:
            found = next((text.format(name) for ratio, text in _ALIAS_RATIOS
                          if abs(1.0 / p - ratio / ps) < 1.0 / span), None)
            if found:
                out.append(f'{label} on {found}')
                break
    return tuple(out)


def _trend(t: np.ndarray, y: np.ndarray, w: np.ndarray, span: float) -> tuple[float, float]:
    """(range of the weighted quadratic fit in time [mag], 2-98 % spread of the rest [mag])."""
    x = 2.0 * t / span - 1.0
    design = np.column_stack([np.ones_like(x), x, x * x])
    sw = np.sqrt(w)
    coef = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)[0]
    trend = design @ coef
    rest = y - trend
    return float(np.ptp(trend)), float(np.percentile(rest, 98) - np.percentile(rest, 2))


def _same_pair(a: tuple[float, float], b: tuple[float, float], span: float) -> bool:
    """Whether two pairs (in either order) agree within the resolution 1/span."""
    return any(abs(a[0] - x) < 1.0 / span and abs(a[1] - z) < 1.0 / span
               for x, z in (b, b[::-1]))


def _grid_minima(rss: np.ndarray, f1s: np.ndarray, f2s: np.ndarray, step: float,
                 count: int) -> list[tuple[float, float]]:
    """Return the ``count`` least trials of a grid, each > 2 steps from a better one."""
    out: list[tuple[float, float]] = []
    for k in np.argsort(rss, axis=None)[:20_000]:
        i, j = np.unravel_index(k, rss.shape)
        if not np.isfinite(rss[i, j]):
            break
        pair = (float(f1s[i]), float(f2s[j]))
        if all(abs(pair[0] - a) > 2 * step or abs(pair[1] - b) > 2 * step for a, b in out):
            out.append(pair)
        if len(out) == count:
            break
    return out


Progress = Callable[[str, float], None]


def stderr_search_progress(after: float = 2.0, every: float = 5.0,
                           stream: TextIO | None = None, label: str = 'period search',
                           ) -> Progress:
    """
    Return a :data:`Progress` that prints ``LABEL: STAGE, 40% (12 s)`` to ``stream`` (stderr).

    Silent for the first ``after`` seconds [s] (a short search prints nothing), then at each
    new stage and at most once every ``every`` seconds within one.
    """
    start = time.monotonic()
    last, current = -math.inf, ''

    def report(stage: str, fraction: float) -> None:
        nonlocal last, current
        now = time.monotonic()
        if now - start < after or (stage == current and now - last < every):
            return
        last, current = now, stage
        print(f'{label}: {stage}, {min(max(fraction, 0.0), 1.0):.0%} '
              f'({now - start:.0f} s)', file=stream or sys.stderr, flush=True)
    return report


def search_periods(t, magnitude, sigma=None, period_min: float | None = None,
                   period_max: float | None = None, start_order: int = 3,
                   max_order: int = MAX_ORDER,
                   named_periods: tuple[tuple[str, float], ...] = (), unit: str = '',
                   progress: Progress | None = None) -> PeriodSolution:
    """
    Find the one or two periods of a lightcurve (module docstring for the method).

    ``t`` (n,) [any time unit], ``magnitude`` (n,) [mag], ``sigma`` (n,) [mag] optional errors
    (weights 1/sigma^2); the periods are searched in [``period_min``, ``period_max``]
    (:func:`_period_range`: by default from the sampling). ``named_periods``: periodicities the
    sampling may have, in the unit of ``t`` (:data:`DAYS_IN_HOURS` for a ground campaign in
    hours), ``unit`` the unit's text for the notes; ``progress(stage, fraction)`` is called as
    the search goes. The solution carries its alternatives, the sampling's periodicities and
    warnings (a trend, periods on a sampling alias or longer than half the span). ValueError
    for bad inputs, naming the argument.
    """
    t, y, w, span, scale = _validate(t, magnitude, sigma)
    p_min, p_max, range_note = _period_range(t, span, period_min, period_max, start_order,
                                             unit)
    report = progress or (lambda stage, fraction: None)
    t0, mean = float(t.min()), float(np.average(y, weights=w))
    t, y = t - t0, y - mean
    n = t.size
    wsum = float(np.sum(w))
    f_lo, f_hi = 1.0 / p_max, 1.0 / p_min
    sampling = sampling_periods(t, w, span, f_hi, named_periods)

    # one period: scan, refine, choose the order
    report('1-period scan', 0.0)
    step1 = 1.0 / (OVERSAMPLE * start_order * span)
    fs = np.arange(f_lo, f_hi + step1, step1)
    scan = _scan_one(t, y, w, fs, start_order)
    peaks = fs[_local_minima(scan, TOP_PEAKS)]
    best_one = (math.inf, 0.0, 1, np.zeros(1))
    for f in peaks:
        for order in range(1, max_order + 1):
            fr = _refine(lambda u: fit_series(t, y, w, u[0], 0.0, order, False)[0],
                         np.array([f]), np.array([step1]))[0]
            rss, coef = fit_series(t, y, w, fr, 0.0, order, False)
            bic = _bic(rss, n, 2 + 2 * order)
            if bic < best_one[0]:
                best_one = (bic, fr, order, coef)
    bic_one, f_one, order_one, coef_one = best_one
    rss_one, _ = fit_series(t, y, w, f_one, 0.0, order_one, False)

    # two periods: grid about the candidates, then the order, then refinement
    candidates = np.unique(np.concatenate([peaks, peaks / 2.0]))
    grids: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, float]] = {}

    def grid_best(order: int) -> np.ndarray:
        step = 1.0 / (OVERSAMPLE * order * span)
        f1s = np.unique(np.concatenate([c + step * np.arange(-WINDOW, WINDOW + 1)
                                        for c in candidates]))
        f1s = f1s[(f1s >= f_lo) & (f1s <= f_hi)]
        f2s = np.arange(f_lo, f_hi + step, step)
        whole = sum(o * o for o in range(1, start_order + 1))   # the cost grows as order^2
        done, share = sum(o * o for o in range(1, order)) / whole, order * order / whole
        rss = _grid_rss(t, y, w, f1s, f2s, order, span,
                        lambda k, total: report(f'2-period grid, order {order}',
                                                done + share * k / total))
        grids[order] = (rss, f1s, f2s, step)
        i, j = np.unravel_index(np.argmin(rss), rss.shape)
        return np.array([f1s[i], f2s[j]])

    def exact(order: int):
        return lambda u: fit_series(t, y, w, u[0], u[1], order)[0]

    def bic_at(pair: np.ndarray, o: int) -> float:
        return _bic(fit_series(t, y, w, pair[0], pair[1], o)[0], n, 3 + 2 * len(harmonics(o)))

    # the grid at every order up to start_order: a low order finds the basis of the lattice,
    # where a high one also fits bases of a finer lattice holding it (f2 / 3, ...)
    def refined(pair: np.ndarray, o: int, maxiter: int = 400) -> np.ndarray:
        objective = exact(o)
        step = 1.0 / (OVERSAMPLE * o * span)
        return _refine(lambda u: math.inf if _degenerate(u[0], u[1], o, span)
                       else objective(u), pair, np.array([step, step]), maxiter)

    tried = [(bic_at(p, o), o, tuple(p)) for o in range(1, start_order + 1)
             for p in [refined(grid_best(o), o)]]
    report('refinement', 1.0)
    pair = np.array(min(tried)[2])
    grid_order = min(tried)[1]
    orders = range(1, max_order + 1)
    order = orders[int(np.argmin([bic_at(pair, o) for o in orders]))]
    pair = refined(pair, order)
    rss_two, coef_two = fit_series(t, y, w, pair[0], pair[1], order)
    # a basis of the same lattice that fits better at this order (the grid held f1 near the
    # 1-period candidates only) is taken instead, once
    better = _mirrors(t, y, w, pair[0], pair[1], order)
    if better and better[0].rms ** 2 * wsum < rss_two * (1.0 - 1e-6):
        pair = refined(np.array([1.0 / better[0].p1, 1.0 / better[0].p2]), order)
        rss_two, coef_two = fit_series(t, y, w, pair[0], pair[1], order)
    bic_two = _bic(rss_two, n, 3 + 2 * len(harmonics(order)))
    two = bic_two < bic_one - BIC_MARGIN
    if pair[1] > pair[0]:      # f1 the higher frequency: P1 < P2
        pair = pair[::-1]
        rss_two, coef_two = fit_series(t, y, w, pair[0], pair[1], order)

    if two:
        freqs, coef, rss, m = pair, coef_two, rss_two, order
    else:
        freqs, coef, rss, m = np.array([f_one]), coef_one, rss_one, order_one
    sig = _sigma(t, y, w, freqs, coef, m, two, rss)
    terms = _terms(m, two)
    f2 = freqs[1] if two else 0.0
    amps = np.hypot(coef[1::2], coef[2::2])
    harm = sorted((Harmonic(int(j), int(k), float(j * freqs[0] + k * f2), float(a))
                   for (j, k), a in zip(terms, amps)), key=lambda h: -h.amplitude)
    p1 = 1.0 / freqs[0]
    p2 = 1.0 / freqs[1] if two else math.nan

    def chi2(rss_w: float, n_par: int) -> float:
        return scale * rss_w / max(n - n_par, 1) if math.isfinite(scale) else math.nan

    report('alternatives', 1.0)
    rss_grid, f1s, f2s, step = grids[grid_order]
    alternatives = _alternatives(
        t, y, w, (float(pair[0]), float(pair[1])), order, span, (f_lo, f_hi),
        _grid_minima(rss_grid, f1s, f2s, step, 6), sampling, refined, chi2)
    one = Alternative('one period', 1.0 / f_one, math.nan, math.sqrt(rss_one / wsum),
                      chi2(rss_one, 2 + 2 * order_one),
                      _aliases({'P': 1.0 / f_one}, sampling, span))
    if two:
        alternatives = tuple(sorted(alternatives + (one,), key=lambda a: a.rms))
    else:      # the 2-period pair first among the others
        alternatives = (Alternative('two periods', 1.0 / pair[0], 1.0 / pair[1],
                                    math.sqrt(rss_two / wsum),
                                    chi2(rss_two, 3 + 2 * len(harmonics(order))),
                                    _aliases({'P1': 1.0 / pair[0], 'P2': 1.0 / pair[1]},
                                             sampling, span)),) + alternatives
    aliases = _aliases({'P1': p1, 'P2': p2} if two else {'P': p1}, sampling, span)
    warnings = _warnings(t, y, w, span, unit, (p1, p2), aliases, harm,
                         scan_edge=bool(f_one < f_lo + 2.0 * step1), p_max=p_max)
    return PeriodSolution(
        two_periods=bool(two), p1=p1, p1_sigma=float(sig[0]) * p1 * p1,
        p2=p2, p2_sigma=float(sig[1]) / freqs[1] ** 2 if two else math.nan,
        order=m, rms=math.sqrt(rss / wsum), rms_one=math.sqrt(rss_one / wsum),
        bic_one=bic_one, bic_two=bic_two, harmonics=tuple(harm),
        mirrors=_mirrors(t, y, w, freqs[0], freqs[1], m) if two else (),
        n=n, span=span, coefficients=tuple(float(c) for c in coef), t0=t0, mean=mean,
        chi2=chi2(rss, len(coef) + (2 if two else 1)), alternatives=alternatives,
        sampling=sampling, aliases=aliases, period_range=(p_min, p_max),
        range_note=range_note, warnings=warnings)


def _alternatives(t, y, w, pair: tuple[float, float], order: int, span: float,
                  band: tuple[float, float], minima: list[tuple[float, float]],
                  sampling: tuple[tuple[str, float], ...], refined, chi2
                  ) -> tuple[Alternative, ...]:
    """
    Return other pairs than ``pair``, each refined and refitted at ``order``.

    The pair's aliases by the sampling's periodicities, (f1 +- fs, f2) and (f1, f2 +- fs), and
    the grid's other minima; by increasing RMS, without duplicates (within 1/span, either
    order) or the pair itself.
    """
    f1, f2 = pair
    starts: list[tuple[str, tuple[float, float]]] = []
    seen: list[float] = []
    for name, ps in sampling:
        fs = 1.0 / ps
        if any(abs(fs - g) < 1.0 / span for g in seen):
            continue                         # the sidereal day beside the solar one
        seen.append(fs)
        starts += [(f'(f1 + 1/({name}), f2)', (f1 + fs, f2)),
                   (f'(f1 - 1/({name}), f2)', (f1 - fs, f2)),
                   (f'(f1, f2 + 1/({name}))', (f1, f2 + fs)),
                   (f'(f1, f2 - 1/({name}))', (f1, f2 - fs))]
    starts += [(f'grid minimum {k}', m) for k, m in enumerate(minima, start=1)]
    wsum = float(np.sum(w))
    found: list[Alternative] = []
    kept: list[tuple[float, float]] = [pair]
    for label, (g1, g2) in starts:
        g1, g2 = abs(g1), abs(g2)
        if min(g1, g2) < 0.5 * band[0] or max(g1, g2) > 2.0 * band[1] or \
                _degenerate(np.asarray(g1), np.asarray(g2), order, span):
            continue
        g = refined(np.array([g1, g2]), order, 150)
        g = (float(max(g)), float(min(g)))
        if any(_same_pair(g, k, span) for k in kept):
            continue
        kept.append(g)
        rss, _ = fit_series(t, y, w, g[0], g[1], order)
        found.append(Alternative(label, 1.0 / g[0], 1.0 / g[1], math.sqrt(rss / wsum),
                                 chi2(rss, 3 + 2 * len(harmonics(order))),
                                 _aliases({'P1': 1.0 / g[0], 'P2': 1.0 / g[1]}, sampling,
                                          span)))
    return tuple(sorted(found, key=lambda a: a.rms)[:_ALTERNATIVES])


def _warnings(t, y, w, span: float, unit: str, periods: tuple[float, float],
              aliases: tuple[str, ...], harm: list[Harmonic], scan_edge: bool,
              p_max: float) -> tuple[str, ...]:
    """Return what could make the periods wrong, one line each (docs/analysis.md)."""
    out = []
    trend, spread = _trend(t, y, w, span)
    data_range = float(np.percentile(y, 98) - np.percentile(y, 2))
    if data_range > ROTATION_RANGE:
        out.append(f'the magnitudes span {data_range:.3g} mag (2-98 %), more than a rotation '
                   f'makes (~{ROTATION_RANGE:g} mag for an elongation of 10): a changing '
                   f'distance or phase angle (a flyby) dominates, and the periods may fit it, '
                   f'not the rotation (search reduced magnitudes)')
    elif trend > TREND_RATIO * spread:
        out.append(f'the magnitudes hold a smooth trend of {trend:.3g} mag over the span (a '
                   f'quadratic in time), {trend / max(spread, 1e-12):.3g} times the '
                   f'{spread:.3g} mag of the rest: a changing distance or phase angle (a '
                   f'flyby), or a period longer than the span; the periods may fit it, not '
                   f'the rotation (search reduced magnitudes)')
    if scan_edge:
        out.append(f'the best single period is the longest searched ({p_max:.4g}{unit}): the '
                   f'data may hold a longer period or a trend, which a span of '
                   f'{span:.4g}{unit} cannot measure')
    for label, p in zip(('P1', 'P2'), periods):
        if math.isfinite(p) and p > span / 2.0:
            out.append(f'{label} = {p:.4g}{unit} is longer than half the span '
                       f'({span:.4g}{unit}): fewer than two cycles observed, not measured')
    for text in aliases:
        out.append(f'{text}: within the resolution 1/span of a periodicity of the sampling, '
                   f'which may be what was fitted; its aliases are among the alternatives')
    data_range = float(np.ptp(y))
    if harm and harm[0].amplitude > 2.0 * data_range:
        out.append(f"the fit's harmonics reach {harm[0].amplitude:.3g} mag against a data "
                   f'range of {data_range:.3g} mag: near-degenerate terms cancel each other, '
                   f'the periods are not determined')
    return tuple(out)


def campaign_times(rng: np.random.Generator, nights: int, night_hours: float = 8.0,
                   per_hour: float = 6.0, clouded: float = 0.2,
                   day_hours: float = 24.0) -> np.ndarray:
    """
    Sample times [h] of a ground-based campaign, sorted, from 0.

    ``nights`` nights of ``night_hours`` each ``day_hours`` apart, each lost to clouds with
    probability ``clouded``, the observed ones shortened at random (50-100 %) and sampled
    ``per_hour`` times an hour at random instants: the gaps and uneven sampling of real data.
    """
    out = []
    for night in range(nights):
        if rng.random() < clouded:
            continue
        length = night_hours * rng.uniform(0.5, 1.0)
        start = night * day_hours + rng.uniform(0.0, night_hours - length)
        count = max(2, int(round(length * per_hour)))
        out.append(start + np.sort(rng.uniform(0.0, length, count)))
    if not out:
        raise ValueError(f'clouded: every night was lost ({nights} nights, p = {clouded})')
    times = np.concatenate(out)
    return times - times[0]


def _fit_text(rms: float, chi2: float) -> str:
    return f'RMS {rms:.4g} mag' + (f', chi2/dof {chi2:.3g}' if math.isfinite(chi2) else '')


def format_periods(sol: PeriodSolution, unit: str = 'h', harmonics_shown: int = 6) -> str:
    """
    Return the solution as text.

    What was searched, the periods, order, RMS (chi-square), the strongest harmonics, the
    mirror bases, the alternatives and the warnings.
    """
    lines = [f'lightcurve: {sol.n} points over {sol.span:.6g} {unit}; periods searched '
             f'{sol.period_range[0]:.4g} to {sol.period_range[1]:.4g} {unit} ({sol.range_note})']
    if sol.reduction:
        lines.append(f'  searched: {sol.reduction}')
    if sol.sampling:
        lines.append('  periodicities of the sampling: ' + ', '.join(
            f'{name} ({p:.6g} {unit})' for name, p in sol.sampling))
    flagged = f' [{"; ".join(sol.aliases)}]' if sol.aliases else ''
    if sol.two_periods:
        lines.append(f'  two periods: P1 = {sol.p1:.6g} +- {sol.p1_sigma:.2g} {unit}, '
                     f'P2 = {sol.p2:.6g} +- {sol.p2_sigma:.2g} {unit} (formal 1 sigma), '
                     f'order {sol.order}, {_fit_text(sol.rms, sol.chi2)} (one period: '
                     f'{sol.rms_one:.4g}){flagged}')
    else:
        lines.append(f'  one period: P = {sol.p1:.6g} +- {sol.p1_sigma:.2g} {unit} (formal 1 '
                     f'sigma), order {sol.order}, {_fit_text(sol.rms, sol.chi2)} (two periods '
                     f'not supported: BIC {sol.bic_two:.1f} vs {sol.bic_one:.1f}){flagged}')
    lines.append('  strongest harmonics (j f1 + k f2: period, amplitude):')
    for h in sol.harmonics[:harmonics_shown]:
        period = 1.0 / abs(h.frequency) if h.frequency else math.inf
        lines.append(f'    ({h.j:+d}, {h.k:+d}): {period:.6g} {unit}, {h.amplitude:.4f} mag')
    if sol.mirrors:
        lines.append("  mirror bases of the same frequencies (P1', P2', RMS):")
        for mirror in sol.mirrors:
            lines.append(f'    {mirror.label}: {mirror.p1:.6g} {unit}, {mirror.p2:.6g} {unit}, '
                         f'{mirror.rms:.4g} mag')
    if sol.alternatives:
        lines.append('  alternatives, best fit first (P1, P2, fit):')
        for alt in sol.alternatives:
            periods = (f'{alt.p1:.6g} {unit}' if math.isnan(alt.p2)
                       else f'{alt.p1:.6g} {unit}, {alt.p2:.6g} {unit}')
            flags = f' [{"; ".join(alt.aliases)}]' if alt.aliases else ''
            lines.append(f'    {alt.label}: {periods}, {_fit_text(alt.rms, alt.chi2)}{flags}')
    for text in sol.warnings:
        lines.append(f'  WARNING: {text}')
    return '\n'.join(lines)

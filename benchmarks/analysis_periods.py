"""The period search of a lightcurve: CPU and wall time of ``search_periods``, before and after.

A doubly periodic synthetic lightcurve (Apophis-like periods 30.565 h and 131.1 h, six terms,
0.01 mag noise) sampled like a ground-based campaign (nights of <= 8 h, clouded ones, 10
points an hour) of 3 and 4 weeks, searched over periods 10-600 h, and the default run's
recorded lightcurve (1,001 samples, ``analyze RUN.mcap --lightcurve``'s default range)
(docs/analysis.md, "Periods from a lightcurve"). Target (issue 29): a few-week campaign in
seconds.

"before" is the same search with the grid's previous kernel (:func:`_baseline_grid_rss`, kept
here only as the reference: complex trigonometric sums gathered into each trial's normal
matrix, solved by LU); "after" the shipped one (one real matrix product for b and -b,
degenerate trials skipped, the RSS as the last Cholesky pivot). Both must give the same
solution: the benchmark says so.
"""
from __future__ import annotations

from contextlib import contextmanager
import tempfile
import time

import numpy as np

from common import section

_BASELINE_CHUNK = 4_000_000


def _column_algebra(terms: np.ndarray, m: int):
    """Index and sign tables that build the normal matrix from the trigonometric sums."""
    jk = np.vstack([[0, 0], np.repeat(terms, 2, axis=0)])
    is_sin = np.r_[False, np.tile([False, True], len(terms))]
    sp = is_sin[:, None]
    sq = is_sin[None, :]
    plus = jk[:, None, :] + jk[None, :, :] + 2 * m
    minus = jk[:, None, :] - jk[None, :, :] + 2 * m
    re_minus = np.where(sp == sq, 0.5, 0.0)
    re_plus = np.where(~sp & ~sq, 0.5, np.where(sp & sq, -0.5, 0.0))
    im_minus = np.where(~sp & sq, -0.5, np.where(sp & ~sq, 0.5, 0.0))
    im_plus = np.where(sp != sq, 0.5, 0.0)
    return jk, is_sin, plus, minus, (re_minus, re_plus, im_minus, im_plus)


def _baseline_grid_rss(t, y, w, f1s, f2s, order, span=None, tick=None):
    """The grid kernel before 2026-12-04 (analysis/periods.py then), the reference; no tick."""
    from tumble_ros.analysis.periods import _degenerate, _terms
    m = order
    jk, is_sin, plus, minus, (a, b, c, d) = _column_algebra(_terms(m, True), m)
    width = 4 * m + 1
    powers = np.arange(-2 * m, 2 * m + 1)
    e1 = np.exp(2j * np.pi * (f1s[:, None, None] * powers[None, :, None]) * t)
    e1w = (e1 * w).reshape(-1, t.size)
    e1wy = (e1[:, m:3 * m + 1] * (w * y)).reshape(-1, t.size)
    yy = float(np.sum(w * y * y))
    n1 = f1s.size
    out = np.empty((n1, f2s.size))
    step = max(1, _BASELINE_CHUNK // (n1 * width * max(t.size, 1)))
    for lo in range(0, f2s.size, step):
        f2 = f2s[lo:lo + step]
        e2 = np.exp(2j * np.pi * (f2[:, None, None] * powers[None, :, None]) * t)
        n2 = f2.size
        s = (e1w @ e2.reshape(-1, t.size).T).reshape(n1, width, n2, width)
        s = s.transpose(0, 2, 1, 3)
        rhs_sum = (e1wy @ e2[:, m:3 * m + 1].reshape(-1, t.size).T)
        rhs_sum = rhs_sum.reshape(n1, 2 * m + 1, n2, 2 * m + 1).transpose(0, 2, 1, 3)
        s_minus = s[:, :, minus[..., 0], minus[..., 1]]
        s_plus = s[:, :, plus[..., 0], plus[..., 1]]
        normal = (a * s_minus.real + b * s_plus.real + c * s_minus.imag + d * s_plus.imag)
        r = rhs_sum[:, :, jk[:, 0] + m, jk[:, 1] + m]
        rhs = np.where(is_sin, r.imag, r.real)
        diag = np.einsum('...ii->...i', normal)
        ridge = 1e-10 * diag.max(axis=-1, keepdims=True)
        normal = normal + ridge[..., None] * np.eye(normal.shape[-1])
        x = np.linalg.solve(normal, rhs[..., None])[..., 0]
        out[:, lo:lo + n2] = yy - np.einsum('...i,...i->...', x, rhs)
    out = np.maximum(out, 0.0)
    if span is not None:
        out[_degenerate(f1s[:, None], f2s[None, :], m, span)] = np.inf
    return out


@contextmanager
def _baseline():
    from tumble_ros.analysis import periods
    shipped = periods._grid_rss
    periods._grid_rss = _baseline_grid_rss
    try:
        yield
    finally:
        periods._grid_rss = shipped


def _timed(t, y, sigma, **kwargs):
    from tumble_ros.analysis.periods import search_periods
    wall, cpu = time.perf_counter(), time.process_time()
    sol = search_periods(t, y, sigma, **kwargs)
    return sol, time.process_time() - cpu, time.perf_counter() - wall


def _default_run_lightcurve():
    """(t [h], magnitude) of the default scenario's recorded lightcurve topic."""
    from pathlib import Path
    from tumble_ros.analysis.lightcurve import recorded_lightcurve
    from tumble_ros.analysis.recording import load_recording
    from tumble_ros.core import load_scenario
    from tumble_ros.runs.offline import record_offline
    config = Path(__file__).resolve().parents[1] / 'tumble_ros' / 'config' / 'default.yaml'
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / 'default.mcap'
        record_offline(load_scenario(config), path, markers=False)
        return recorded_lightcurve(load_recording(path))


@section("Period search of a lightcurve (analysis/periods.py)", order=45)
def periods_section(ctx):
    from tumble_ros.analysis.periods import campaign_times

    f1, f2 = 1.0 / 30.565, 1.0 / 131.1
    terms = [(2, 0, 0.25, 0.3), (1, 0, 0.05, 1.0), (0, 1, 0.03, 2.0), (1, -1, 0.04, 0.5),
             (2, 1, 0.02, 4.0), (1, 2, 0.01, 2.5)]
    cases = []
    for nights in ((14,) if ctx.quick else (21, 28)):
        rng = np.random.default_rng(nights)
        t = campaign_times(rng, nights, per_hour=10.0)
        y = sum(a * np.cos(2 * np.pi * (j * f1 + k * f2) * t + p) for j, k, a, p in terms)
        y = y + rng.normal(0.0, 0.01, t.size)
        cases.append((f'{nights} nights', t, y, np.full(t.size, 0.01),
                      {'period_min': 10.0, 'period_max': 600.0}))
    if not ctx.quick:
        t, mag = _default_run_lightcurve()
        cases.append(('default run', t, mag, None, {}))
    rows, result = [], {}
    for name, t, y, sigma, kwargs in cases:
        with _baseline():
            before, cpu0, wall0 = _timed(t, y, sigma, **kwargs)
        after, cpu1, wall1 = _timed(t, y, sigma, **kwargs)
        same = (before.two_periods == after.two_periods and before.order == after.order
                and abs(before.p1 - after.p1) <= 1e-3 * after.p1_sigma
                and (not after.two_periods or abs(before.p2 - after.p2) <= 1e-3 * after.p2_sigma))
        rows.append((name, t.size, f"{after.p1:.4f}", f"{after.p2:.4f}", after.order,
                     f"{cpu0:.2f}", f"{cpu1:.2f}", f"{cpu0 / cpu1:.1f}",
                     f"{wall0:.2f}", f"{wall1:.2f}", "yes" if same else "NO"))
        result[name] = {"points": int(t.size), "cpu_s": cpu1, "wall_s": wall1,
                        "cpu_before_s": cpu0, "wall_before_s": wall0, "same": bool(same)}
    ctx.table(["case", "points", "P1", "P2", "order", "CPU before [s]", "CPU after [s]",
               "ratio", "wall before [s]", "wall after [s]", "same solution"], rows)
    ctx.note("the basis may be a mirror of (30.565 h, 131.1 h): the same lattice of frequencies; "
             "the default run's periods are in hours of its simulated time (its torque-free "
             "tumble is slow); 'same solution': order, one/two periods and the periods within "
             "1e-3 of their 1-sigma")
    return result

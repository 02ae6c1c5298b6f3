"""
Compiled ``dop853``: scipy's ``DOP853`` transcribed (``scipy/integrate/_ivp/rk.py``, 1.17).

The step, error norm, step-size control, initial step and 7th-order dense output, with
scipy's own coefficient tables; steps are taken in the segment's local time as scipy's solver
sees it (``integrators.adaptive``). Each function works on one body's state ``st``.
"""
from __future__ import annotations

import importlib
import importlib.util
import math
from pathlib import Path
import types

import numpy as np

from tumble_ros.core.compiling.jit import jit, jit_inline, jit_wide
from tumble_ros.core.kernels.lanes import lanes_rhs
from tumble_ros.core.kernels.layout import (Array, CF, Extra, FAIL, LANE_STAGES, LN, N, ST,
                                            STATUS)
from tumble_ros.core.kernels.physics import rhs, rhs_called

__all__ = ['start', 'step', 'dense', 'MAX_REJECTIONS', 'scipy_tables', 'step_start', 'attempt',
           'error_norm', 'control', 'accepted', 'lanes_start', 'lanes_attempt', 'lanes_stages',
           'lanes_control', 'lanes_accept']


def scipy_tables() -> types.ModuleType:
    """
    Return scipy's DOP853 tables, the module ``scipy/integrate/_ivp/dop853_coefficients.py``.

    Read from its file, without importing the ``scipy.integrate`` package around it: that
    import costs ~0.2-0.5 s (scipy.optimize, linalg, sparse) in every process that imports the
    kernels, the nodes included, and the tables need only numpy (benchmarks/HISTORY.md, "Node
    start-up"). Where the file is not found (another layout of scipy), the ordinary import.
    """
    spec = importlib.util.find_spec('scipy')
    origin = Path(spec.origin) if spec is not None and spec.origin else None
    path = origin.parent / 'integrate' / '_ivp' / 'dop853_coefficients.py' if origin else None
    if path is None or not path.is_file():  # pragma: no cover - scipy's layout since 1.4
        return importlib.import_module('scipy.integrate._ivp.dop853_coefficients')
    located = importlib.util.spec_from_file_location(f'{__name__}._scipy_coefficients', path)
    assert located is not None and located.loader is not None
    tables = importlib.util.module_from_spec(located)
    located.loader.exec_module(tables)
    return tables


_dop = scipy_tables()

_A = np.ascontiguousarray(_dop.A, dtype=np.float64)
_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
_C = np.ascontiguousarray(_dop.C, dtype=np.float64)
_E3 = np.ascontiguousarray(_dop.E3, dtype=np.float64)
_E5 = np.ascontiguousarray(_dop.E5, dtype=np.float64)
_D = np.ascontiguousarray(_dop.D, dtype=np.float64)
_NSTAGES = int(_dop.N_STAGES)          # 12
_NEXT = int(_dop.N_STAGES_EXTENDED)    # 16
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERR_EXP = -1.0 / (7 + 1)              # DOP853: error_estimator_order = 7
#: Rejected step sizes in a row before the step fails. Each rejection divides h by >= 5
#: (_MIN_FACTOR), so a finite h reaches min_step (FAIL.TOO_SMALL) within ~480 rejections even
#: from 1e9 yr; this only bounds the loop by construction.
MAX_REJECTIONS = 1000
# the lanes' last stage is the candidate y_new, f at the step's end (lanes_stages)
assert _NSTAGES + 1 == LANE_STAGES and _C[_NSTAGES] == 1.0
assert np.array_equal(_A[_NSTAGES, :_NSTAGES], _B)


@jit
def _rms(st: Array, o: int, scale_o: int) -> float:
    """Return scipy's norm(x) = ||x|| / sqrt(n) of st[o:o+7] / st[scale_o:scale_o+7]."""
    acc = 0.0
    for i in range(N):
        v = st[o + i] / st[scale_o + i]
        acc += v * v
    root_n: float = N ** 0.5
    return math.sqrt(acc) / root_n


@jit
def start(p: Array, extra: Extra, cfg: Array, st: Array) -> None:
    """Evaluate f at the segment's start and choose the first step (select_initial_step)."""
    if st[ST.STATUS] != STATUS.RUNNING:  # scipy's solver is never built for an empty segment
        return
    rtol = cfg[CF.RTOL]
    atol = cfg[CF.ATOL]
    span = st[ST.TAU_BOUND]
    t0 = st[ST.T0]
    rhs_called(p, extra, t0, st, ST.Y, ST.F)
    st[ST.F_VALID] = 1.0
    # scipy.integrate._ivp.common.select_initial_step, direction = +1, order = 7
    for i in range(N):
        st[ST.SCRATCH + i] = atol + abs(st[ST.Y + i]) * rtol      # scale
    d0 = _rms(st, ST.Y, ST.SCRATCH)
    d1 = _rms(st, ST.F, ST.SCRATCH)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    if span < h0:
        h0 = span
    for i in range(N):
        st[ST.TMP + i] = st[ST.Y + i] + h0 * st[ST.F + i]
    rhs_called(p, extra, t0 + h0, st, ST.TMP, ST.Y_NEW)
    for i in range(N):
        st[ST.Y_NEW + i] = st[ST.Y_NEW + i] - st[ST.F + i]
    d2 = _rms(st, ST.Y_NEW, ST.SCRATCH) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        dm = d2 if d2 > d1 else d1
        h1 = (0.01 / dm) ** (1.0 / 8.0)
    h = 100.0 * h0
    if h1 < h:
        h = h1
    if span < h:
        h = span
    if cfg[CF.MAX_STEP] < h:
        h = cfg[CF.MAX_STEP]
    st[ST.H] = h
    st[ST.NFEV] = 2.0


@jit_inline
def step_start(cfg: Array, st: Array) -> tuple[float, float]:
    """Return (min_step, h_abs) of a step from st[ST.TAU]: scipy's bounds on its size [yr]."""
    t = st[ST.TAU]
    min_step: float = 10.0 * abs(np.nextafter(t, np.inf) - t)
    h_abs = st[ST.H]
    if h_abs > cfg[CF.MAX_STEP]:
        h_abs = cfg[CF.MAX_STEP]
    elif h_abs < min_step:
        h_abs = min_step
    return min_step, h_abs


@jit_inline
def attempt(t: float, t_bound: float, h_abs: float, min_step: float,
            n_rejected: float) -> tuple[float, float, float]:
    """
    Return (FAIL code, t_new, h) of an attempt of size h_abs from local time t [yr].

    The checks before each attempt of scipy's loop (and the bound on rejections), then the
    attempt's end t_new, clipped to t_bound, and its step h = t_new - t.
    """
    if h_abs != h_abs:
        # NaN (a non-finite right-hand side at the segment start): every comparison below
        # is False, so without this the loop neither accepts nor fails, for ever
        return FAIL.STEP_NAN, t, 0.0
    if h_abs < min_step:
        return FAIL.TOO_SMALL, t, 0.0
    if n_rejected >= MAX_REJECTIONS:
        return FAIL.REJECTED, t, 0.0
    t_new = t + h_abs
    if t_new - t_bound > 0:
        t_new = t_bound
    return FAIL.NONE, t_new, t_new - t


@jit_inline
def error_norm(e5: float, e3: float, h: float) -> float:
    """Return DOP853's error norm of a step h from the sums of squares of its two estimates."""
    e5 = math.sqrt(e5) ** 2
    e3 = math.sqrt(e3) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    err: float = abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * N)
    return err


@jit_inline
def control(err: float, h_abs: float, rejected: bool) -> tuple[bool, float]:
    """Return (accepted, the next h_abs) after an attempt of error norm err: scipy's control."""
    if err < 1.0:
        if err == 0.0:
            factor = _MAX_FACTOR
        else:
            factor = _SAFETY * err ** _ERR_EXP
            if not factor < _MAX_FACTOR:
                factor = _MAX_FACTOR
        if rejected and not factor < 1.0:
            factor = 1.0
        return True, h_abs * factor
    factor = _SAFETY * err ** _ERR_EXP
    if not factor > _MIN_FACTOR:
        factor = _MIN_FACTOR
    return False, h_abs * factor


@jit_inline
def accepted(st: Array, t: float, t_new: float, h: float, h_abs: float) -> None:
    """Record an accepted step h from local time t to t_new, the next one h_abs [yr]."""
    st[ST.H_PREV] = h
    st[ST.TAU_OLD] = t
    st[ST.TAU] = t_new
    st[ST.H] = h_abs
    st[ST.DENSE] = 0.0


@jit
def step(p: Array, extra: Extra, cfg: Array, st: Array) -> float:
    """Take a step as scipy's RungeKutta._step_impl with DOP853's rk_step; returns a FAIL code."""
    t = st[ST.TAU]               # scipy's t is the local time
    t_bound = st[ST.TAU_BOUND]
    t0 = st[ST.T0]
    rtol = cfg[CF.RTOL]
    atol = cfg[CF.ATOL]
    min_step, h_abs = step_start(cfg, st)
    rejected = False
    ns = _NSTAGES
    n_rejected = 0.0
    while True:
        code, t_new, h = attempt(t, t_bound, h_abs, min_step, n_rejected)
        if code != FAIL.NONE:
            return code
        h_abs = abs(h)
        for i in range(N):
            st[ST.K + i] = st[ST.F + i]
        for s in range(1, ns):
            for i in range(N):
                acc = 0.0
                for j in range(s):
                    acc += st[ST.K + j * N + i] * _A[s, j]
                st[ST.TMP + i] = st[ST.Y + i] + acc * h
            rhs(p, extra, t0 + (t + _C[s] * h), st, ST.TMP, ST.K + s * N)
        for i in range(N):
            acc = 0.0
            for j in range(ns):
                acc += st[ST.K + j * N + i] * _B[j]
            st[ST.Y_NEW + i] = st[ST.Y + i] + h * acc
        rhs(p, extra, t0 + (t + h), st, ST.Y_NEW, ST.K + ns * N)
        st[ST.NFEV] += float(ns)
        e5 = 0.0
        e3 = 0.0
        for i in range(N):
            ay = abs(st[ST.Y + i])
            an = abs(st[ST.Y_NEW + i])
            scale = atol + (an if an > ay else ay) * rtol
            a5 = 0.0
            a3 = 0.0
            for j in range(ns + 1):
                kj = st[ST.K + j * N + i]
                a5 += kj * _E5[j]
                a3 += kj * _E3[j]
            a5 = a5 / scale
            a3 = a3 / scale
            e5 += a5 * a5
            e3 += a3 * a3
        ok, h_abs = control(error_norm(e5, e3, h), h_abs, rejected)
        if ok:
            break
        rejected = True
        n_rejected += 1.0
    for i in range(N):
        st[ST.Y + i] = st[ST.Y_NEW + i]
        st[ST.F + i] = st[ST.K + ns * N + i]
    accepted(st, t, t_new, h, h_abs)
    return FAIL.NONE


@jit
def dense(p: Array, extra: Extra, cfg: Array, st: Array, tau: float) -> None:
    """Write DOP853's 7th-order interpolant at local time tau of the last step to ST.SCRATCH."""
    tau_old = st[ST.TAU_OLD]
    if st[ST.DENSE] == 0.0:
        h = st[ST.H_PREV]
        for s in range(_NSTAGES + 1, _NEXT):
            for i in range(N):
                acc = 0.0
                for j in range(s):
                    acc += st[ST.K + j * N + i] * _A[s, j]
                st[ST.TMP + i] = st[ST.Y_OLD + i] + acc * h
            rhs_called(p, extra, st[ST.T0] + (tau_old + _C[s] * h), st, ST.TMP, ST.K + s * N)
            st[ST.NFEV] += 1.0
        for i in range(N):
            delta = st[ST.Y + i] - st[ST.Y_OLD + i]
            f_old = st[ST.K + i]
            st[ST.FD + i] = delta
            st[ST.FD + N + i] = h * f_old - delta
            st[ST.FD + 2 * N + i] = 2 * delta - h * (st[ST.F + i] + f_old)
            for r in range(4):
                acc = 0.0
                for j in range(_NEXT):
                    acc += _D[r, j] * st[ST.K + j * N + i]
                st[ST.FD + (3 + r) * N + i] = h * acc
        st[ST.DENSE] = 1.0
    x = (tau - tau_old) / (st[ST.TAU] - tau_old)
    for i in range(N):
        y = 0.0
        for k in range(7):
            y += st[ST.FD + (6 - k) * N + i]
            if k % 2 == 0:
                y *= x
            else:
                y *= 1 - x
        st[ST.SCRATCH + i] = y + st[ST.Y_OLD + i]


# ---------------------------------------------------------------------------------------
# Lanes with their own clocks (kernels.lanes): buffers (LN.SIZE, L), one body a column
# ---------------------------------------------------------------------------------------
@jit_inline
def lanes_start(cfg: Array, st: Array, ln: Array, i: int) -> None:
    """Start a step of lane i from its state st (:func:`step_start`): no attempt rejected."""
    min_step, h_abs = step_start(cfg, st)
    ln[LN.TAU, i] = st[ST.TAU]
    ln[LN.MIN_STEP, i] = min_step
    ln[LN.H_ABS, i] = h_abs
    ln[LN.REJECTED, i] = 0.0


@jit_inline
def lanes_attempt(st: Array, ln: Array, i: int) -> float:
    """Set up lane i's next attempt (:func:`attempt`) and count its evaluations; a FAIL code."""
    code, t_new, h = attempt(ln[LN.TAU, i], st[ST.TAU_BOUND], ln[LN.H_ABS, i],
                             ln[LN.MIN_STEP, i], ln[LN.REJECTED, i])
    if code == FAIL.NONE:
        ln[LN.TAU_NEW, i] = t_new
        ln[LN.H, i] = h
        ln[LN.H_ABS, i] = abs(h)
        st[ST.NFEV] += float(_NSTAGES)
    return code


@jit_inline
def _lanes_sum(ln: Array, acc: int, k: int, coefficients: Array, s: int, m: int) -> None:
    """
    ln[acc] = sum over j < s of ln[k + j N] * coefficients[j] for m lanes, from 0.0 in j's order.

    The single body's ``acc += K[j] * a[j]``, one rounding a term in the same order, four terms
    a pass over the lanes (the sum kept in a register: a quarter of the loads and stores).
    """
    for i in range(m):
        ln[acc, i] = 0.0
    j = 0
    while j + 4 <= s:
        a0 = coefficients[j]
        a1 = coefficients[j + 1]
        a2 = coefficients[j + 2]
        a3 = coefficients[j + 3]
        r = k + j * N
        for i in range(m):
            x = ln[acc, i]
            x += ln[r, i] * a0
            x += ln[r + N, i] * a1
            x += ln[r + 2 * N, i] * a2
            x += ln[r + 3 * N, i] * a3
            ln[acc, i] = x
        j += 4
    while j < s:
        a0 = coefficients[j]
        r = k + j * N
        for i in range(m):
            ln[acc, i] += ln[r, i] * a0
        j += 1


@jit_wide
def lanes_stages(p: Array, extra: Extra, cfg: Array, t0: float, ln: Array, m: int) -> None:
    """
    One attempt of m lanes, each from its own (tau, h): :func:`step`'s stages and error norm.

    Its operations in its order, cut into passes over the lanes (vectorised): each stage's
    argument (the sum over the earlier stages), the stage's times and right-hand side
    (:func:`~.lanes.lanes_rhs`); the 12th stage's argument is the candidate y_new (scipy's
    B is its A[12], C[12] = 1); then the error norm of each lane to ln[LN.ERR].
    """
    ns = _NSTAGES
    for c in range(N):
        for i in range(m):
            ln[LN.K + c, i] = ln[LN.F + c, i]
    for s in range(1, ns + 1):
        out = LN.TMP if s < ns else LN.Y_NEW
        for c in range(N):
            _lanes_sum(ln, LN.ACC, LN.K + c, _A[s], s, m)
            for i in range(m):
                ln[out + c, i] = ln[LN.Y + c, i] + ln[LN.ACC, i] * ln[LN.H, i]
        cs = _C[s]
        for i in range(m):
            ln[LN.T, i] = t0 + (ln[LN.TAU, i] + cs * ln[LN.H, i])
        lanes_rhs(p, extra, ln, out, LN.K + s * N, m)
    rtol = cfg[CF.RTOL]
    atol = cfg[CF.ATOL]
    for i in range(m):
        ln[LN.E5, i] = 0.0
        ln[LN.E3, i] = 0.0
    for c in range(N):
        _lanes_sum(ln, LN.ACC, LN.K + c, _E5, ns + 1, m)
        _lanes_sum(ln, LN.ACC3, LN.K + c, _E3, ns + 1, m)
        for i in range(m):
            ay = abs(ln[LN.Y + c, i])
            an = abs(ln[LN.Y_NEW + c, i])
            scale = atol + (an if an > ay else ay) * rtol
            a5 = ln[LN.ACC, i] / scale
            a3 = ln[LN.ACC3, i] / scale
            ln[LN.E5, i] += a5 * a5
            ln[LN.E3, i] += a3 * a3
    for i in range(m):
        ln[LN.ERR, i] = error_norm(ln[LN.E5, i], ln[LN.E3, i], ln[LN.H, i])


@jit_inline
def lanes_control(ln: Array, i: int) -> bool:
    """Judge lane i's attempt (:func:`control`): True if accepted; the next size to ln."""
    ok, h_abs = control(ln[LN.ERR, i], ln[LN.H_ABS, i], ln[LN.REJECTED, i] > 0.0)
    ln[LN.H_ABS, i] = h_abs
    if not ok:
        ln[LN.REJECTED, i] += 1.0
    return ok


@jit_inline
def lanes_accept(st: Array, ln: Array, i: int) -> None:
    """Move lane i to its accepted attempt's end, as :func:`step` does (its checks passed)."""
    for c in range(N):
        ln[LN.Y_OLD + c, i] = ln[LN.Y + c, i]
        ln[LN.Y + c, i] = ln[LN.Y_NEW + c, i]
        ln[LN.F + c, i] = ln[LN.K + _NSTAGES * N + c, i]
    accepted(st, ln[LN.TAU, i], ln[LN.TAU_NEW, i], ln[LN.H, i], ln[LN.H_ABS, i])

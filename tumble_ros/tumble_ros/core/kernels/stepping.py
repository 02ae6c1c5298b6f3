"""
The stepping loop: one body through one segment, with the Propagator's per-step work.

The method-independent part of every compiled method (``rk4``, ``dop853``, ``splitting``, each
in its own module with ``start``/``step``/``dense``): the segment's set-up in local time, the
failure checks after each step (:mod:`.checks`, as ``integrators.base.Stepper.step``), the
continuous Euler angles (:mod:`.tracking`, as ``Propagator``) and output sampling, so a whole
segment runs without returning to Python. Like the reference steppers (``integrators.base``:
"Local time") every method steps in the segment's local time tau = t - t0 (st[ST.TAU]);
st[ST.T] is the absolute time handed out.

A template: the functions below call the method through the names :func:`method_start`,
:func:`method_step` and :func:`method_dense`, which :mod:`.methods` binds, for each method of
its registry, to that method's module (a copy of these functions per method, compiled with the
method inlined: no run-time dispatch). Called here, unbound, they raise.
"""
from __future__ import annotations

import numpy as np

from tumble_ros.core.compiling.jit import jit, jit_inline
from tumble_ros.core.kernels.checks import collapsed, finite_norm, MIN_STEP_ULPS
from tumble_ros.core.kernels.layout import Array, CF, Extra, FAIL, N, ST, STATUS
from tumble_ros.core.kernels.tracking import (refresh_track, set_track, track_pieces, track_rate,
                                              UNWRAP_STEP, unwrapped_euler)

__all__ = ['seg_init', 'step', 'step_taken', 'dense', 'track_euler', 'emit', 'advance',
           'LOOP_FUNCTIONS']

#: The functions of this module that call the method (directly or through each other): the
#: ones :mod:`.methods` copies per method, in an order where each comes after those it calls.
LOOP_FUNCTIONS = ('seg_init', 'step', 'dense', 'track_update', 'track_euler', 'emit', 'advance')


def method_start(p: Array, extra: Extra, cfg: Array, st: Array) -> None:
    """Start the segment: the method's ``start`` (bound per method by :mod:`.methods`)."""
    raise NotImplementedError('a template: run the loops of kernels.methods.loops(name)')


def method_step(p: Array, extra: Extra, cfg: Array, st: Array) -> float:
    """Take one step, return a FAIL code: the method's ``step`` (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run the loops of kernels.methods.loops(name)')


def method_dense(p: Array, extra: Extra, cfg: Array, st: Array, tau: float) -> None:
    """Dense output at local time tau: the method's ``dense`` (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run the loops of kernels.methods.loops(name)')


@jit
def seg_init(p: Array, extra: Extra, cfg: Array, st: Array, t0: float,
             t_bound: float) -> None:
    """Start a segment [t0, t_bound] from the state already in st[ST.Y] (counters reset)."""
    st[ST.T] = t0
    st[ST.T0] = t0
    st[ST.T_OLD] = t0
    st[ST.T_BOUND] = t_bound
    span = t_bound - t0     # local time tau = t - t0 (integrators.base.Stepper.tau_bound)
    st[ST.TAU] = 0.0
    st[ST.TAU_OLD] = 0.0
    st[ST.TAU_BOUND] = span
    st[ST.N_STEPS] = 0.0
    st[ST.NFEV_DONE] += st[ST.NFEV]   # evaluations of earlier segments (ensembles)
    st[ST.NFEV] = 0.0
    st[ST.FAIL] = FAIL.NONE
    st[ST.F_VALID] = 0.0
    st[ST.DENSE] = 0.0
    st[ST.STATUS] = STATUS.FINISHED if t0 >= t_bound else STATUS.RUNNING
    big = abs(span)
    st[ST.COLLAPSE] = MIN_STEP_ULPS * (np.nextafter(big, np.inf) - big)
    st[ST.WIN_T] = t0
    st[ST.WIN_STEPS] = 0.0
    method_start(p, extra, cfg, st)


@jit_inline
def step(p: Array, extra: Extra, cfg: Array, st: Array) -> bool:
    """
    One step of the segment's method with the checks of ``integrators.base.Stepper.step``.

    Returns True on success; on failure the state is left at the last good step and
    st[ST.FAIL] says why. The work budget (``limits.step_budget``): a step is refused
    (FAIL.BUDGET) when cfg[CF.WINDOW_STEPS] steps were accepted within less than cfg[CF.WINDOW]
    of simulated time; it only counts, so it changes no step of a run it does not stop.
    """
    if st[ST.WIN_STEPS] >= cfg[CF.WINDOW_STEPS]:
        st[ST.STATUS] = STATUS.FAILED
        st[ST.FAIL] = FAIL.BUDGET
        st[ST.FAIL_T] = st[ST.T]
        st[ST.FAIL_DT] = st[ST.T] - st[ST.WIN_T]
        return False
    t_good = st[ST.T]
    tau_good = st[ST.TAU]
    tau_old_good = st[ST.TAU_OLD]
    for i in range(N):
        st[ST.Y_OLD + i] = st[ST.Y + i]
    code = method_step(p, extra, cfg, st)
    if code == FAIL.NONE and not finite_norm(st[ST.Y:ST.Y + N]):
        code = FAIL.NONFINITE
    # (the exact test only for steps near the collapse bound: ST.COLLAPSE >= 16 ulp(tau_good))
    if (code == FAIL.NONE and st[ST.TAU] - tau_good <= st[ST.COLLAPSE]
            and collapsed(tau_good, st[ST.TAU], st[ST.TAU_BOUND])):
        code = FAIL.COLLAPSE
        st[ST.FAIL_DT] = st[ST.TAU] - tau_good
    if code != FAIL.NONE:
        st[ST.T] = t_good
        st[ST.TAU] = tau_good
        st[ST.TAU_OLD] = tau_old_good
        for i in range(N):
            st[ST.Y + i] = st[ST.Y_OLD + i]
        st[ST.STATUS] = STATUS.FAILED
        st[ST.FAIL] = code
        st[ST.FAIL_T] = t_good
        return False
    step_taken(cfg, st, t_good)
    return True


@jit_inline
def step_taken(cfg: Array, st: Array, t_good: float) -> None:
    """
    Count a step from absolute time t_good that passed its checks (st[ST.TAU] its end).

    The absolute time handed out, the work budget's window, the segment's end; the same for
    one body (:func:`step`) and for a block's shared or a lane's own times (``lockstep``,
    ``lanes``).
    """
    st[ST.N_STEPS] += 1.0
    st[ST.T_OLD] = t_good
    # the absolute time handed out (integrators.base.Stepper.absolute)
    st[ST.T] = st[ST.T_BOUND] if st[ST.TAU] >= st[ST.TAU_BOUND] else st[ST.T0] + st[ST.TAU]
    st[ST.WIN_STEPS] += 1.0
    if st[ST.T] - st[ST.WIN_T] >= cfg[CF.WINDOW]:   # a new window (Stepper.step: the same)
        st[ST.WIN_T] = st[ST.T]
        st[ST.WIN_STEPS] = 0.0
    if st[ST.TAU] >= st[ST.TAU_BOUND]:
        st[ST.STATUS] = STATUS.FINISHED


@jit
def dense(p: Array, extra: Extra, cfg: Array, st: Array, t: float) -> None:
    """State at absolute time t in [t_old, t] of the last step, written to st[ST.SCRATCH]."""
    if t == st[ST.T]:
        for i in range(N):
            st[ST.SCRATCH + i] = st[ST.Y + i]
        return
    # local time, kept inside the step (integrators.base.Stepper.state_at)
    tau = min(max(t - st[ST.T0], st[ST.TAU_OLD]), st[ST.TAU])
    method_dense(p, extra, cfg, st, tau)


@jit
def track_update(p: Array, extra: Extra, cfg: Array, st: Array, track: Array,
                 increment: float) -> int:
    """
    Update the track for the last step, whose bound is ``increment`` [rad].

    It first catches up from wherever it was left to the start of the step (see
    :func:`track_euler`). A step of bound at most UNWRAP_STEP (one piece) then becomes the
    budget: the track is within it of the state, as the state is within 1 rad of bound of
    a track set at the step's end, for one conversion instead of two. A longer step is
    followed to its end in pieces (the reference's subdivision). Returns the number of
    dense-output evaluations it took (work, at most MAX_TRACK_PIECES - 1).
    """
    if st[ST.BUDGET] > 0.0:
        set_track(st, ST.Y_OLD, track)
    n = track_pieces(increment)
    if n == 1:
        st[ST.BUDGET] = increment
        return 0
    st[ST.BUDGET] = 0.0
    t = st[ST.T]
    t_old = st[ST.T_OLD]
    h = t - t_old
    for j in range(1, n + 1):
        if j == n:
            o = ST.Y
        else:
            dense(p, extra, cfg, st, t_old + h * j / n)
            o = ST.SCRATCH
        set_track(st, o, track)
    return n - 1


@jit_inline
def track_euler(p: Array, extra: Extra, cfg: Array, st: Array, track: Array) -> int:
    """
    Follow phi, psi continuously through the step just taken (``Propagator._track_euler``).

    The reference updates the track at the end of every step, subdividing steps over which
    phi or psi may turn by more than ~1 rad (bound: ``tracking.track_rate``). Here the bound
    is accumulated over steps and the track is updated only when it would pass 1 rad (to
    the start of the step, the step's bound then the budget; a step of more than 1 rad
    through the step as the reference does, :func:`track_update`), or by
    ``tracking.refresh_track``: the track is then never more than 1 rad of bound away from the
    state, so every unwrapped angle gets the same 2 pi multiple as on the reference path,
    while most steps skip the three atan2 of the conversion. Returns the dense-output
    evaluations taken (work).
    """
    increment = track_rate(st[ST.Y], st[ST.Y + 1], st[ST.Y + 2], st[ST.Y + 3], st[ST.Y + 4],
                           st[ST.Y + 5], st[ST.Y + 6]) * (st[ST.T] - st[ST.T_OLD])
    if st[ST.BUDGET] + increment < UNWRAP_STEP:
        st[ST.BUDGET] += increment
        return 0
    return track_update(p, extra, cfg, st, track, increment)


@jit
def emit(p: Array, extra: Extra, cfg: Array, st: Array, track: Array, t_out: Array,
         y_out: Array, e_out: Array, k: int) -> int:
    """
    Write every output t_out[k:] <= t (state and unwrapped Euler angles); returns the new k.

    Without Euler angles (cfg[CF.EULER] 0) e_out is not written (it may hold no sample).
    """
    n_out = t_out.shape[0]
    while k < n_out and t_out[k] <= st[ST.T]:
        tk = t_out[k]
        if tk == st[ST.T]:
            o = ST.Y
        else:
            dense(p, extra, cfg, st, tk)
            o = ST.SCRATCH
        for i in range(N):
            y_out[k, i] = st[o + i]
        if cfg[CF.EULER] != 0.0:
            phi, psi, theta = unwrapped_euler(st, o, track)
            e_out[k, 0] = phi
            e_out[k, 1] = psi
            e_out[k, 2] = theta
        k += 1
    return k


@jit
def advance(p: Array, extra: Extra, cfg: Array, st: Array, track: Array, t_target: float,
            t_out: Array, y_out: Array, e_out: Array, k: int,
            budget: float) -> tuple[int, int, int]:
    """
    Step the segment until t >= t_target, tracking the Euler angles and writing the outputs.

    It stops early when the segment finishes or fails, or when ``budget`` units of work are
    spent; the outputs written are those passed on the way.

    Work: one unit per step plus one per dense evaluation of the Euler-angle tracking
    (:func:`track_update`), so one call does a bounded amount of work however long the
    interval; the caller calls again to go on (same steps, same results). Returns
    (k, steps, work).
    """
    n_out = t_out.shape[0]
    k = emit(p, extra, cfg, st, track, t_out, y_out, e_out, k)
    steps = 0
    work = 0
    while st[ST.STATUS] == STATUS.RUNNING and st[ST.T] < t_target and work < budget:
        ok = step(p, extra, cfg, st)
        if not ok:
            break
        steps += 1
        work += 1
        if cfg[CF.EULER] != 0.0:
            work += track_euler(p, extra, cfg, st, track)
        if k < n_out and t_out[k] <= st[ST.T]:  # (no call otherwise)
            k = emit(p, extra, cfg, st, track, t_out, y_out, e_out, k)
    refresh_track(st, track)
    return k, steps, work

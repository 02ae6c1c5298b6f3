"""
The lanes loop: a block of bodies sharing their segments, each body with its own clock.

An adaptive method (``dop853``) takes steps that depend on the body, so bodies cannot share
one time grid as in :mod:`.lockstep`. Bodies that share their segments (no per-body impact:
``propagation.ensemble`` decides) are stepped as lanes instead: in each iteration every lane
still running attempts one step from its own (tau, h). The attempt's stages are passes over
the lanes on a structure of arrays (layout :data:`~.layout.LN`: row r = component r of every
lane), which LLVM vectorises, each lane with its own stage times (the Sun's direction per lane
and stage: ``trig``'s sin/cos, vectorised too, as a single body takes them); then, per lane,
its error, accept or reject and next step size, exactly as the single body's step does. The
method's ``lanes_*`` functions (:mod:`.dop853`) are that split of its ``step``: the same
operations in the same order, so every lane keeps the bits of its own run.

Everything else is the single-body code on the lane's own state ``states[b]`` (layout
:data:`~.layout.ST`): the segment's set-up (``seg_init``), the checks after a step
(:mod:`.checks`), the Euler-angle track and the output samples (``track_update``, ``emit``:
the lane's vectors are copied into its state first, :func:`lane_load`), as
``ensemble.body_advance`` runs them. A lane that finished the segment or reached the call's
stop idles (its columns computed and ignored) until the last lane of the block does; then the
next segment. A template like :mod:`.lockstep`: :mod:`.methods` binds ``method_lanes_*`` and
the single-body functions per method.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit, jit_inline, jit_wide
from tumble_ros.core.kernels.checks import collapsed
from tumble_ros.core.kernels.layout import (Array, CF, Extra, FAIL, LANE_STAGES, LN, N, PR, ST,
                                            STATUS)
# (emit, seg_init, track_update: lockstep's unbound single-body functions, bound here too by
# kernels.methods)
from tumble_ros.core.kernels.lockstep import BIGGEST, emit, seg_init, track_update
from tumble_ros.core.kernels.physics import derivatives, plain_torque_given_sun, torque_given_sun
from tumble_ros.core.kernels.stepping import step_taken
from tumble_ros.core.kernels.tracking import (refresh_track, track_pieces, track_rate,
                                              UNWRAP_STEP)
from tumble_ros.core.torques.gravity_gradient import sun_in_orbit_plane_rows

__all__ = ['lanes_rhs', 'lane_load', 'lanes_advance', 'LOOP_FUNCTIONS']

#: The functions :mod:`.methods` copies per method (each after those it calls).
LOOP_FUNCTIONS = ('lane_started', 'step_checked', 'after_step', 'lanes_block', 'lanes_advance')


def method_lanes_start(cfg: Array, st: Array, ln: Array, i: int) -> None:
    """Start a step of lane i (bound per method by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).lanes_advance')


def method_lanes_attempt(st: Array, ln: Array, i: int) -> float:
    """Set up lane i's next attempt, return a FAIL code (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).lanes_advance')


def method_lanes_stages(p: Array, extra: Extra, cfg: Array, t0: float, ln: Array,
                        m: int) -> None:
    """One attempt of m lanes to ln[LN.Y_NEW], its error ln[LN.ERR] (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).lanes_advance')


def method_lanes_control(ln: Array, i: int) -> bool:
    """Judge lane i's attempt: True if accepted (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).lanes_advance')


def method_lanes_accept(st: Array, ln: Array, i: int) -> None:
    """Move lane i to its accepted attempt's end (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).lanes_advance')


@jit_inline
def _omega_rates(p: Array, ln: Array, yo: int, oo: int, i: int, tx: float, ty: float,
                 tz: float) -> None:
    """Write d omega/dt of lane i (state rows yo, torque (tx, ty, tz)) to rows oo .. oo+2."""
    f0, f1, f2, _, _, _, _ = derivatives(p, ln[yo, i], ln[yo + 1, i], ln[yo + 2, i],
                                         ln[yo + 3, i], ln[yo + 4, i], ln[yo + 5, i],
                                         ln[yo + 6, i], tx, ty, tz)
    ln[oo, i] = f0
    ln[oo + 1, i] = f1
    ln[oo + 2, i] = f2


@jit_wide
def lanes_rhs(p: Array, extra: Extra, ln: Array, yo: int, oo: int, m: int) -> None:
    """
    Write f(t, y) of m lanes, t = ln[LN.T], y = ln[yo:yo+7], to ln[oo:oo+7].

    The Sun's direction of each lane at its own time first (``sun_in_orbit_plane_rows``:
    ``trig``'s sin/cos vectorised, the bits a single body gets), then the passes of
    ``rk4.block_rhs`` (vectorised: the torque and d omega/dt, then dq/dt), the Sun's direction
    a row.
    """
    sun_in_orbit_plane_rows(p[PR.ORBIT_RATE], ln[LN.T], ln[LN.SX], ln[LN.SY], m)
    if extra is None and p[PR.HAS_ORBITAL] == 0.0:     # the torque without its branches
        for i in range(m):
            tx, ty, tz = plain_torque_given_sun(p, ln[LN.SX, i], ln[LN.SY, i], ln[yo + 3, i],
                                                ln[yo + 4, i], ln[yo + 5, i], ln[yo + 6, i])
            _omega_rates(p, ln, yo, oo, i, tx, ty, tz)
    else:
        for i in range(m):
            tx, ty, tz = torque_given_sun(p, extra, ln[LN.T, i], ln[LN.SX, i], ln[LN.SY, i],
                                          ln[yo + 3, i], ln[yo + 4, i], ln[yo + 5, i],
                                          ln[yo + 6, i])
            _omega_rates(p, ln, yo, oo, i, tx, ty, tz)
    for i in range(m):
        _, _, _, f3, f4, f5, f6 = derivatives(p, ln[yo, i], ln[yo + 1, i], ln[yo + 2, i],
                                              ln[yo + 3, i], ln[yo + 4, i], ln[yo + 5, i],
                                              ln[yo + 6, i], 0.0, 0.0, 0.0)
        ln[oo + 3, i] = f3
        ln[oo + 4, i] = f4
        ln[oo + 5, i] = f5
        ln[oo + 6, i] = f6


@jit_inline
def lane_load_start(st: Array, ln: Array, i: int) -> None:
    """
    Copy lane i's y at the step's start into its state st: what a track update reads.

    ``stepping.track_update`` of a step followed in one piece converts the step's start only
    (no y, no dense output: no f, no stages); :func:`lane_load` copies the rest before
    anything that reads it (an output sample, a step followed in pieces, the last refresh).
    """
    for c in range(N):
        st[ST.Y_OLD + c] = ln[LN.Y_OLD + c, i]


@jit
def lane_load(st: Array, ln: Array, i: int) -> None:
    """Copy lane i's vectors into its state st: y, y at the step's start, f, the stages."""
    lane_load_start(st, ln, i)
    for c in range(N):
        st[ST.Y + c] = ln[LN.Y + c, i]
        st[ST.F + c] = ln[LN.F + c, i]
    for r in range(LANE_STAGES * N):
        st[ST.K + r] = ln[LN.K + r, i]


@jit
def lane_fail(st: Array, code: float) -> None:
    """Record a failed step of a lane: as ``stepping.step``, its state the last good step's."""
    st[ST.STATUS] = STATUS.FAILED
    st[ST.FAIL] = code
    st[ST.FAIL_T] = st[ST.T]


@jit
def lane_stop(st: Array, ln: Array, track: Array, i: int) -> None:
    """Take lane i out of the iterations: ``stepping.advance``'s end (the track refreshed)."""
    ln[LN.GO, i] = 0.0
    lane_load(st, ln, i)
    refresh_track(st, track)


@jit_inline
def lane_started(cfg: Array, st: Array, ln: Array, track: Array, t_stop: float,
                 i: int) -> None:
    """Start lane i's next step if it goes on (running, before t_stop), else stop it."""
    if st[ST.STATUS] != STATUS.RUNNING or st[ST.T] >= t_stop:
        lane_stop(st, ln, track, i)
    elif st[ST.WIN_STEPS] >= cfg[CF.WINDOW_STEPS]:    # stepping.step's work budget
        st[ST.FAIL_DT] = st[ST.T] - st[ST.WIN_T]
        lane_fail(st, FAIL.BUDGET)
        lane_stop(st, ln, track, i)
    else:
        method_lanes_start(cfg, st, ln, i)
        ln[LN.GO, i] = 1.0


@jit_inline
def step_checked(cfg: Array, st: Array, ln: Array, i: int) -> None:
    """
    Lane i's accepted attempt through ``stepping.step``'s checks: on to its end, or failed.

    The finite check (``checks.finite_norm``'s sum) and the collapse check on the attempt's
    end before the lane moves there: a failed lane stays at its last good step.
    """
    acc = 0.0
    for c in range(N):
        acc += ln[LN.Y_NEW + c, i] * ln[LN.Y_NEW + c, i]
    tau_good = st[ST.TAU]
    tau = ln[LN.TAU_NEW, i]
    if not acc <= BIGGEST:
        lane_fail(st, FAIL.NONFINITE)
    elif tau - tau_good <= st[ST.COLLAPSE] and collapsed(tau_good, tau, st[ST.TAU_BOUND]):
        st[ST.FAIL_DT] = tau - tau_good
        lane_fail(st, FAIL.COLLAPSE)
    else:
        t_good = st[ST.T]
        method_lanes_accept(st, ln, i)
        step_taken(cfg, st, t_good)


@jit_inline
def after_step(p: Array, extra: Extra, cfg: Array, st: Array, ln: Array, track: Array,
               t_out: Array, y_out: Array, e_out: Array, k_out: npt.NDArray[np.int64], b: int,
               i: int) -> None:
    """``stepping.advance`` after a step of lane i (body b): the track, then the outputs."""
    loaded = False
    if cfg[CF.EULER] != 0.0:     # stepping.track_euler
        increment = track_rate(ln[LN.Y, i], ln[LN.Y + 1, i], ln[LN.Y + 2, i], ln[LN.Y + 3, i],
                               ln[LN.Y + 4, i], ln[LN.Y + 5, i], ln[LN.Y + 6, i]) * (
                                   st[ST.T] - st[ST.T_OLD])
        if st[ST.BUDGET] + increment < UNWRAP_STEP:
            st[ST.BUDGET] += increment
        else:
            if track_pieces(increment) > 1:     # dense outputs inside the step: all of it
                lane_load(st, ln, i)
                loaded = True
            else:                               # the step's start only
                lane_load_start(st, ln, i)
            track_update(p, extra, cfg, st, track, increment)
    k = k_out[b]
    if k < t_out.shape[0] and t_out[k] <= st[ST.T]:
        if not loaded:
            lane_load(st, ln, i)
        k_out[b] = emit(p, extra, cfg, st, track, t_out, y_out, e_out, k)


@jit_wide
def lanes_block(extra: Extra, cfg: Array, probs: Array, seg_t: Array,
                seg_ptr: npt.NDArray[np.int64], cur: npt.NDArray[np.int64], states: Array,
                tracks: Array, t_stop: float, t_out: Array, y_out: Array, e_out: Array,
                k_out: npt.NDArray[np.int64], steps_out: npt.NDArray[np.int64], a: int, m: int,
                ln: Array) -> None:
    """
    Advance the lanes of bodies a .. a+m-1 (sharing their segments) until t >= t_stop.

    ``ensemble.body_advance`` for each of them (the same calls at the same points of its own
    steps). Their y and f are in their states between calls; ln is the call's scratch.
    """
    n_out = t_out.shape[0]
    for i in range(m):
        st = states[a + i]
        for c in range(N):
            ln[LN.Y + c, i] = st[ST.Y + c]
            ln[LN.F + c, i] = st[ST.F + c]
            ln[LN.Y_OLD + c, i] = st[ST.Y_OLD + c]
    while True:
        alive = 0
        finished = 0
        going = 0
        r = -1                 # a lane still alive: the segment (the same for all) is its
        for i in range(m):     # the top of body_advance: outputs, then on or not
            b = a + i
            st = states[b]
            if st[ST.STATUS] == STATUS.FAILED:
                continue
            alive += 1
            r = b if r < 0 else r
            k = k_out[b]
            if k < n_out and t_out[k] <= st[ST.T]:
                lane_load(st, ln, i)
                k_out[b] = emit(probs[cur[b]], extra, cfg, st, tracks[b], t_out, y_out[b],
                                e_out[b], k)
            if st[ST.T] >= t_stop:
                continue
            if st[ST.STATUS] == STATUS.FINISHED:
                finished += 1
            else:
                going += 1
        if going == 0:
            if alive == 0 or finished < alive or cur[r] + 1 >= seg_ptr[r + 1]:
                break
            for i in range(m):     # every lane finished the segment: the next one
                b = a + i
                st = states[b]
                if st[ST.STATUS] == STATUS.FAILED:
                    continue
                cur[b] += 1
                seg_init(probs[cur[b]], extra, cfg, st, st[ST.T], seg_t[cur[b], 1])
                for c in range(N):
                    ln[LN.F + c, i] = st[ST.F + c]
            continue
        p = probs[cur[r]]
        t0 = states[r, ST.T0]
        for i in range(m):
            st = states[a + i]
            ln[LN.GO, i] = 0.0
            if st[ST.STATUS] != STATUS.FAILED:
                lane_started(cfg, st, ln, tracks[a + i], t_stop, i)
        while going > 0:
            going = 0
            for i in range(m):
                if ln[LN.GO, i] == 0.0:
                    continue
                st = states[a + i]
                code = method_lanes_attempt(st, ln, i)
                if code != FAIL.NONE:
                    lane_fail(st, code)
                    lane_stop(st, ln, tracks[a + i], i)
                else:
                    going += 1
            if going == 0:
                break
            method_lanes_stages(p, extra, cfg, t0, ln, m)
            for i in range(m):
                if ln[LN.GO, i] == 0.0 or not method_lanes_control(ln, i):
                    continue
                b = a + i
                st = states[b]
                step_checked(cfg, st, ln, i)
                if st[ST.STATUS] != STATUS.FAILED:
                    steps_out[b] += 1
                    after_step(p, extra, cfg, st, ln, tracks[b], t_out, y_out[b], e_out[b],
                               k_out, b, i)
                lane_started(cfg, st, ln, tracks[b], t_stop, i)
    for i in range(m):
        st = states[a + i]
        for c in range(N):
            st[ST.Y + c] = ln[LN.Y + c, i]
            st[ST.F + c] = ln[LN.F + c, i]
            st[ST.Y_OLD + c] = ln[LN.Y_OLD + c, i]


@jit_wide
def lanes_advance(extra: Extra, cfg: Array, probs: Array, seg_t: Array,
                  seg_ptr: npt.NDArray[np.int64], cur: npt.NDArray[np.int64], states: Array,
                  tracks: Array, t_stop: float, t_out: Array, y_out: Array, e_out: Array,
                  k_out: npt.NDArray[np.int64], steps_out: npt.NDArray[np.int64], b0: int,
                  b1: int, ln: Array) -> None:
    """
    ``ensemble.ensemble_advance`` for bodies b0 .. b1-1 sharing their segments, as lanes.

    Blocks of L lanes (ln: a scratch (LN.SIZE, L)), one after the other (releases the GIL).
    """
    width = ln.shape[1]
    for a in range(b0, b1, width):
        lanes_block(extra, cfg, probs, seg_t, seg_ptr, cur, states, tracks, t_stop, t_out,
                    y_out, e_out, k_out, steps_out, a, min(width, b1 - a), ln)

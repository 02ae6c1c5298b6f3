"""
The lockstep loop: a block of bodies sharing one time grid, stepped together.

When every body of an ensemble has the same segments and a fixed-step method takes the same
steps on them (no per-body impact, no pulse: ``propagation.ensemble`` decides), the times of
every step and stage are the same for all bodies. A block of B bodies is then stepped together:
the shared part of a step (its times, the checks of :func:`~.stepping.step` on the local time,
the Sun's direction at each stage) is computed once per step, and the per-body part
(``method_block_step`` of the method's module, e.g. :func:`~.splitting.block_step`) runs as
loops over the block's bodies on a structure of arrays, row r of a buffer ``(BK.SIZE, B)`` the
component r of all B bodies (layout :data:`~.layout.BK`): loops LLVM vectorises across bodies.

Each body gets exactly the bits of its own run (``stepping.advance`` on one body): the same
operations in the same order, vector lanes or not (no FMA contraction: numba does not allow it
without ``fastmath``). The outputs and the Euler track are the single-body functions' too,
on the block's columns: a sample is written for the whole block at once (:func:`block_emit`:
the method's ``block_dense`` for a sample inside a step, then ``tracking.euler_of``'s
conversion of every body in one vectorised pass, :func:`block_euler`, its rare rest (the
band's ``hypot``) and the unwrapping body by body: ``stepping.emit``'s operations), and a
track update without dense output takes ``tracking.follow`` on the columns
(``stepping.track_update``'s phi and psi; theta, which no lockstep output reads, skipped), the
bodies due in a step gathered and converted in one vectorised pass (``trig.atan2``, which the
single-body track takes too). The rare rest (a method without ``block_dense``, a track update
in pieces) calls the single-body functions (:func:`~.stepping.emit`,
:func:`~.stepping.track_update`) on a scratch state ``bst`` (layout :data:`~.layout.ST`) into
which the method's ``block_load`` copies the body (``bst`` also holds the block's shared times
and counters, as a single body's state holds them). A template like :mod:`.stepping`:
:mod:`.methods` binds ``method_block_*`` per method.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit, jit_inline, jit_wide
from tumble_ros.core.kernels.checks import collapsed
from tumble_ros.core.kernels.layout import (Array, BB, BK, BT, CF, Extra, FAIL, LI, N, ST,
                                            STATUS)
from tumble_ros.core.kernels.stepping import step_taken
from tumble_ros.core.kernels.tracking import (euler_finish, euler_parts, follow, settle,
                                              track_angles, TRACK_BAND, track_pieces,
                                              track_rate, UNWRAP_STEP)

__all__ = ['block_init', 'block_advance', 'no_block_dense', 'LOOP_FUNCTIONS', 'BIGGEST']

#: The functions :mod:`.methods` copies per method (each after those it calls).
LOOP_FUNCTIONS = ('load_body', 'store_body', 'block_seg_init', 'block_emit', 'block_step',
                  'block_track', 'block_init', 'block_advance')

#: The largest finite float: |y|^2 <= BIGGEST is finite_norm's test (NaN compares False).
BIGGEST = float(np.finfo(np.float64).max)


def method_block_start(p: Array, extra: Extra, cfg: Array, bst: Array, cur: Array,
                       m: int) -> None:
    """Run the per-body part of the method's ``start`` (bound per method by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


def method_block_step(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, new: Array,
                      tmp: Array, bodies: Array, m: int) -> None:
    """Step m bodies from buffer old to new (bound per method by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


def method_block_dense(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, out: Array,
                       tmp: Array, tau: float, m: int) -> bool:
    """Dense output of m bodies at local time tau to ``out``; False if none (see methods)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


@jit
def no_block_dense(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, out: Array,
                   tmp: Array, tau: float, m: int) -> bool:
    """``method_block_dense`` of a method without a block dense output: False (per body)."""
    return False


def method_block_load(bst: Array, old: Array, new: Array, i: int) -> None:
    """Copy body i into bst for the single-body functions (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


def method_block_store(bst: Array, new: Array, i: int) -> None:
    """Copy back what a single-body function computed for body i (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


@jit
def load_body(bst: Array, old: Array, cur: Array, bodies: Array, i: int) -> float:
    """Copy body i into bst before a single-body call; return bst's evaluation count."""
    method_block_load(bst, old, cur, i)
    bst[ST.BUDGET] = bodies[BB.BUDGET, i]
    bst[ST.F_VALID] = bodies[BB.F_VALID, i]
    nfev: float = bst[ST.NFEV]
    return nfev


@jit
def store_body(bst: Array, cur: Array, bodies: Array, i: int, nfev: float) -> None:
    """After a single-body call on body i: keep its track budget, its F, its evaluations."""
    method_block_store(bst, cur, i)
    bodies[BB.BUDGET, i] = bst[ST.BUDGET]
    bodies[BB.F_VALID, i] = bst[ST.F_VALID]
    bodies[BB.NFEV_ADJ, i] += bst[ST.NFEV] - nfev
    bst[ST.NFEV] = nfev
    bst[ST.F_VALID] = 0.0


def seg_init(p: Array, extra: Extra, cfg: Array, st: Array, t0: float, t_bound: float) -> None:
    """Start a segment: the single-body ``stepping.seg_init`` (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


def emit(p: Array, extra: Extra, cfg: Array, st: Array, track: Array, t_out: Array,
         y_out: Array, e_out: Array, k: int) -> int:
    """Write outputs: the single-body ``stepping.emit`` (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


def track_update(p: Array, extra: Extra, cfg: Array, st: Array, track: Array,
                 increment: float) -> int:
    """Update the track: the single-body ``stepping.track_update`` (bound by :mod:`.methods`)."""
    raise NotImplementedError('a template: run kernels.methods.loops(name).block_advance')


@jit_wide
def block_seg_init(p: Array, extra: Extra, cfg: Array, bst: Array, soa: Array, bodies: Array,
                   counters: npt.NDArray[np.int64], t0: float, t_bound: float, m: int) -> None:
    """
    Start a segment [t0, t_bound] for the block: ``seg_init`` on the shared times, per body.

    The shared part is the single body's ``seg_init`` on bst (holding body 0: the step count
    of a segment without pulse does not depend on the body); the per-body part is the method's
    ``block_start`` on the current buffer, copied to the other one.
    """
    cur = soa[counters[LI.PAR]]
    other = soa[1 - counters[LI.PAR]]
    for c in range(N):
        bst[ST.Y + c] = cur[BK.Y + c, 0]
    seg_init(p, extra, cfg, bst, t0, t_bound)
    method_block_start(p, extra, cfg, bst, cur, m)
    for i in range(m):
        bodies[BB.F_VALID, i] = 0.0
    for r in range(BK.SIZE):
        for i in range(m):
            other[r, i] = cur[r, i]


@jit_wide
def block_euler(src: Array, tmp: Array, m: int) -> None:
    """
    ``tracking.euler_parts`` of the quaternions of m bodies (rows BK.Y + 3 .. of src).

    To tmp[BT.EULER:BT.EULER + 4]: phi, psi, theta [rad] and 1.0 if they hold (0.0: the band,
    ``tracking.euler_band``). One pass LLVM vectorises (no call, no branch). No method's
    function in it: compiled once for every method (not in :data:`LOOP_FUNCTIONS`).
    """
    for i in range(m):
        phi, psi, theta, plain = euler_parts(src[BK.Y + 3, i], src[BK.Y + 4, i],
                                             src[BK.Y + 5, i], src[BK.Y + 6, i])
        tmp[BT.EULER, i] = phi
        tmp[BT.EULER + 1, i] = psi
        tmp[BT.EULER + 2, i] = theta
        tmp[BT.EULER + 3, i] = plain


@jit_wide
def block_emit(p: Array, extra: Extra, cfg: Array, bst: Array, soa: Array, tmp: Array,
               bodies: Array, counters: npt.NDArray[np.int64], tracks: Array, t_out: Array,
               y_out: Array, e_out: Array, body0: int, m: int) -> None:
    """
    Write the outputs t_out[k:] <= t of every running body: ``stepping.emit``'s bits.

    A block at a time: the state at t_out[k] (the current buffer, or the method's
    ``block_dense`` of every body into a scratch buffer), the Euler angles of every body in one
    vectorised pass (:func:`block_euler`), then each running body's row of y_out and its Euler
    angles (``tracking.euler_finish``: the band's ``hypot`` if needed, unwrapped towards its
    track: :func:`~.tracking.euler_of`'s bits). A method without ``block_dense`` (rk4) takes
    the single-body ``emit`` per body for a sample inside a step.
    """
    k = counters[LI.K]
    n_out = t_out.shape[0]
    if k >= n_out or t_out[k] > bst[ST.T]:
        return
    cur = soa[counters[LI.PAR]]
    old = soa[1 - counters[LI.PAR]]
    out = tmp[BT.DENSE:BT.DENSE + BK.TORQUE + 3]   # (rows Y, PI, TORQUE as BK)
    euler = cfg[CF.EULER] != 0.0
    while k < n_out and t_out[k] <= bst[ST.T]:
        tk = t_out[k]
        src = cur
        if tk != bst[ST.T]:
            # stepping.dense's local time, kept inside the step
            tau = min(max(tk - bst[ST.T0], bst[ST.TAU_OLD]), bst[ST.TAU])
            if not method_block_dense(p, extra, cfg, bst, old, out, tmp, tau, m):
                break
            src = out
        if euler:
            block_euler(src, tmp, m)
        for i in range(m):
            if bodies[BB.FAILED, i] != 0.0:
                continue
            row = y_out[body0 + i, k]
            for c in range(N):
                row[c] = src[BK.Y + c, i]
            if euler:   # (tracking.euler_of: its second half, the band's hypot if needed)
                track = tracks[i]
                phi, psi, theta = euler_finish(
                    tmp[BT.EULER, i], tmp[BT.EULER + 1, i], tmp[BT.EULER + 2, i],
                    tmp[BT.EULER + 3, i], src[BK.Y + 3, i], src[BK.Y + 4, i],
                    src[BK.Y + 5, i], src[BK.Y + 6, i], track[0], track[1])
                e_row = e_out[body0 + i, k]
                e_row[0] = phi
                e_row[1] = psi
                e_row[2] = theta
        k += 1
    if k < n_out and t_out[k] <= bst[ST.T]:   # no block dense output: per body
        k_new = k
        for i in range(m):
            if bodies[BB.FAILED, i] != 0.0:
                continue
            nfev = load_body(bst, old, cur, bodies, i)
            k_new = emit(p, extra, cfg, bst, tracks[i], t_out, y_out[body0 + i],
                         e_out[body0 + i], k)
            store_body(bst, cur, bodies, i, nfev)
        k = k_new
    counters[LI.K] = k


@jit_wide
def _fail_bodies(bst: Array, old: Array, new: Array, tmp: Array, bodies: Array,
                 counters: npt.NDArray[np.int64], code: float, t_good: float, m: int) -> int:
    """
    Fail the running bodies whose step failed (all of them if ``code`` is a shared failure).

    A failed body's state goes back to its last good step (``new`` = ``old``) and its
    counters are kept in ``bodies``; returns how many bodies are still running.
    """
    alive = 0
    for i in range(m):
        if bodies[BB.FAILED, i] != 0.0:
            continue
        if code == FAIL.NONE and tmp[BT.ACC, i] <= BIGGEST:
            alive += 1
            continue
        bodies[BB.FAILED, i] = 1.0
        bodies[BB.FAIL, i] = FAIL.NONFINITE if code == FAIL.NONE else code
        bodies[BB.FAIL_T, i] = t_good
        bodies[BB.FAIL_DT, i] = bst[ST.FAIL_DT] if code == FAIL.COLLAPSE else 0.0
        bodies[BB.STEPS, i] = counters[LI.STEPS]
        bodies[BB.NFEV, i] = bst[ST.NFEV_DONE] + bst[ST.NFEV] + bodies[BB.NFEV_ADJ, i]
        bodies[BB.K, i] = counters[LI.K]
        for r in range(BK.SIZE):
            new[r, i] = old[r, i]
    return alive


@jit_wide
def block_step(p: Array, extra: Extra, cfg: Array, bst: Array, soa: Array, tmp: Array,
               bodies: Array, counters: npt.NDArray[np.int64], m: int) -> bool:
    """
    One step of the block with the checks of ``stepping.step``; False when no body is left.

    The shared checks (work budget, collapse of the local time) fail every running body; the
    finite check fails a body alone: its state stays at its last good step (both buffers) and
    its counters are kept in ``bodies``. Swaps the buffers.
    """
    par = counters[LI.PAR]
    old = soa[par]
    new = soa[1 - par]
    t_good = bst[ST.T]
    tau_good = bst[ST.TAU]
    tau_old_good = bst[ST.TAU_OLD]
    code = FAIL.NONE
    if bst[ST.WIN_STEPS] >= cfg[CF.WINDOW_STEPS]:
        code = FAIL.BUDGET
        bst[ST.FAIL_DT] = bst[ST.T] - bst[ST.WIN_T]
    else:
        method_block_step(p, extra, cfg, bst, old, new, tmp, bodies, m)
        if (bst[ST.TAU] - tau_good <= bst[ST.COLLAPSE]
                and collapsed(tau_good, bst[ST.TAU], bst[ST.TAU_BOUND])):
            code = FAIL.COLLAPSE
            bst[ST.FAIL_DT] = bst[ST.TAU] - tau_good
    alive = 0
    running = 0
    if code == FAIL.NONE:
        for i in range(m):   # finite_norm of every body's y, as stepping.step (vectorised)
            acc = 0.0
            for c in range(N):
                acc += new[BK.Y + c, i] * new[BK.Y + c, i]
            tmp[BT.ACC, i] = acc
            going = bodies[BB.FAILED, i] == 0.0
            running += 1 if going else 0
            alive += 1 if going and acc <= BIGGEST else 0
    if code != FAIL.NONE or alive < running:   # a body failed: the rare per-body pass
        alive = _fail_bodies(bst, old, new, tmp, bodies, counters, code, t_good, m)
    if alive == 0:
        bst[ST.T] = t_good
        bst[ST.TAU] = tau_good
        bst[ST.TAU_OLD] = tau_old_good
        bst[ST.STATUS] = STATUS.FAILED
        bst[ST.FAIL] = code
        bst[ST.FAIL_T] = t_good
        return False
    step_taken(cfg, bst, t_good)
    counters[LI.PAR] = 1 - par
    counters[LI.STEPS] += 1
    return True


@jit_inline
def _settle_gathered(tmp: Array, angles: int, quaternion: int, j: int, track: Array) -> None:
    """``tracking.follow`` of gathered body j from its converted angles (rows ``angles``)."""
    if tmp[angles + 2, j] == TRACK_BAND:   # (rare: the band's hypot, by follow itself)
        follow(tmp[quaternion, j], tmp[quaternion + 1, j], tmp[quaternion + 2, j],
               tmp[quaternion + 3, j], track)
    else:
        settle(tmp[angles, j], tmp[angles + 1, j], tmp[angles + 2, j], track)


@jit_wide
def block_track(p: Array, extra: Extra, cfg: Array, bst: Array, soa: Array, tmp: Array,
                bodies: Array, counters: npt.NDArray[np.int64], tracks: Array, m: int) -> None:
    """
    ``stepping.track_euler`` for every running body: the bound vectorised, updates rare.

    Each body keeps its own schedule (its updates at the steps of its single run: updating a
    block's bodies together would move them, and below theta ~ 0.1 the bound does not bound
    phi and psi, so the 2 pi multiples could differ). An update of a step in one piece runs on
    the columns (``stepping.track_update``: ``tracking.follow`` of the step's start, the
    step's bound then the budget): the bodies due whose track was left before the step are
    gathered (rows ``BT.TRACK_*``), their angles converted in one vectorised pass
    (``tracking.track_angles``), then each track unwrapped in turn (``tracking.settle``).
    """
    if cfg[CF.EULER] == 0.0:
        return
    cur = soa[counters[LI.PAR]]
    old = soa[1 - counters[LI.PAR]]
    dt = bst[ST.T] - bst[ST.T_OLD]
    due = 0
    for i in range(m):
        inc = track_rate(cur[BK.Y, i], cur[BK.Y + 1, i], cur[BK.Y + 2, i], cur[BK.Y + 3, i],
                         cur[BK.Y + 4, i], cur[BK.Y + 5, i], cur[BK.Y + 6, i]) * dt
        total = bodies[BB.BUDGET, i] + inc
        late = total >= UNWRAP_STEP
        tmp[BT.INC, i] = inc if late else -1.0
        bodies[BB.BUDGET, i] = bodies[BB.BUDGET, i] if late else total
        due += 1 if late else 0
    if due == 0:
        return
    n = 0
    for i in range(m):
        inc = tmp[BT.INC, i]
        if inc < 0.0 or bodies[BB.FAILED, i] != 0.0:
            continue
        if track_pieces(inc) == 1:   # track_update's step in one piece: gathered
            if bodies[BB.BUDGET, i] > 0.0:    # (the catch-up to the step's start)
                tmp[BT.TRACK_I, n] = i
                for c in range(4):
                    tmp[BT.TRACK_Q_OLD + c, n] = old[BK.Y + 3 + c, i]
                n += 1
            bodies[BB.BUDGET, i] = inc
        else:
            nfev = load_body(bst, old, cur, bodies, i)
            track_update(p, extra, cfg, bst, tracks[i], inc)
            store_body(bst, cur, bodies, i, nfev)
    for j in range(n):   # (vectorised)
        phi, psi, verdict = track_angles(tmp[BT.TRACK_Q_OLD, j], tmp[BT.TRACK_Q_OLD + 1, j],
                                         tmp[BT.TRACK_Q_OLD + 2, j], tmp[BT.TRACK_Q_OLD + 3, j])
        tmp[BT.TRACK_OLD, j] = phi
        tmp[BT.TRACK_OLD + 1, j] = psi
        tmp[BT.TRACK_OLD + 2, j] = verdict
    for j in range(n):   # tracking.follow's unwrapping
        _settle_gathered(tmp, BT.TRACK_OLD, BT.TRACK_Q_OLD, j, tracks[int(tmp[BT.TRACK_I, j])])


@jit_wide
def block_refresh(soa: Array, bodies: Array, counters: npt.NDArray[np.int64], tracks: Array,
                  m: int) -> None:
    """
    ``tracking.refresh_track`` for every running body (``tracking.follow`` on the columns).

    No method's function in it: compiled once for every method (not in :data:`LOOP_FUNCTIONS`).
    """
    cur = soa[counters[LI.PAR]]
    for i in range(m):
        if bodies[BB.BUDGET, i] > 0.0 and bodies[BB.FAILED, i] == 0.0:   # (on the columns)
            follow(cur[BK.Y + 3, i], cur[BK.Y + 4, i], cur[BK.Y + 5, i], cur[BK.Y + 6, i],
                   tracks[i])
            bodies[BB.BUDGET, i] = 0.0


@jit_wide
def block_init(extra: Extra, cfg: Array, probs: Array, seg_t: Array, soa: Array,
               bodies: Array, counters: npt.NDArray[np.int64], bst: Array, m: int) -> None:
    """Start the first segment of a block whose current buffer holds every body's y0."""
    block_seg_init(probs[0], extra, cfg, bst, soa, bodies, counters, seg_t[0, 0], seg_t[0, 1],
                   m)


@jit_wide
def block_advance(extra: Extra, cfg: Array, probs: Array, seg_t: Array, soa: Array,
                  tmp: Array, bodies: Array, counters: npt.NDArray[np.int64], bst: Array,
                  tracks: Array, t_stop: float, t_out: Array, y_out: Array, e_out: Array,
                  body0: int, m: int) -> None:
    """
    Advance a block of m bodies through the shared segments until t >= t_stop.

    ``ensemble.body_advance`` and ``stepping.advance`` for all of them at once: body i of the
    block is body ``body0 + i`` of the outputs y_out, e_out and column i of the block's arrays
    soa (2, BK.SIZE, B), tmp (BT.SIZE, B), bodies (BB.SIZE, B), tracks (B, 3). Releases the GIL.
    """
    n_seg = probs.shape[0]
    n_out = t_out.shape[0]
    while True:
        cur = counters[LI.SEG]
        p = probs[cur]
        block_emit(p, extra, cfg, bst, soa, tmp, bodies, counters, tracks, t_out, y_out, e_out,
                   body0, m)
        if bst[ST.T] >= t_stop or bst[ST.STATUS] == STATUS.FAILED:
            break
        if bst[ST.STATUS] == STATUS.FINISHED:
            if cur + 1 >= n_seg:
                break
            counters[LI.SEG] = cur + 1
            block_seg_init(probs[cur + 1], extra, cfg, bst, soa, bodies, counters, bst[ST.T],
                           seg_t[cur + 1, 1], m)
            continue
        while bst[ST.STATUS] == STATUS.RUNNING and bst[ST.T] < t_stop:
            if not block_step(p, extra, cfg, bst, soa, tmp, bodies, counters, m):
                break
            block_track(p, extra, cfg, bst, soa, tmp, bodies, counters, tracks, m)
            k = counters[LI.K]
            if k < n_out and t_out[k] <= bst[ST.T]:
                block_emit(p, extra, cfg, bst, soa, tmp, bodies, counters, tracks, t_out,
                           y_out, e_out, body0, m)
        block_refresh(soa, bodies, counters, tracks, m)

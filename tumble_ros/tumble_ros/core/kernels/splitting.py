"""
Compiled ``splitting*``: the Lie-Poisson splitting methods (``integrators.splitting``).

Kick (the total torque, attitude frozen) - free flow (:func:`~.physics.free_flow`) - kick,
composed with the coefficients gamma_j of the config; momentum pi = I w carried in
ST.PI. Each function works on one body's state ``st``.
"""
from __future__ import annotations

import math

import numpy as np

from tumble_ros.core.compiling.jit import called, jit, jit_inline, jit_wide
from tumble_ros.core.kernels.layout import Array, BK, BT, CF, Extra, FAIL, N, PR, ST
from tumble_ros.core.kernels.physics import (axis_turn, body_torque, flow_pieces, free_flow,
                                             pi_turn, plain_torque_given_sun,
                                             torque_given_sun)
from tumble_ros.core.kernels.rk4 import step_count
from tumble_ros.core.torques.gravity_gradient import sun_in_orbit_plane
from tumble_ros.core.trig import sin_cos_rows

__all__ = ['flow', 'flow_called', 'pulse_step_count', 'start', 'step', 'dense',
           'MAX_PULSE_SUBSTEPS', 'block_start', 'block_step', 'block_dense', 'block_flow',
           'block_load', 'block_store', 'block_sincos',
           'block_axis']

#: Most steps the pulse rule (:func:`pulse_step_count`) adds to a segment's own count.
MAX_PULSE_SUBSTEPS = 1000


@jit_inline
def flow(p: Array, extra: Extra, cfg: Array, st: Array, yo: int, po: int, to: int, t0: float,
         s0: float, h: float, yd: int, pd: int, td: int) -> None:
    """
    Take one composed splitting step of length h from local time s0 (absolute time t0 + s0).

    From attitude st[yo+3:yo+7], angular momentum st[po:po+3], cached torque st[to:to+3];
    result to st[yd:yd+7] (w and q), st[pd:pd+3] (momentum) and st[td:td+3] (torque at the
    end).
    """
    px = st[po]
    py = st[po + 1]
    pz = st[po + 2]
    q0 = st[yo + 3]
    q1 = st[yo + 4]
    q2 = st[yo + 5]
    q3 = st[yo + 6]
    tx = st[to]
    ty = st[to + 1]
    tz = st[to + 2]
    for j in range(int(cfg[CF.N_STAGES])):
        a = cfg[CF.GAMMA + j] * h
        half = 0.5 * a
        px += half * tx
        py += half * ty
        pz += half * tz
        px, py, pz, q0, q1, q2, q3 = free_flow(p, a, px, py, pz, q0, q1, q2, q3)
        tx, ty, tz = body_torque(p, extra, t0 + (s0 + cfg[CF.CUM + j] * h), q0, q1, q2, q3)
        px += half * tx
        py += half * ty
        pz += half * tz
    st[pd] = px
    st[pd + 1] = py
    st[pd + 2] = pz
    st[yd] = px * p[PR.INV_INERTIA]        # (not / I: a multiply vectorises 4x cheaper)
    st[yd + 1] = py * p[PR.INV_INERTIA + 1]
    st[yd + 2] = pz * p[PR.INV_INERTIA + 2]
    st[yd + 3] = q0
    st[yd + 4] = q1
    st[yd + 5] = q2
    st[yd + 6] = q3
    st[td] = tx
    st[td + 1] = ty
    st[td + 2] = tz


#: :func:`flow` compiled on its own (dense output, the reference stepper).
flow_called = called(flow)


@jit
def pulse_step_count(p: Array, span: float, step: float, order: float, wx: float, wy: float,
                     wz: float) -> float:
    """
    Return the number of equal steps (a float) of a splitting method on a segment.

    ``span`` is the segment's length, ``step`` the requested step, ``order`` the method's order
    p and (wx, wy, wz) the angular velocity at its start; ``p`` holds the segment's pulse
    torques. Outside pulses it is n = ceil(span / step), as for rk4.

    A pulse segment is integrated with sub-steps a = step * min(1, rho): Strang's local error is
    a^3 (1/12 [B, [B, A]] - 1/24 [A, [A, B]]) (BCH; A the kick, B the free flow). With the
    pulse torque b in the kick, [B, [B, A]] ~ Lambda^2 |b| (the free rotation, rate Lambda,
    acting twice on the kick) and [A, [A, B]] = 2 b x I^-1 b <= 2 Delta |b|^2 (pulse x pulse:
    the kick acting twice on the free flow, Delta = 1/I_min - 1/I_max), so per unit time the
    pulse makes an error ~ a^2 |b| (Lambda^2 + Delta |b|) / 12, ~1e6 times that of the tidal
    kick. A regular step h at the body's rate makes ~ h^2 Lambda^3 P / 12 per unit time
    (relative error (Lambda h)^2 / 12 per radian, P = |I w|). Making the two equal gives, for
    order 2, rho^2 = Lambda^3 P / (|b| (Lambda^2 + Delta |b|)); for a symmetric composition of
    order p (error terms of degree p + 1) the same reasoning gives
    rho = Lambda / sqrt(Lambda^2 + Delta |b|) * (Lambda P / |b|)^(1/p). The pulse's jump then
    converges with the order of the method (a single step over a short pulse, the rule n =
    ceil(span / step), made an error independent of the step). Lambda and P are bounds over the
    pulse: |w| + |b| span / I_min and |I w| + |b| span (a body at rest has Lambda = 0 before
    it). At most MAX_PULSE_SUBSTEPS steps are added (bounded work: a weak pulse on a body
    nearly at rest asks for many).
    """
    n = step_count(span, step)
    if not span > 0.0:
        return n
    tb = math.sqrt(p[PR.PULSE_BODY] ** 2 + p[PR.PULSE_BODY + 1] ** 2 + p[PR.PULSE_BODY + 2] ** 2)
    mo = math.sqrt(p[PR.PULSE_ORBITAL] ** 2 + p[PR.PULSE_ORBITAL + 1] ** 2
                   + p[PR.PULSE_ORBITAL + 2] ** 2)
    b = tb + mo
    if not b > 0.0:
        return n
    ix = p[PR.INERTIA]
    iy = p[PR.INERTIA + 1]
    iz = p[PR.INERTIA + 2]
    i_min = min(ix, min(iy, iz))
    i_max = max(ix, max(iy, iz))
    lam = math.sqrt(wx * wx + wy * wy + wz * wz) + b * span / i_min
    mom = math.sqrt((ix * wx) ** 2 + (iy * wy) ** 2 + (iz * wz) ** 2) + b * span
    delta = 1.0 / i_min - 1.0 / i_max
    rho = lam / math.sqrt(lam * lam + delta * b) * (lam * mom / b) ** (1.0 / order)
    if rho < 1.0:
        m = span / (step * rho) * (1.0 - 1e-12)
        cap = n + MAX_PULSE_SUBSTEPS
        if not m <= cap:  # (also inf or NaN)
            m = cap
        n = max(n, np.ceil(m))
    return n


@jit
def start(p: Array, extra: Extra, cfg: Array, st: Array) -> None:
    """Set the segment's step count (:func:`pulse_step_count`), momentum and opening torque."""
    span = st[ST.TAU_BOUND]
    n = pulse_step_count(p, span, cfg[CF.STEP], cfg[CF.ORDER], st[ST.Y], st[ST.Y + 1],
                         st[ST.Y + 2])
    st[ST.H] = span / n
    st[ST.N_TOTAL] = n
    for i in range(3):
        st[ST.PI + i] = p[PR.INERTIA + i] * st[ST.Y + i]
    tx, ty, tz = body_torque(p, extra, st[ST.T0] + 0.0, st[ST.Y + 3], st[ST.Y + 4],
                             st[ST.Y + 5], st[ST.Y + 6])
    st[ST.TORQUE] = tx
    st[ST.TORQUE + 1] = ty
    st[ST.TORQUE + 2] = tz


@jit_inline
def step(p: Array, extra: Extra, cfg: Array, st: Array) -> float:
    """Advance one composed step, momentum and torque carried; returns a FAIL code."""
    h = st[ST.H]
    tau = st[ST.TAU]
    for i in range(3):
        st[ST.TORQUE_OLD + i] = st[ST.TORQUE + i]
        st[ST.PI_OLD + i] = st[ST.PI + i]
    flow(p, extra, cfg, st, ST.Y_OLD, ST.PI_OLD, ST.TORQUE_OLD, st[ST.T0], tau, h, ST.Y, ST.PI,
         ST.TORQUE)
    st[ST.TAU_OLD] = tau
    # tau_k = k h (no accumulated rounding in t over millions of steps)
    st[ST.TAU] = (st[ST.TAU_BOUND] if st[ST.N_STEPS] + 1.0 >= st[ST.N_TOTAL]
                  else (st[ST.N_STEPS] + 1.0) * h)
    st[ST.NFEV] += cfg[CF.N_STAGES]
    return FAIL.NONE


@jit
def dense(p: Array, extra: Extra, cfg: Array, st: Array, tau: float) -> None:
    """Write a step of the method from the step's start to local time tau to ST.SCRATCH."""
    tau_old = st[ST.TAU_OLD]
    flow_called(p, extra, cfg, st, ST.Y_OLD, ST.PI_OLD, ST.TORQUE_OLD, st[ST.T0], tau_old,
                tau - tau_old, ST.SCRATCH, ST.TMP, ST.TMP + 3)


# ---------------------------------------------------------------------------------------
# A block of bodies in lockstep (kernels.lockstep): buffers (BK.SIZE, B), one body a column
# ---------------------------------------------------------------------------------------
@jit_wide
def block_start(p: Array, extra: Extra, cfg: Array, bst: Array, cur: Array, m: int) -> None:
    """:func:`start` per body (momentum, opening torque); bst holds the shared step count."""
    for i in range(m):
        for c in range(3):
            cur[BK.PI + c, i] = p[PR.INERTIA + c] * cur[BK.Y + c, i]
        tx, ty, tz = body_torque(p, extra, bst[ST.T0] + 0.0, cur[BK.Y + 3, i], cur[BK.Y + 4, i],
                                 cur[BK.Y + 5, i], cur[BK.Y + 6, i])
        cur[BK.TORQUE, i] = tx
        cur[BK.TORQUE + 1, i] = ty
        cur[BK.TORQUE + 2, i] = tz


@jit_wide
def block_sincos(tmp: Array, m: int) -> None:
    """
    tmp[BT.COS], tmp[BT.SIN] = cos, sin of tmp[BT.ANGLE]: :func:`~.trig.sin_cos`'s bits.

    ``trig.sin_cos_rows``: a step's angles are mostly below ``trig.SMALL``, without reduction.
    """
    sin_cos_rows(tmp[BT.ANGLE], tmp[BT.SIN], tmp[BT.COS], m)


@jit_wide
def block_axis(new: Array, tmp: Array, axis: int, m: int, next_axis: int, c_next: float,
               factor_a: float) -> None:
    """
    Turn m bodies by the axis piece of :func:`~.physics.free_flow` about ``axis`` (vectorised).

    Its half angle's cos/sin in tmp; then the next piece's half angle 0.5 beta, beta =
    c_next pi_next factor_a, to tmp[BT.ANGLE] (next_axis < 0: none).
    """
    for i in range(m):
        px, py, pz, q0, q1, q2, q3 = axis_turn(
            axis, tmp[BT.COS, i], tmp[BT.SIN, i], new[BK.PI, i], new[BK.PI + 1, i],
            new[BK.PI + 2, i], new[BK.Y + 3, i], new[BK.Y + 4, i], new[BK.Y + 5, i],
            new[BK.Y + 6, i])
        new[BK.PI, i] = px
        new[BK.PI + 1, i] = py
        new[BK.PI + 2, i] = pz
        new[BK.Y + 3, i] = q0
        new[BK.Y + 4, i] = q1
        new[BK.Y + 5, i] = q2
        new[BK.Y + 6, i] = q3
        if next_axis >= 0:
            tmp[BT.ANGLE, i] = 0.5 * (c_next * new[BK.PI + next_axis, i] * factor_a)


@jit_wide
def block_step(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, new: Array,
               tmp: Array, bodies: Array, m: int) -> None:
    """Take :func:`step` for m bodies at once: buffer old -> new, the shared times in bst."""
    h = bst[ST.H]
    tau = bst[ST.TAU]
    block_flow(p, extra, cfg, old, new, tmp, bst[ST.T0], tau, h, m)
    bst[ST.TAU_OLD] = tau
    bst[ST.TAU] = (bst[ST.TAU_BOUND] if bst[ST.N_STEPS] + 1.0 >= bst[ST.N_TOTAL]
                   else (bst[ST.N_STEPS] + 1.0) * h)
    bst[ST.NFEV] += cfg[CF.N_STAGES]


@jit_wide
def block_dense(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, out: Array,
                tmp: Array, tau: float, m: int) -> bool:
    """
    :func:`dense` for m bodies at once: the last step's start (buffer old) to local time tau.

    The state at tau goes to buffer ``out`` (rows as ``old``); :func:`dense`'s bits: the same
    :func:`flow` from the step's start over tau - tau_old, as :func:`block_flow`. Returns True
    (a method without it: ``lockstep.no_block_dense``).
    """
    tau_old = bst[ST.TAU_OLD]
    block_flow(p, extra, cfg, old, out, tmp, bst[ST.T0], tau_old, tau - tau_old, m)
    return True


@jit_wide
def block_flow(p: Array, extra: Extra, cfg: Array, old: Array, new: Array, tmp: Array,
               t0: float, s0: float, h: float, m: int) -> None:
    """
    Take :func:`flow` for m bodies at once: a step of length h from local time s0, old -> new.

    :func:`flow`'s operations in its order, cut into passes over the bodies, each vectorised
    by LLVM: kick and the |pi| angle; sin/cos (:func:`block_sincos`); the turn about pi and the
    first axis angle; per axis piece sin/cos and the turn; the torque (the Sun's direction once
    for all bodies; :func:`~.physics.plain_torque_given_sun` on a segment it covers) and the
    second kick. Rows Y, PI and TORQUE of ``new`` are written (absolute time t0 + s0 + ...).
    """
    tau = s0
    inv_ref = p[PR.INV_REF]
    first, second = flow_pieces(p)
    for r in range(BK.Y + 3, BK.TORQUE + 3):
        for i in range(m):
            new[r, i] = old[r, i]
    for j in range(int(cfg[CF.N_STAGES])):
        a = cfg[CF.GAMMA + j] * h
        half = 0.5 * a
        for i in range(m):
            px = new[BK.PI, i] + half * new[BK.TORQUE, i]
            py = new[BK.PI + 1, i] + half * new[BK.TORQUE + 1, i]
            pz = new[BK.PI + 2, i] + half * new[BK.TORQUE + 2, i]
            new[BK.PI, i] = px
            new[BK.PI + 1, i] = py
            new[BK.PI + 2, i] = pz
            n = math.sqrt(px * px + py * py + pz * pz)
            tmp[BT.NORM, i] = n
            tmp[BT.ANGLE, i] = 0.5 * (n * a * inv_ref)
        block_sincos(tmp, m)
        # the first axis piece: B_first(a/2) of B_first(a/2) B_second(a) B_first(a/2), or
        # B_first(a) alone (physics.free_flow)
        factor = 0.5 * a if second >= 0 else a
        c_first = p[PR.FLOW + first] if first >= 0 else 0.0
        for i in range(m):
            n = tmp[BT.NORM, i]
            px = new[BK.PI, i]
            py = new[BK.PI + 1, i]
            pz = new[BK.PI + 2, i]
            q0 = new[BK.Y + 3, i]
            q1 = new[BK.Y + 4, i]
            q2 = new[BK.Y + 5, i]
            q3 = new[BK.Y + 6, i]
            if n > 0.0:
                q0, q1, q2, q3 = pi_turn(tmp[BT.COS, i], tmp[BT.SIN, i] / n, px, py, pz, q0,
                                         q1, q2, q3)
            new[BK.Y + 3, i] = q0
            new[BK.Y + 4, i] = q1
            new[BK.Y + 5, i] = q2
            new[BK.Y + 6, i] = q3
            if first >= 0:
                tmp[BT.ANGLE, i] = 0.5 * (c_first * new[BK.PI + first, i] * factor)
        if second >= 0:
            block_sincos(tmp, m)
            block_axis(new, tmp, first, m, second, p[PR.FLOW + second], a)
            block_sincos(tmp, m)
            block_axis(new, tmp, second, m, first, c_first, 0.5 * a)
            block_sincos(tmp, m)
            block_axis(new, tmp, first, m, -1, 0.0, 0.0)
        elif first >= 0:
            block_sincos(tmp, m)
            block_axis(new, tmp, first, m, -1, 0.0, 0.0)
        t = t0 + (tau + cfg[CF.CUM + j] * h)
        sx, sy = sun_in_orbit_plane(p[PR.ORBIT_RATE], t)
        if extra is None and p[PR.HAS_ORBITAL] == 0.0:     # the torque without its branches
            for i in range(m):
                tx, ty, tz = plain_torque_given_sun(p, sx, sy, new[BK.Y + 3, i],
                                                    new[BK.Y + 4, i], new[BK.Y + 5, i],
                                                    new[BK.Y + 6, i])
                block_kick(new, i, half, tx, ty, tz)
        else:
            for i in range(m):
                tx, ty, tz = torque_given_sun(p, extra, t, sx, sy, new[BK.Y + 3, i],
                                              new[BK.Y + 4, i], new[BK.Y + 5, i],
                                              new[BK.Y + 6, i])
                block_kick(new, i, half, tx, ty, tz)
    for i in range(m):
        new[BK.Y, i] = new[BK.PI, i] * p[PR.INV_INERTIA]   # as flow
        new[BK.Y + 1, i] = new[BK.PI + 1, i] * p[PR.INV_INERTIA + 1]
        new[BK.Y + 2, i] = new[BK.PI + 2, i] * p[PR.INV_INERTIA + 2]


@jit_inline
def block_kick(new: Array, i: int, half: float, tx: float, ty: float, tz: float) -> None:
    """Keep body i's torque (tx, ty, tz) and kick its angular momentum by ``half`` times it."""
    new[BK.TORQUE, i] = tx
    new[BK.TORQUE + 1, i] = ty
    new[BK.TORQUE + 2, i] = tz
    new[BK.PI, i] += half * tx
    new[BK.PI + 1, i] += half * ty
    new[BK.PI + 2, i] += half * tz


@jit
def block_load(bst: Array, old: Array, new: Array, i: int) -> None:
    """Copy body i (its state before and after the step) into bst for :func:`dense`."""
    for c in range(N):
        bst[ST.Y + c] = new[BK.Y + c, i]
        bst[ST.Y_OLD + c] = old[BK.Y + c, i]
    for c in range(3):
        bst[ST.PI + c] = new[BK.PI + c, i]
        bst[ST.PI_OLD + c] = old[BK.PI + c, i]
        bst[ST.TORQUE + c] = new[BK.TORQUE + c, i]
        bst[ST.TORQUE_OLD + c] = old[BK.TORQUE + c, i]


@jit
def block_store(bst: Array, new: Array, i: int) -> None:
    """Copy nothing back: the splitting's dense output leaves the body's state as it was."""

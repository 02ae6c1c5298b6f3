"""
Compiled ``splitting*``: the Lie-Poisson splitting methods (``integrators.splitting``).

Kick (the total torque, attitude frozen) - free flow (:func:`~.physics.free_flow`) - kick,
composed with the coefficients gamma_j of the config; momentum pi = I w carried in
ST.PI. Each function works on one body's state ``st``.
"""
from __future__ import annotations

import math

import numpy as np

from tumble_ros.core.jit import called, jit, jit_inline
from tumble_ros.core.kernels.layout import Array, CF, Extra, FAIL, PR, ST
from tumble_ros.core.kernels.physics import body_torque, free_flow
from tumble_ros.core.kernels.rk4 import step_count

__all__ = ['flow', 'flow_called', 'pulse_step_count', 'start', 'step', 'dense',
           'MAX_PULSE_SUBSTEPS']

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
    st[yd] = px / p[PR.INERTIA]
    st[yd + 1] = py / p[PR.INERTIA + 1]
    st[yd + 2] = pz / p[PR.INERTIA + 2]
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

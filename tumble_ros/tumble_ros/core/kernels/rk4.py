"""
Compiled ``rk4``: the classical Runge-Kutta method of order 4 (``integrators.fixed_step.RK4``).

n = ceil(span / step) equal steps on a segment, local time tau_k = k h (exactly tau_bound at
the last step), cubic Hermite dense output whose end-of-step derivative opens the next step.
``start``/``step``/``dense`` work on one body's state ``st`` (layout :data:`~.layout.ST`).

The method is written once: :func:`step_count`, :func:`stage`, :func:`combine`, :func:`next_tau`
and :func:`hermite` are its arithmetic, which the compiled step applies per component (floats,
inlined) and the reference stepper ``integrators.fixed_step.RK4`` (any attitude, any
right-hand side) applies to numpy arrays through their Python source: the same operations in
the same order, so the two give the same bits.
"""
from __future__ import annotations

from typing import TypeVar

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit, jit_inline, jit_wide
from tumble_ros.core.kernels.layout import Array, BB, BK, BT, CF, Extra, FAIL, N, PR, ST
from tumble_ros.core.kernels.physics import (derivatives, plain_torque_given_sun, rhs, rhs_called,
                                             torque_given_sun)
from tumble_ros.core.torques.gravity_gradient import sun_in_orbit_plane

__all__ = ['step_count', 'stage', 'combine', 'next_tau', 'hermite', 'start', 'step', 'dense',
           'V', 'block_start', 'block_rhs', 'block_stage', 'block_step', 'block_load',
           'block_store']

#: A component (compiled loop) or a whole state vector (reference stepper).
V = TypeVar('V', float, npt.NDArray[np.float64])


@jit
def step_count(span: float, step: float) -> float:
    """Return n = ceil(span / step) (a float, at least 1) for a segment of length ``span``."""
    if not span > 0.0:
        return 1.0
    # np.ceil stays a float (math.ceil is an int64 in numba: a span / step above 9e18 wrapped
    # around to one step over the whole segment)
    n: float = np.ceil(span / step * (1.0 - 1e-12))
    return max(1.0, n)


@jit_inline
def stage(y: V, k: V, a: float) -> V:
    """Return a stage's argument y + a k (a = h/2 or h)."""
    return y + a * k


@jit_inline
def combine(y: V, k1: V, k2: V, k3: V, k4: V, h: float) -> V:
    """Return the step's result y + h/6 (k1 + 2 (k2 + k3) + k4)."""
    return y + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


@jit_inline
def next_tau(n_steps: float, n_total: float, h: float, tau_bound: float) -> float:
    """Return the local time after step n_steps + 1: (n_steps + 1) h, exactly tau_bound last."""
    # tau_k = k h: no accumulated rounding in t over millions of steps (over 10^6 steps,
    # t + h + h + ... drifts by ~1e-10 yr, enough to show in the Jacobi integral at 1e-13)
    return tau_bound if n_steps + 1.0 >= n_total else (n_steps + 1.0) * h


@jit_inline
def hermite(s: float) -> tuple[float, float, float, float]:
    """Return the cubic Hermite weights (h00, h10, h01, h11) at s in [0, 1] of a step."""
    h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    h10 = s * (1.0 - s) ** 2
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = s * s * (s - 1.0)
    return h00, h10, h01, h11


@jit
def start(p: Array, extra: Extra, cfg: Array, st: Array) -> None:
    """Set the segment's step count and step (st[ST.TAU_BOUND] is its span)."""
    n = step_count(st[ST.TAU_BOUND], cfg[CF.STEP])
    st[ST.H] = st[ST.TAU_BOUND] / n
    st[ST.N_TOTAL] = n


@jit_inline
def step(p: Array, extra: Extra, cfg: Array, st: Array) -> float:
    """Take one step from st[ST.Y] at local time st[ST.TAU]; returns a FAIL code."""
    h = st[ST.H]
    tau = st[ST.TAU]
    t0 = st[ST.T0]
    if st[ST.F_VALID] == 0.0:
        rhs(p, extra, t0 + tau, st, ST.Y, ST.F)
        st[ST.NFEV] += 1.0
    k2 = ST.K
    k3 = ST.K + N
    k4 = ST.K + 2 * N
    for i in range(N):
        st[ST.TMP + i] = stage(st[ST.Y + i], st[ST.F + i], 0.5 * h)
    rhs(p, extra, t0 + (tau + 0.5 * h), st, ST.TMP, k2)
    for i in range(N):
        st[ST.TMP + i] = stage(st[ST.Y + i], st[k2 + i], 0.5 * h)
    rhs(p, extra, t0 + (tau + 0.5 * h), st, ST.TMP, k3)
    for i in range(N):
        st[ST.TMP + i] = stage(st[ST.Y + i], st[k3 + i], h)
    rhs(p, extra, t0 + (tau + h), st, ST.TMP, k4)
    st[ST.NFEV] += 3.0
    for i in range(N):
        st[ST.F_OLD + i] = st[ST.F + i]
        st[ST.Y + i] = combine(st[ST.Y + i], st[ST.F + i], st[k2 + i], st[k3 + i], st[k4 + i],
                               h)
    st[ST.TAU_OLD] = tau
    st[ST.TAU] = next_tau(st[ST.N_STEPS], st[ST.N_TOTAL], h, st[ST.TAU_BOUND])
    st[ST.F_VALID] = 0.0
    return FAIL.NONE


@jit
def dense(p: Array, extra: Extra, cfg: Array, st: Array, tau: float) -> None:
    """Write the cubic Hermite interpolant at local time tau of the last step to ST.SCRATCH."""
    if st[ST.F_VALID] == 0.0:  # f at the end of the step
        rhs_called(p, extra, st[ST.T0] + st[ST.TAU], st, ST.Y, ST.F)
        st[ST.F_VALID] = 1.0
        st[ST.NFEV] += 1.0
    tau_old = st[ST.TAU_OLD]
    h = st[ST.TAU] - tau_old
    s = (tau - tau_old) / h
    h00, h10, h01, h11 = hermite(s)
    for i in range(N):
        st[ST.SCRATCH + i] = (h00 * st[ST.Y_OLD + i] + (h10 * h) * st[ST.F_OLD + i]
                              + h01 * st[ST.Y + i] + (h11 * h) * st[ST.F + i])


# ---------------------------------------------------------------------------------------
# A block of bodies in lockstep (kernels.lockstep): buffers (BK.SIZE, B), one body a column
# ---------------------------------------------------------------------------------------
@jit_wide
def block_start(p: Array, extra: Extra, cfg: Array, bst: Array, cur: Array, m: int) -> None:
    """Do nothing per body: :func:`start` sets the shared step count only (bst)."""


@jit_wide
def block_rhs(p: Array, extra: Extra, t: float, y: Array, out: Array, m: int) -> None:
    """
    Write f(t, y) of m bodies, y in rows 0-6 of ``y``, to rows 0-6 of ``out`` (vectorised).

    Two passes, each vectorised by LLVM: the torque (the Sun's direction at t once for all;
    :func:`~.physics.plain_torque_given_sun` on a segment it covers) and d omega/dt, then
    dq/dt, which needs no torque (:func:`~.physics.derivatives` in each,
    the other components left unused: the same operations). All seven derivatives in one
    pass, reading ten rows and writing seven, LLVM left scalar: too many rows to check for
    overlap at run time (``inspect_asm``: ``vmulsd``, not ``vmulpd``).
    """
    sx, sy = sun_in_orbit_plane(p[PR.ORBIT_RATE], t)
    if extra is None and p[PR.HAS_ORBITAL] == 0.0:     # the torque without its branches
        for i in range(m):
            tx, ty, tz = plain_torque_given_sun(p, sx, sy, y[3, i], y[4, i], y[5, i], y[6, i])
            f0, f1, f2, _, _, _, _ = derivatives(p, y[0, i], y[1, i], y[2, i], y[3, i],
                                                 y[4, i], y[5, i], y[6, i], tx, ty, tz)
            out[0, i] = f0
            out[1, i] = f1
            out[2, i] = f2
    else:
        for i in range(m):
            tx, ty, tz = torque_given_sun(p, extra, t, sx, sy, y[3, i], y[4, i], y[5, i],
                                          y[6, i])
            f0, f1, f2, _, _, _, _ = derivatives(p, y[0, i], y[1, i], y[2, i], y[3, i],
                                                 y[4, i], y[5, i], y[6, i], tx, ty, tz)
            out[0, i] = f0
            out[1, i] = f1
            out[2, i] = f2
    for i in range(m):
        _, _, _, f3, f4, f5, f6 = derivatives(p, y[0, i], y[1, i], y[2, i], y[3, i], y[4, i],
                                              y[5, i], y[6, i], 0.0, 0.0, 0.0)
        out[3, i] = f3
        out[4, i] = f4
        out[5, i] = f5
        out[6, i] = f6


@jit_wide
def block_stage(y: Array, k: Array, kr: int, a: float, tmp: Array, m: int) -> None:
    """Write the stage argument y + a k of m bodies to tmp[BT.STAGE:] (:func:`stage`)."""
    for c in range(N):
        for i in range(m):
            tmp[BT.STAGE + c, i] = stage(y[BK.Y + c, i], k[kr + c, i], a)


@jit_wide
def block_step(p: Array, extra: Extra, cfg: Array, bst: Array, old: Array, new: Array,
               tmp: Array, bodies: Array, m: int) -> None:
    """
    Take :func:`step` for m bodies at once: buffer old -> new, the shared times in bst.

    f(t, y) is evaluated for every body (a body whose dense output already took it gets the
    same bits again; its count is one less: bodies[BB.NFEV_ADJ]); then the stages, each a
    vectorised pass with the Sun's direction once.
    """
    h = bst[ST.H]
    tau = bst[ST.TAU]
    t0 = bst[ST.T0]
    args = tmp[BT.STAGE:BT.STAGE + N]
    block_rhs(p, extra, t0 + tau, old[BK.Y:BK.Y + N], old[BK.F:BK.F + N], m)
    block_stage(old, old, BK.F, 0.5 * h, tmp, m)
    block_rhs(p, extra, t0 + (tau + 0.5 * h), args, tmp[BT.K2:BT.K2 + N], m)
    block_stage(old, tmp, BT.K2, 0.5 * h, tmp, m)
    block_rhs(p, extra, t0 + (tau + 0.5 * h), args, tmp[BT.K3:BT.K3 + N], m)
    block_stage(old, tmp, BT.K3, h, tmp, m)
    block_rhs(p, extra, t0 + (tau + h), args, tmp[BT.K4:BT.K4 + N], m)
    for c in range(N):
        for i in range(m):
            new[BK.Y + c, i] = combine(old[BK.Y + c, i], old[BK.F + c, i], tmp[BT.K2 + c, i],
                                       tmp[BT.K3 + c, i], tmp[BT.K4 + c, i], h)
    for i in range(m):
        bodies[BB.NFEV_ADJ, i] -= bodies[BB.F_VALID, i]
        bodies[BB.F_VALID, i] = 0.0
    bst[ST.NFEV] += 4.0
    bst[ST.TAU_OLD] = tau
    bst[ST.TAU] = next_tau(bst[ST.N_STEPS], bst[ST.N_TOTAL], h, bst[ST.TAU_BOUND])


@jit
def block_load(bst: Array, old: Array, new: Array, i: int) -> None:
    """Copy body i (state and f before and after the step) into bst for :func:`dense`."""
    for c in range(N):
        bst[ST.Y + c] = new[BK.Y + c, i]
        bst[ST.Y_OLD + c] = old[BK.Y + c, i]
        bst[ST.F + c] = new[BK.F + c, i]
        bst[ST.F_OLD + c] = old[BK.F + c, i]


@jit
def block_store(bst: Array, new: Array, i: int) -> None:
    """Copy back f(t, y) that :func:`dense` may have evaluated for body i."""
    for c in range(N):
        new[BK.F + c, i] = bst[ST.F + c]

"""
Compiled ``rk4``: the classical Runge-Kutta method of order 4 (``integrators.fixed_step.RK4``).

n = ceil(span / step) equal steps on a segment, local time tau_k = k h (exactly tau_bound at
the last step), cubic Hermite dense output whose end-of-step derivative opens the next step.
Each function works on one body's state ``st`` (layout :data:`~.layout.ST`).
"""
from __future__ import annotations

import numpy as np

from .layout import CF, FAIL, N, ST
from .physics import rhs, rhs_called
from ..jit import jit, jit_inline

__all__ = ['step_count', 'start', 'step', 'dense']


@jit
def step_count(span, step):
    """Return n = ceil(span / step) (a float, at least 1) for a segment of length ``span``."""
    if not span > 0.0:
        return 1.0
    # np.ceil stays a float (math.ceil is an int64 in numba: a span / step above 9e18 wrapped
    # around to one step over the whole segment)
    return max(1.0, np.ceil(span / step * (1.0 - 1e-12)))


@jit
def start(p, extra, cfg, st):
    """Set the segment's step count and step (st[ST.TAU_BOUND] is its span)."""
    n = step_count(st[ST.TAU_BOUND], cfg[CF.STEP])
    st[ST.H] = st[ST.TAU_BOUND] / n
    st[ST.N_TOTAL] = n


@jit_inline
def step(p, extra, cfg, st):
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
        st[ST.TMP + i] = st[ST.Y + i] + (0.5 * h) * st[ST.F + i]
    rhs(p, extra, t0 + (tau + 0.5 * h), st, ST.TMP, k2)
    for i in range(N):
        st[ST.TMP + i] = st[ST.Y + i] + (0.5 * h) * st[k2 + i]
    rhs(p, extra, t0 + (tau + 0.5 * h), st, ST.TMP, k3)
    for i in range(N):
        st[ST.TMP + i] = st[ST.Y + i] + h * st[k3 + i]
    rhs(p, extra, t0 + (tau + h), st, ST.TMP, k4)
    st[ST.NFEV] += 3.0
    for i in range(N):
        st[ST.F_OLD + i] = st[ST.F + i]
        st[ST.Y + i] = st[ST.Y + i] + (h / 6.0) * (
            st[ST.F + i] + 2.0 * (st[k2 + i] + st[k3 + i]) + st[k4 + i])
    st[ST.TAU_OLD] = tau
    # tau_k = k h (no accumulated rounding in t over millions of steps)
    st[ST.TAU] = (st[ST.TAU_BOUND] if st[ST.N_STEPS] + 1.0 >= st[ST.N_TOTAL]
                  else (st[ST.N_STEPS] + 1.0) * h)
    st[ST.F_VALID] = 0.0
    return FAIL.NONE


@jit
def dense(p, extra, cfg, st, tau):
    """Write the cubic Hermite interpolant at local time tau of the last step to ST.SCRATCH."""
    if st[ST.F_VALID] == 0.0:  # f at the end of the step
        rhs_called(p, extra, st[ST.T0] + st[ST.TAU], st, ST.Y, ST.F)
        st[ST.F_VALID] = 1.0
        st[ST.NFEV] += 1.0
    tau_old = st[ST.TAU_OLD]
    h = st[ST.TAU] - tau_old
    s = (tau - tau_old) / h
    h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    h10 = s * (1.0 - s) ** 2
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = s * s * (s - 1.0)
    for i in range(N):
        st[ST.SCRATCH + i] = (h00 * st[ST.Y_OLD + i] + (h10 * h) * st[ST.F_OLD + i]
                              + h01 * st[ST.Y + i] + (h11 * h) * st[ST.F + i])

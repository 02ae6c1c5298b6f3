"""
A compiled method for tests: the explicit midpoint rule (order 2), written as a kernel module.

The shape every method of ``core/kernels/methods.KERNELS`` has (start, step, dense on one
body's state ``st``): test_core_kernel_registry registers it with the one registry line and
runs it through simulate() and the ensemble loop. Fixed step, n = ceil(span / step) equal
steps (``rk4.step_count``); dense output linear between the step's ends (order 2 as well).
"""
from tumble_ros.core.compiling.jit import jit, jit_inline
from tumble_ros.core.kernels.layout import CF, FAIL, N, ST
from tumble_ros.core.kernels.physics import rhs
from tumble_ros.core.kernels.rk4 import step_count


@jit
def start(p, extra, cfg, st):
    """Set the segment's step count and step (st[ST.TAU_BOUND] is its span)."""
    n = step_count(st[ST.TAU_BOUND], cfg[CF.STEP])
    st[ST.H] = st[ST.TAU_BOUND] / n
    st[ST.N_TOTAL] = n


@jit_inline
def step(p, extra, cfg, st):
    """Take y += h f(tau + h/2, y + h/2 f(tau, y)); returns FAIL.NONE."""
    h = st[ST.H]
    tau = st[ST.TAU]
    t0 = st[ST.T0]
    rhs(p, extra, t0 + tau, st, ST.Y, ST.F)
    for i in range(N):
        st[ST.TMP + i] = st[ST.Y + i] + (0.5 * h) * st[ST.F + i]
    rhs(p, extra, t0 + (tau + 0.5 * h), st, ST.TMP, ST.K)
    for i in range(N):
        st[ST.Y + i] = st[ST.Y + i] + h * st[ST.K + i]
    st[ST.NFEV] += 2.0
    st[ST.TAU_OLD] = tau
    st[ST.TAU] = (st[ST.TAU_BOUND] if st[ST.N_STEPS] + 1.0 >= st[ST.N_TOTAL]
                  else (st[ST.N_STEPS] + 1.0) * h)
    return FAIL.NONE


@jit
def dense(p, extra, cfg, st, tau):
    """Write the linear interpolant at local time tau of the last step to ST.SCRATCH."""
    s = (tau - st[ST.TAU_OLD]) / (st[ST.TAU] - st[ST.TAU_OLD])
    for i in range(N):
        st[ST.SCRATCH + i] = (1.0 - s) * st[ST.Y_OLD + i] + s * st[ST.Y + i]

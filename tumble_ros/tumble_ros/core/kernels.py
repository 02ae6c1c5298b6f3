"""
Compiled integration loops: the hot path without interpreter overhead.

Everything here is plain Python written in the subset numba compiles (floats, 1-D/2-D float64
arrays, loops). With numba installed the functions are compiled once (``cache=True``: the
machine code is kept in ``__pycache__`` and reused by later processes); without numba, or with
``TUMBLE_ROS_NO_JIT=1`` / ``NUMBA_DISABLE_JIT=1``, :data:`COMPILED` is False and the callers
(:class:`~.integrators.compiled.CompiledStepper`, :mod:`~.ensemble`) use the reference
step-by-step path instead, which gives the same trajectory (tests/test_core_fast.py).

What is compiled, for the quaternion attitude only:

* the right-hand side (the reference steppers call it too, through ``dynamics``);
* ``rk4``: ``integrators.fixed_step.RK4`` (n = ceil(span / step) equal steps, cubic Hermite
  dense output);
* ``dop853``: scipy's ``DOP853`` step, error norm, step-size control, initial step and
  7th-order dense output, transcribed from scipy 1.17 (``scipy/integrate/_ivp/rk.py``) with
  scipy's own coefficient tables;
* ``splitting``: the Lie-Poisson splitting methods of ``integrators.splitting``;
* the per-step bookkeeping of the :class:`~.propagator.Propagator`: failure checks (non-finite
  state, step collapse), the continuous Euler-angle tracking (``Propagator._track_euler``) and
  output sampling, so a whole segment (or a whole ensemble) runs without returning to Python.

Like the reference steppers (``integrators.base``: "Local time") every method steps in the
segment's local time tau = t - t0 (st[S_TAU]); st[S_T] is the absolute time handed out.

Each body's integration state lives in one float64 array ``st`` (layout: the ``S_*``/``O_*``
constants below); a segment's problem (inertia, orbit rate, pulse torques, precomputed
coefficients) in ``p`` (:func:`problem_array`); the method and its settings in ``cfg``
(:func:`config_array`).
"""
from __future__ import annotations

import math
import os

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dop

__all__ = ['free_flow_split', 'COMPILED', 'NUMBA_VERSION', 'problem_array', 'problem_arrays',
           'config_array', 'new_state', 'KERNEL_IDS', 'split_step_count', 'MAX_PULSE_SUBSTEPS']

try:  # pragma: no cover - exercised by the environment, not by a test
    import numba as _numba
except ImportError:  # pragma: no cover
    _numba = None

NUMBA_VERSION = getattr(_numba, '__version__', None)
#: True when the kernels below are compiled (numba present and not disabled).
COMPILED = bool(_numba is not None and not _numba.config.DISABLE_JIT
                and os.environ.get('TUMBLE_ROS_NO_JIT', '') in ('', '0'))

if COMPILED:
    def jit(f):
        # nogil: ensembles run blocks of bodies in several Python threads at once
        return _numba.njit(cache=True, error_model='numpy', nogil=True)(f)

    def jit_inline(f):
        # Inlined into callers at numba's IR level: no call, no reference counting of the
        # array arguments (which costs more than the arithmetic of a small step). Only for
        # the per-step hot path: inlining multiplies compile time.
        return _numba.njit(cache=True, error_model='numpy', nogil=True, inline='always')(f)

    def called(f):
        """Compile a jit_inline function separately (not inlined), for cold paths."""
        return jit(f.py_func)
else:
    def jit(f):
        return f

    jit_inline = called = jit

# -- method ids (cfg[C_METHOD]) ---------------------------------------------------------
M_RK4, M_DOP853, M_SPLIT = 1, 2, 3
KERNEL_IDS = {'rk4': M_RK4, 'dop853': M_DOP853, 'splitting': M_SPLIT}

# -- cfg layout -------------------------------------------------------------------------
C_METHOD, C_STEP, C_RTOL, C_ATOL, C_MAXSTEP, C_NG = 0, 1, 2, 3, 4, 5
C_G = 6          # composition coefficients gamma_j (up to 16)
C_CUM = 22       # cumulative sums c_j = gamma_1 + ... + gamma_j
C_ORDER = 38     # order of the method (splitting: the pulse sub-step rule, split_step_count)
N_CFG = 39
MAX_STAGES = 16

# -- p (segment problem) layout -----------------------------------------------------------
P_IX, P_IY, P_IZ, P_WS = 0, 1, 2, 3
P_AX, P_AY, P_AZ = 4, 5, 6            # Euler-equation coefficients (Iy - Iz)/Ix, ...
P_GX, P_GY, P_GZ = 7, 8, 9            # gravity-gradient coefficients 3 ws^2 (Iz - Iy)/Ix, ...
P_BX, P_BY, P_BZ = 10, 11, 12         # body pulse torque / I
P_MOX, P_MOY, P_MOZ, P_ORB = 13, 14, 15, 16   # orbital pulse torque; P_ORB != 0 if any
P_KX, P_KY, P_KZ = 17, 18, 19         # torque coefficients 3 ws^2 (Iz - Iy), ... (splitting)
P_TBX, P_TBY, P_TBZ = 20, 21, 22      # body pulse torque (splitting)
P_INVREF, P_CX, P_CY, P_CZ = 23, 24, 25, 26   # free-flow split: 1/I_ref, 1/I_i - 1/I_ref
N_P = 27

# -- st (state) layout --------------------------------------------------------------------
S_T, S_TOLD, S_TBOUND, S_H, S_NTOTAL, S_NSTEPS, S_NFEV, S_STATUS = 0, 1, 2, 3, 4, 5, 6, 7
S_FAIL, S_FAILT, S_FAILDT, S_FVALID, S_DENSE, S_HPREV, S_NFEVDONE, S_T0 = (8, 9, 10, 11, 12, 13,
                                                                           14, 15)
S_BUDGET = 16             # Euler tracking: angle change bound accumulated since the last update
S_COLLAPSE = 17           # 16 ulp of the segment's largest tau: no step longer than this collapses
S_TAU, S_TAUOLD, S_TAUBOUND = 18, 19, 20   # local times tau = t - S_T0 (S_T, S_TOLD, S_TBOUND)
RUNNING, FINISHED, FAILED = 0.0, 1.0, 2.0
FAIL_NONE, FAIL_NONFINITE, FAIL_COLLAPSE, FAIL_TOO_SMALL = 0.0, 1.0, 2.0, 3.0
FAIL_STEP_NAN, FAIL_REJECTED = 4.0, 5.0   # dop853: step size not a number; too many rejections
N = 7                     # state size: omega (3) + quaternion (4)
O_Y = 24                  # current state
O_YOLD = O_Y + N          # state at the start of the last step
O_F = O_YOLD + N          # f(t, y) (rk4: valid if S_FVALID; dop853: always)
O_FOLD = O_F + N          # f at the start of the last step (rk4 dense output)
O_TAU = O_FOLD + N        # splitting: body torque at (t, y)
O_TAUOLD = O_TAU + 3      # splitting: body torque at the start of the last step
O_PI = O_TAUOLD + 3       # splitting: body angular momentum I w (kept, not recomputed from w:
O_PIOLD = O_PI + 3        # the round trip w -> I w -> w would bias |L| at the 1e-17/step level)
O_TMP = O_PIOLD + 3       # stage argument
O_YNEW = O_TMP + N        # candidate state (dop853)
O_SCR = O_YNEW + N        # dense output result
O_K = O_SCR + N           # Runge-Kutta stages, 16 x 7 (dop853: scipy's K_extended)
O_FD = O_K + 16 * N       # dop853 dense-output coefficients F, 7 x 7
N_STATE = O_FD + 7 * N

# -- DOP853 tables (scipy's own) -----------------------------------------------------------
_D_A = np.ascontiguousarray(_dop.A, dtype=np.float64)
_D_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
_D_C = np.ascontiguousarray(_dop.C, dtype=np.float64)
_D_E3 = np.ascontiguousarray(_dop.E3, dtype=np.float64)
_D_E5 = np.ascontiguousarray(_dop.E5, dtype=np.float64)
_D_D = np.ascontiguousarray(_dop.D, dtype=np.float64)
_D_NSTAGES = int(_dop.N_STAGES)          # 12
_D_NEXT = int(_dop.N_STAGES_EXTENDED)    # 16
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERR_EXP = -1.0 / (7 + 1)                # DOP853: error_estimator_order = 7
_MIN_STEP_ULPS = 16.0                    # integrators.base._MIN_STEP_ULPS
_UNWRAP_STEP = 1.0                       # propagator._UNWRAP_STEP
_UNWRAP_MIN_SIN = 0.1                    # propagator._UNWRAP_MIN_SIN
_MAX_TRACK_PIECES = 100_000              # propagator._MAX_TRACK_PIECES
#: splitting: most steps the pulse rule (split_step_count) adds to a segment's own count.
MAX_PULSE_SUBSTEPS = 1000
#: dop853: rejected step sizes in a row before the step fails. Each rejection divides h by >= 5
#: (_MIN_FACTOR), so a finite h reaches min_step (FAIL_TOO_SMALL) within ~480 rejections even
#: from 1e9 yr; this only bounds the loop by construction.
_MAX_REJECTIONS = 1000
_TWO_PI = 2.0 * math.pi


# =======================================================================================
# Python-side constructors of the arrays (not compiled)
# =======================================================================================
def free_flow_split(inertia) -> tuple[float, tuple[float, float, float]]:
    """
    (1/I_r, (c_x, c_y, c_z)) with I_r the middle moment and c_i = 1/I_i - 1/I_r.

    c_r is exactly 0, and so is c_i for a moment equal to I_r (symmetric body: exact free flow).
    """
    inertia = tuple(float(v) for v in inertia)
    r = sorted(range(3), key=lambda i: inertia[i])[1]
    inv_ref = 1.0 / inertia[r]
    return inv_ref, tuple(0.0 if i == r else 1.0 / inertia[i] - inv_ref for i in range(3))


def problem_arrays(inertia, orbit_rate, torques) -> np.ndarray:
    """
    Return the ``p`` rows of n segments of one body: (n, N_P).

    ``torques`` (n, 6): each segment's body pulse torque then orbital pulse torque [I rad/yr^2].
    The one place that knows the layout of ``p`` (the single-body path and the ensembles).
    """
    ix, iy, iz = (float(v) for v in inertia)
    ws = float(orbit_rate)
    k = 3.0 * ws * ws
    torques = np.asarray(torques, dtype=float).reshape(-1, 6)
    p = np.zeros((len(torques), N_P))
    p[:, P_IX], p[:, P_IY], p[:, P_IZ], p[:, P_WS] = ix, iy, iz, ws
    p[:, P_AX], p[:, P_AY], p[:, P_AZ] = (iy - iz) / ix, (iz - ix) / iy, (ix - iy) / iz
    p[:, P_GX], p[:, P_GY], p[:, P_GZ] = k * (iz - iy) / ix, k * (ix - iz) / iy, k * (iy - ix) / iz
    p[:, P_BX], p[:, P_BY], p[:, P_BZ] = torques[:, 0] / ix, torques[:, 1] / iy, torques[:, 2] / iz
    p[:, P_MOX:P_MOZ + 1] = torques[:, 3:]
    p[:, P_ORB] = np.where(np.any(torques[:, 3:] != 0.0, axis=1), 1.0, 0.0)
    p[:, P_KX], p[:, P_KY], p[:, P_KZ] = k * (iz - iy), k * (ix - iz), k * (iy - ix)
    p[:, P_TBX:P_TBZ + 1] = torques[:, :3]
    inv_ref, coeffs = free_flow_split((ix, iy, iz))
    p[:, P_INVREF] = inv_ref
    p[:, P_CX], p[:, P_CY], p[:, P_CZ] = coeffs
    return p


def problem_array(inertia, orbit_rate, torque_body=(0.0, 0.0, 0.0),
                  torque_orbital=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Return the ``p`` array of one segment (see :func:`problem_arrays`)."""
    return problem_arrays(inertia, orbit_rate, [*torque_body, *torque_orbital])[0]


def config_array(kernel: str, settings, gammas=(), order: int = 0) -> np.ndarray:
    """Return the ``cfg`` array: method, step, tolerances, order, composition coefficients."""
    cfg = np.zeros(N_CFG)
    cfg[C_METHOD] = KERNEL_IDS[kernel]
    cfg[C_ORDER] = float(order)
    cfg[C_STEP] = settings.step
    cfg[C_RTOL] = settings.rtol
    cfg[C_ATOL] = settings.atol
    cfg[C_MAXSTEP] = settings.max_step if settings.max_step > 0 else np.inf
    gammas = tuple(float(g) for g in gammas)
    if len(gammas) > MAX_STAGES:
        raise ValueError(f'at most {MAX_STAGES} composition stages')
    cfg[C_NG] = len(gammas)
    total = 0.0
    for j, g in enumerate(gammas):
        total += g
        cfg[C_G + j] = g
        cfg[C_CUM + j] = total
    if gammas:
        cfg[C_CUM + len(gammas) - 1] = 1.0  # the last stage ends exactly at t + h
    return cfg


def new_state() -> np.ndarray:
    """Return a zeroed ``st`` array."""
    return np.zeros(N_STATE)


# =======================================================================================
# Right-hand side and torque
# =======================================================================================
@jit_inline
def rhs(p, t, st, yo, oo):
    """Write f(t, y) for y = st[yo:yo+7] to st[oo:oo+7] (the only quaternion-attitude RHS)."""
    wx = st[yo]
    wy = st[yo + 1]
    wz = st[yo + 2]
    q0 = st[yo + 3]
    q1 = st[yo + 4]
    q2 = st[yo + 5]
    q3 = st[yo + 6]
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c00 = 1.0 - s * (q2 * q2 + q3 * q3)
    c01 = s * (q1 * q2 - q0 * q3)
    c02 = s * (q1 * q3 + q0 * q2)
    c10 = s * (q1 * q2 + q0 * q3)
    c11 = 1.0 - s * (q1 * q1 + q3 * q3)
    c12 = s * (q2 * q3 - q0 * q1)
    ws = p[P_WS]
    sn = math.sin(ws * t)
    cs = math.cos(ws * t)
    ux = c00 * sn + c10 * cs
    uy = c01 * sn + c11 * cs
    uz = c02 * sn + c12 * cs
    dwx = p[P_AX] * wy * wz + p[P_GX] * uy * uz + p[P_BX]
    dwy = p[P_AY] * wz * wx + p[P_GY] * ux * uz + p[P_BY]
    dwz = p[P_AZ] * wx * wy + p[P_GZ] * ux * uy + p[P_BZ]
    if p[P_ORB] != 0.0:
        mox = p[P_MOX]
        moy = p[P_MOY]
        moz = p[P_MOZ]
        c20 = s * (q1 * q3 - q0 * q2)
        c21 = s * (q2 * q3 + q0 * q1)
        c22 = 1.0 - s * (q1 * q1 + q2 * q2)
        dwx += (c00 * mox + c10 * moy + c20 * moz) / p[P_IX]
        dwy += (c01 * mox + c11 * moy + c21 * moz) / p[P_IY]
        dwz += (c02 * mox + c12 * moy + c22 * moz) / p[P_IZ]
    st[oo] = dwx
    st[oo + 1] = dwy
    st[oo + 2] = dwz
    st[oo + 3] = 0.5 * (-q1 * wx - q2 * wy - q3 * wz)
    st[oo + 4] = 0.5 * (q0 * wx + q2 * wz - q3 * wy)
    st[oo + 5] = 0.5 * (q0 * wy - q1 * wz + q3 * wx)
    st[oo + 6] = 0.5 * (q0 * wz + q1 * wy - q2 * wx)


rhs_called = called(rhs)


@jit_inline
def body_torque(p, q0, q1, q2, q3, t):
    """Total body-axis torque (gravity gradient + pulses) at attitude q and time t."""
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c00 = 1.0 - s * (q2 * q2 + q3 * q3)
    c01 = s * (q1 * q2 - q0 * q3)
    c02 = s * (q1 * q3 + q0 * q2)
    c10 = s * (q1 * q2 + q0 * q3)
    c11 = 1.0 - s * (q1 * q1 + q3 * q3)
    c12 = s * (q2 * q3 - q0 * q1)
    ws = p[P_WS]
    sn = math.sin(ws * t)
    cs = math.cos(ws * t)
    ux = c00 * sn + c10 * cs
    uy = c01 * sn + c11 * cs
    uz = c02 * sn + c12 * cs
    tx = p[P_KX] * uy * uz + p[P_TBX]
    ty = p[P_KY] * ux * uz + p[P_TBY]
    tz = p[P_KZ] * ux * uy + p[P_TBZ]
    if p[P_ORB] != 0.0:
        mox = p[P_MOX]
        moy = p[P_MOY]
        moz = p[P_MOZ]
        c20 = s * (q1 * q3 - q0 * q2)
        c21 = s * (q2 * q3 + q0 * q1)
        c22 = 1.0 - s * (q1 * q1 + q2 * q2)
        tx += c00 * mox + c10 * moy + c20 * moz
        ty += c01 * mox + c11 * moy + c21 * moz
        tz += c02 * mox + c12 * moy + c22 * moz
    return tx, ty, tz


# =======================================================================================
# Splitting (integrators.splitting documents the method; this is the same arithmetic)
# =======================================================================================
@jit
def _axis_rotation(axis, beta, px, py, pz, q0, q1, q2, q3):
    """Exact flow of 1/2 c pi_axis^2 (beta = c pi_axis a): pi turns by -beta, q by +beta."""
    c2 = math.cos(0.5 * beta)
    s2 = math.sin(0.5 * beta)
    v = 2.0 * s2 * s2      # 1 - cos(beta), accurate for small beta
    sb = 2.0 * s2 * c2     # sin(beta)
    # pi' = pi - (v pi_perp -/+ sb ...): the rounding of cos(beta/2) near 1 does not scale |pi|
    # (with cos(beta) = c2^2 - s2^2 it would, by the same factor at every step: a drift)
    if axis == 0:
        npy = py - (v * py - sb * pz)
        npz = pz - (v * pz + sb * py)
        return (px, npy, npz,
                q0 * c2 - q1 * s2, q0 * s2 + q1 * c2, q2 * c2 + q3 * s2, q3 * c2 - q2 * s2)
    if axis == 1:
        npx = px - (v * px + sb * pz)
        npz = pz - (v * pz - sb * px)
        return (npx, py, npz,
                q0 * c2 - q2 * s2, q1 * c2 - q3 * s2, q0 * s2 + q2 * c2, q3 * c2 + q1 * s2)
    npx = px - (v * px - sb * py)
    npy = py - (v * py + sb * px)
    return (npx, npy, pz,
            q0 * c2 - q3 * s2, q1 * c2 + q2 * s2, q2 * c2 - q1 * s2, q0 * s2 + q3 * c2)


@jit_inline
def free_flow(p, a, px, py, pz, q0, q1, q2, q3):
    """Free rigid-body flow over time a, split as T = |pi|^2/(2 I_ref) + sum 1/2 c_i pi_i^2."""
    n = math.sqrt(px * px + py * py + pz * pz)
    if n > 0.0:
        half = 0.5 * (n * a * p[P_INVREF])
        c = math.cos(half)
        s = math.sin(half) / n
        r1 = s * px
        r2 = s * py
        r3 = s * pz
        n0 = q0 * c - q1 * r1 - q2 * r2 - q3 * r3
        n1 = q0 * r1 + q1 * c + q2 * r3 - q3 * r2
        n2 = q0 * r2 - q1 * r3 + q2 * c + q3 * r1
        n3 = q0 * r3 + q1 * r2 - q2 * r1 + q3 * c
        q0, q1, q2, q3 = n0, n1, n2, n3
    first = -1
    second = -1
    for axis in range(3):
        if p[P_CX + axis] != 0.0:
            if first < 0:
                first = axis
            else:
                second = axis
    if second >= 0:  # Strang: B_first(a/2) B_second(a) B_first(a/2)
        cf = p[P_CX + first]
        cs = p[P_CX + second]
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = _axis_rotation(first, cf * pi[first] * (0.5 * a), px, py, pz,
                                                    q0, q1, q2, q3)
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = _axis_rotation(second, cs * pi[second] * a, px, py, pz, q0,
                                                    q1, q2, q3)
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = _axis_rotation(first, cf * pi[first] * (0.5 * a), px, py, pz,
                                                    q0, q1, q2, q3)
    elif first >= 0:
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = _axis_rotation(first, p[P_CX + first] * pi[first] * a,
                                                    px, py, pz, q0, q1, q2, q3)
    return px, py, pz, q0, q1, q2, q3


@jit_inline
def split_flow(p, cfg, st, yo, po, to, t0, s0, h, yd, pd, td):
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
    for j in range(int(cfg[C_NG])):
        a = cfg[C_G + j] * h
        half = 0.5 * a
        px += half * tx
        py += half * ty
        pz += half * tz
        px, py, pz, q0, q1, q2, q3 = free_flow(p, a, px, py, pz, q0, q1, q2, q3)
        tx, ty, tz = body_torque(p, q0, q1, q2, q3, t0 + (s0 + cfg[C_CUM + j] * h))
        px += half * tx
        py += half * ty
        pz += half * tz
    st[pd] = px
    st[pd + 1] = py
    st[pd + 2] = pz
    st[yd] = px / p[P_IX]
    st[yd + 1] = py / p[P_IY]
    st[yd + 2] = pz / p[P_IZ]
    st[yd + 3] = q0
    st[yd + 4] = q1
    st[yd + 5] = q2
    st[yd + 6] = q3
    st[td] = tx
    st[td + 1] = ty
    st[td + 2] = tz


split_flow_called = called(split_flow)


@jit
def split_step_count(p, span, step, order, wx, wy, wz):
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
    if not span > 0.0:
        return 1.0
    # np.ceil stays a float (math.ceil is an int64 in numba: a span / step above 9e18
    # wrapped around to one step over the whole segment)
    n = max(1.0, np.ceil(span / step * (1.0 - 1e-12)))
    tb = math.sqrt(p[P_TBX] * p[P_TBX] + p[P_TBY] * p[P_TBY] + p[P_TBZ] * p[P_TBZ])
    mo = math.sqrt(p[P_MOX] * p[P_MOX] + p[P_MOY] * p[P_MOY] + p[P_MOZ] * p[P_MOZ])
    b = tb + mo
    if not b > 0.0:
        return n
    ix = p[P_IX]
    iy = p[P_IY]
    iz = p[P_IZ]
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


# =======================================================================================
# Segment set-up, steps, dense output
# =======================================================================================
@jit
def _rms(st, o, scale_o):
    """Return scipy's norm(x) = ||x|| / sqrt(n) of st[o:o+7] / st[scale_o:scale_o+7]."""
    acc = 0.0
    for i in range(N):
        v = st[o + i] / st[scale_o + i]
        acc += v * v
    return math.sqrt(acc) / N ** 0.5


@jit
def seg_init(p, cfg, st, t0, t_bound):
    """Start a segment [t0, t_bound] from the state already in st[O_Y:O_Y+7] (counters reset)."""
    st[S_T] = t0
    st[S_T0] = t0
    st[S_TOLD] = t0
    st[S_TBOUND] = t_bound
    span = t_bound - t0     # local time tau = t - t0 (integrators.base.Stepper.tau_bound)
    st[S_TAU] = 0.0
    st[S_TAUOLD] = 0.0
    st[S_TAUBOUND] = span
    st[S_NSTEPS] = 0.0
    st[S_NFEVDONE] += st[S_NFEV]   # evaluations of earlier segments (ensembles)
    st[S_NFEV] = 0.0
    st[S_FAIL] = FAIL_NONE
    st[S_FVALID] = 0.0
    st[S_DENSE] = 0.0
    st[S_STATUS] = FINISHED if t0 >= t_bound else RUNNING
    big = abs(span)
    st[S_COLLAPSE] = _MIN_STEP_ULPS * (np.nextafter(big, np.inf) - big)
    method = int(cfg[C_METHOD])
    if method == M_RK4 or method == M_SPLIT:
        if method == M_RK4:
            n = 1.0
            if span > 0:
                # np.ceil stays a float (math.ceil is an int64 in numba: a span / step above 9e18
                # wrapped around to one step over the whole segment)
                n = max(1.0, np.ceil(span / cfg[C_STEP] * (1.0 - 1e-12)))
        else:
            n = split_step_count(p, span, cfg[C_STEP], cfg[C_ORDER], st[O_Y], st[O_Y + 1],
                                 st[O_Y + 2])
        st[S_H] = span / n
        st[S_NTOTAL] = n
        if method == M_SPLIT:
            st[O_PI] = p[P_IX] * st[O_Y]
            st[O_PI + 1] = p[P_IY] * st[O_Y + 1]
            st[O_PI + 2] = p[P_IZ] * st[O_Y + 2]
            tx, ty, tz = body_torque(p, st[O_Y + 3], st[O_Y + 4], st[O_Y + 5], st[O_Y + 6],
                                     t0 + 0.0)
            st[O_TAU] = tx
            st[O_TAU + 1] = ty
            st[O_TAU + 2] = tz
    elif method == M_DOP853:
        if st[S_STATUS] != RUNNING:
            return  # scipy's solver is never built for an empty segment
        rtol = cfg[C_RTOL]
        atol = cfg[C_ATOL]
        rhs_called(p, t0, st, O_Y, O_F)
        st[S_FVALID] = 1.0
        # scipy.integrate._ivp.common.select_initial_step, direction = +1, order = 7
        for i in range(N):
            st[O_SCR + i] = atol + abs(st[O_Y + i]) * rtol      # scale
        d0 = _rms(st, O_Y, O_SCR)
        d1 = _rms(st, O_F, O_SCR)
        if d0 < 1e-5 or d1 < 1e-5:
            h0 = 1e-6
        else:
            h0 = 0.01 * d0 / d1
        if span < h0:
            h0 = span
        for i in range(N):
            st[O_TMP + i] = st[O_Y + i] + h0 * st[O_F + i]
        rhs_called(p, t0 + h0, st, O_TMP, O_YNEW)
        for i in range(N):
            st[O_YNEW + i] = st[O_YNEW + i] - st[O_F + i]
        d2 = _rms(st, O_YNEW, O_SCR) / h0
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
        if cfg[C_MAXSTEP] < h:
            h = cfg[C_MAXSTEP]
        st[S_H] = h
        st[S_NFEV] = 2.0


@jit_inline
def _rk4_step(p, st):
    h = st[S_H]
    tau = st[S_TAU]
    t0 = st[S_T0]
    if st[S_FVALID] == 0.0:
        rhs(p, t0 + tau, st, O_Y, O_F)
        st[S_NFEV] += 1.0
    k2 = O_K
    k3 = O_K + N
    k4 = O_K + 2 * N
    for i in range(N):
        st[O_TMP + i] = st[O_Y + i] + (0.5 * h) * st[O_F + i]
    rhs(p, t0 + (tau + 0.5 * h), st, O_TMP, k2)
    for i in range(N):
        st[O_TMP + i] = st[O_Y + i] + (0.5 * h) * st[k2 + i]
    rhs(p, t0 + (tau + 0.5 * h), st, O_TMP, k3)
    for i in range(N):
        st[O_TMP + i] = st[O_Y + i] + h * st[k3 + i]
    rhs(p, t0 + (tau + h), st, O_TMP, k4)
    st[S_NFEV] += 3.0
    for i in range(N):
        st[O_FOLD + i] = st[O_F + i]
        st[O_Y + i] = st[O_Y + i] + (h / 6.0) * (
            st[O_F + i] + 2.0 * (st[k2 + i] + st[k3 + i]) + st[k4 + i])
    st[S_TAUOLD] = tau
    # tau_k = k h (no accumulated rounding in t over millions of steps)
    st[S_TAU] = (st[S_TAUBOUND] if st[S_NSTEPS] + 1.0 >= st[S_NTOTAL]
                 else (st[S_NSTEPS] + 1.0) * h)
    st[S_FVALID] = 0.0
    return FAIL_NONE


@jit
def _dop853_step(p, cfg, st):
    """Take a step as scipy's RungeKutta._step_impl with DOP853's rk_step and error norm."""
    t = st[S_TAU]               # scipy's t is the local time (adaptive._ScipyStepper)
    t_bound = st[S_TAUBOUND]
    t0 = st[S_T0]
    rtol = cfg[C_RTOL]
    atol = cfg[C_ATOL]
    max_step = cfg[C_MAXSTEP]
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    h_abs = st[S_H]
    if h_abs > max_step:
        h_abs = max_step
    elif h_abs < min_step:
        h_abs = min_step
    rejected = False
    ns = _D_NSTAGES
    n_rejected = 0
    while True:
        if h_abs != h_abs:
            # NaN (a non-finite right-hand side at the segment start): every comparison below
            # is False, so without this the loop neither accepts nor fails, for ever
            return FAIL_STEP_NAN
        if h_abs < min_step:
            return FAIL_TOO_SMALL
        if n_rejected >= _MAX_REJECTIONS:
            return FAIL_REJECTED
        t_new = t + h_abs
        if t_new - t_bound > 0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        for i in range(N):
            st[O_K + i] = st[O_F + i]
        for s in range(1, ns):
            for i in range(N):
                acc = 0.0
                for j in range(s):
                    acc += st[O_K + j * N + i] * _D_A[s, j]
                st[O_TMP + i] = st[O_Y + i] + acc * h
            rhs(p, t0 + (t + _D_C[s] * h), st, O_TMP, O_K + s * N)
        for i in range(N):
            acc = 0.0
            for j in range(ns):
                acc += st[O_K + j * N + i] * _D_B[j]
            st[O_YNEW + i] = st[O_Y + i] + h * acc
        rhs(p, t0 + (t + h), st, O_YNEW, O_K + ns * N)
        st[S_NFEV] += float(ns)
        e5 = 0.0
        e3 = 0.0
        for i in range(N):
            ay = abs(st[O_Y + i])
            an = abs(st[O_YNEW + i])
            scale = atol + (an if an > ay else ay) * rtol
            a5 = 0.0
            a3 = 0.0
            for j in range(ns + 1):
                kj = st[O_K + j * N + i]
                a5 += kj * _D_E5[j]
                a3 += kj * _D_E3[j]
            a5 = a5 / scale
            a3 = a3 / scale
            e5 += a5 * a5
            e3 += a3 * a3
        e5 = math.sqrt(e5) ** 2
        e3 = math.sqrt(e3) ** 2
        if e5 == 0.0 and e3 == 0.0:
            err = 0.0
        else:
            err = abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * N)
        if err < 1.0:
            if err == 0.0:
                factor = _MAX_FACTOR
            else:
                factor = _SAFETY * err ** _ERR_EXP
                if not factor < _MAX_FACTOR:
                    factor = _MAX_FACTOR
            if rejected and not factor < 1.0:
                factor = 1.0
            h_abs *= factor
            break
        factor = _SAFETY * err ** _ERR_EXP
        if not factor > _MIN_FACTOR:
            factor = _MIN_FACTOR
        h_abs *= factor
        rejected = True
        n_rejected += 1
    st[S_HPREV] = h
    for i in range(N):
        st[O_Y + i] = st[O_YNEW + i]
        st[O_F + i] = st[O_K + ns * N + i]
    st[S_TAUOLD] = t
    st[S_TAU] = t_new
    st[S_H] = h_abs
    st[S_DENSE] = 0.0
    return FAIL_NONE


@jit_inline
def _split_step(p, cfg, st):
    h = st[S_H]
    tau = st[S_TAU]
    for i in range(3):
        st[O_TAUOLD + i] = st[O_TAU + i]
        st[O_PIOLD + i] = st[O_PI + i]
    split_flow(p, cfg, st, O_YOLD, O_PIOLD, O_TAUOLD, st[S_T0], tau, h, O_Y, O_PI, O_TAU)
    st[S_TAUOLD] = tau
    # tau_k = k h (no accumulated rounding in t over millions of steps)
    st[S_TAU] = (st[S_TAUBOUND] if st[S_NSTEPS] + 1.0 >= st[S_NTOTAL]
                 else (st[S_NSTEPS] + 1.0) * h)
    st[S_NFEV] += cfg[C_NG]
    return FAIL_NONE


@jit_inline
def step(p, cfg, st):
    """
    One step of the segment's method with the checks of ``integrators.base.Stepper.step``.

    Returns True on success; on failure the state is left at the last good step and
    st[S_FAIL] says why.
    """
    t_good = st[S_T]
    tau_good = st[S_TAU]
    tau_old_good = st[S_TAUOLD]
    for i in range(N):
        st[O_YOLD + i] = st[O_Y + i]
    method = int(cfg[C_METHOD])
    if method == M_RK4:
        code = _rk4_step(p, st)
    elif method == M_DOP853:
        code = _dop853_step(p, cfg, st)
    else:
        code = _split_step(p, cfg, st)
    if code == FAIL_NONE:
        # |y|^2 finite (integrators.base.Stepper.step): also refuses a finite state whose square
        # overflows, from which no rotation matrix, energy or attitude can be computed any more
        acc = 0.0
        for i in range(N):
            acc += st[O_Y + i] * st[O_Y + i]
        if not math.isfinite(acc):
            code = FAIL_NONFINITE
    if (code == FAIL_NONE and st[S_TAU] < st[S_TAUBOUND]
            and st[S_TAU] - tau_good <= st[S_COLLAPSE]):
        # the exact test of integrators.base, in local time (only reached for steps near the
        # bound)
        ulp = np.nextafter(abs(tau_good), np.inf) - abs(tau_good)
        if st[S_TAU] - tau_good <= _MIN_STEP_ULPS * ulp:
            code = FAIL_COLLAPSE
            st[S_FAILDT] = st[S_TAU] - tau_good
    if code != FAIL_NONE:
        st[S_T] = t_good
        st[S_TAU] = tau_good
        st[S_TAUOLD] = tau_old_good
        for i in range(N):
            st[O_Y + i] = st[O_YOLD + i]
        st[S_STATUS] = FAILED
        st[S_FAIL] = code
        st[S_FAILT] = t_good
        return False
    st[S_NSTEPS] += 1.0
    st[S_TOLD] = t_good
    # the absolute time handed out (integrators.base.Stepper.absolute)
    st[S_T] = st[S_TBOUND] if st[S_TAU] >= st[S_TAUBOUND] else st[S_T0] + st[S_TAU]
    if st[S_TAU] >= st[S_TAUBOUND]:
        st[S_STATUS] = FINISHED
    return True


@jit
def dense(p, cfg, st, t):
    """State at t in [t_old, t] of the last step, written to st[O_SCR:O_SCR+7]."""
    if t == st[S_T]:
        for i in range(N):
            st[O_SCR + i] = st[O_Y + i]
        return
    method = int(cfg[C_METHOD])
    # local time, kept inside the step (integrators.base.Stepper.state_at)
    t_old = st[S_TAUOLD]
    t = min(max(t - st[S_T0], t_old), st[S_TAU])
    if method == M_RK4:
        # cubic Hermite (fixed_step.RK4._state_at_impl); needs f at the end of the step
        if st[S_FVALID] == 0.0:
            rhs_called(p, st[S_T0] + st[S_TAU], st, O_Y, O_F)
            st[S_FVALID] = 1.0
            st[S_NFEV] += 1.0
        h = st[S_TAU] - t_old
        s = (t - t_old) / h
        h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
        h10 = s * (1.0 - s) ** 2
        h01 = s * s * (3.0 - 2.0 * s)
        h11 = s * s * (s - 1.0)
        for i in range(N):
            st[O_SCR + i] = (h00 * st[O_YOLD + i] + (h10 * h) * st[O_FOLD + i]
                             + h01 * st[O_Y + i] + (h11 * h) * st[O_F + i])
    elif method == M_DOP853:
        if st[S_DENSE] == 0.0:
            h = st[S_HPREV]
            for s in range(_D_NSTAGES + 1, _D_NEXT):
                for i in range(N):
                    acc = 0.0
                    for j in range(s):
                        acc += st[O_K + j * N + i] * _D_A[s, j]
                    st[O_TMP + i] = st[O_YOLD + i] + acc * h
                rhs_called(p, st[S_T0] + (t_old + _D_C[s] * h), st, O_TMP, O_K + s * N)
                st[S_NFEV] += 1.0
            for i in range(N):
                delta = st[O_Y + i] - st[O_YOLD + i]
                f_old = st[O_K + i]
                st[O_FD + i] = delta
                st[O_FD + N + i] = h * f_old - delta
                st[O_FD + 2 * N + i] = 2 * delta - h * (st[O_F + i] + f_old)
                for r in range(4):
                    acc = 0.0
                    for j in range(_D_NEXT):
                        acc += _D_D[r, j] * st[O_K + j * N + i]
                    st[O_FD + (3 + r) * N + i] = h * acc
            st[S_DENSE] = 1.0
        x = (t - t_old) / (st[S_TAU] - t_old)
        for i in range(N):
            y = 0.0
            for k in range(7):
                y += st[O_FD + (6 - k) * N + i]
                if k % 2 == 0:
                    y *= x
                else:
                    y *= 1 - x
            st[O_SCR + i] = y + st[O_YOLD + i]
    else:
        # splitting: a step of the same method from the start of the step, of length t - t_old
        split_flow_called(p, cfg, st, O_YOLD, O_PIOLD, O_TAUOLD, st[S_T0], t_old, t - t_old,
                          O_SCR, O_TMP, O_TMP + 3)


# =======================================================================================
# Euler-angle tracking and output (Propagator._track_euler / _unwrapped)
# =======================================================================================
@jit
def _unwrap(angle, reference):
    return angle + _TWO_PI * round((reference - angle) / _TWO_PI)


@jit
def unwrapped_euler(st, o, track):
    """
    Return the paper's (phi, psi, theta) of quaternion st[o+3:o+7].

    phi and psi are unwrapped towards track (``Propagator._unwrapped``).
    """
    q0 = st[o + 3]
    q1 = st[o + 4]
    q2 = st[o + 5]
    q3 = st[o + 6]
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c00 = 1.0 - s * (q2 * q2 + q3 * q3)
    c02 = s * (q1 * q3 + q0 * q2)
    c10 = s * (q1 * q2 + q0 * q3)
    c12 = s * (q2 * q3 - q0 * q1)
    c20 = s * (q1 * q3 - q0 * q2)
    c21 = s * (q2 * q3 + q0 * q1)
    c22 = 1.0 - s * (q1 * q1 + q2 * q2)
    # rotation.matrix_to_euler(r) with r = C^T
    sth = math.hypot(c20, c21)
    theta = math.atan2(sth, c22)
    if sth < 1e-300:
        phi = math.atan2(c10, c00)
        psi = 0.0
    else:
        psi = math.atan2(c20, c21)
        phi = math.atan2(c02, -c12)
    return _unwrap(phi, track[0]), _unwrap(psi, track[1]), theta


@jit
def set_track(st, o, track):
    """
    Set track to the unwrapped Euler angles of st[o:o+7], unless they are not finite.

    Not finite: a dense output inside a step whose state ran away (``Propagator._unwrapped``
    returns None).
    """
    phi, psi, theta = unwrapped_euler(st, o, track)
    if math.isfinite(phi) and math.isfinite(psi) and math.isfinite(theta):
        track[0] = phi
        track[1] = psi
        track[2] = theta


@jit_inline
def track_increment(st):
    """
    Return a bound on how far phi, psi turned during the last step [rad].

    As ``Propagator._track_euler``: |w| / max(0.1, sin theta) times the step.
    """
    wx = st[O_Y]
    wy = st[O_Y + 1]
    wz = st[O_Y + 2]
    w = math.sqrt(wx ** 2 + wy ** 2 + wz ** 2)
    q1 = st[O_Y + 4]
    q2 = st[O_Y + 5]
    q0 = st[O_Y + 3]
    q3 = st[O_Y + 6]
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    cos_theta = 1.0 - s * (q1 * q1 + q2 * q2)
    sin_theta = math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
    rate = w / max(_UNWRAP_MIN_SIN, sin_theta)
    return rate * (st[S_T] - st[S_TOLD])


@jit
def track_update(p, cfg, st, track, increment):
    """
    Update the track through the last step (the reference's subdivision).

    It first catches up from wherever it was left at the start of the step (see
    :func:`track_euler`). Returns the number of dense-output evaluations it took (work, at
    most _MAX_TRACK_PIECES - 1).
    """
    if st[S_BUDGET] > 0.0:
        set_track(st, O_YOLD, track)
    st[S_BUDGET] = 0.0
    t = st[S_T]
    t_old = st[S_TOLD]
    h = t - t_old
    pieces = increment / _UNWRAP_STEP
    if not pieces <= _MAX_TRACK_PIECES:
        # a step far too long for the spin (or a state running away): follow it in at most
        # this many pieces (bounded work per step; propagator._track_euler does the same)
        n = _MAX_TRACK_PIECES
    else:
        n = max(1, int(math.ceil(pieces)))
    for j in range(1, n + 1):
        if j == n:
            o = O_Y
        else:
            dense(p, cfg, st, t_old + h * j / n)
            o = O_SCR
        set_track(st, o, track)
    return n - 1


@jit_inline
def track_euler(p, cfg, st, track):
    """
    Follow phi, psi continuously through the step just taken (``Propagator._track_euler``).

    The reference updates the track at the end of every step, subdividing steps over which
    phi or psi may turn by more than ~1 rad (bound: :func:`track_increment`). Here the bound
    is accumulated over steps and the track is updated only when it would pass 1 rad (from
    the start of the step, then through the step as the reference does), or by
    :func:`refresh_track`: the track is then never more than 1 rad of bound away from the
    state, so every unwrapped angle gets the same 2 pi multiple as on the reference path,
    while most steps skip the three atan2 of the conversion. Returns the dense-output
    evaluations taken (work).
    """
    increment = track_increment(st)
    if st[S_BUDGET] + increment < _UNWRAP_STEP:
        st[S_BUDGET] += increment
        return 0
    return track_update(p, cfg, st, track, increment)


@jit
def refresh_track(st, track):
    """Bring a lazily updated track to the current state (see :func:`track_euler`)."""
    if st[S_BUDGET] > 0.0:
        set_track(st, O_Y, track)
        st[S_BUDGET] = 0.0


@jit
def emit(p, cfg, st, track, t_out, y_out, e_out, k):
    """Write every output t_out[k:] <= t (state and unwrapped Euler angles); returns the new k."""
    n_out = t_out.shape[0]
    while k < n_out and t_out[k] <= st[S_T]:
        tk = t_out[k]
        if tk == st[S_T]:
            o = O_Y
        else:
            dense(p, cfg, st, tk)
            o = O_SCR
        for i in range(N):
            y_out[k, i] = st[o + i]
        phi, psi, theta = unwrapped_euler(st, o, track)
        e_out[k, 0] = phi
        e_out[k, 1] = psi
        e_out[k, 2] = theta
        k += 1
    return k


@jit
def advance(p, cfg, st, track, t_target, t_out, y_out, e_out, k, budget):
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
    k = emit(p, cfg, st, track, t_out, y_out, e_out, k)
    steps = 0
    work = 0
    while st[S_STATUS] == RUNNING and st[S_T] < t_target and work < budget:
        ok = step(p, cfg, st)
        if not ok:
            break
        steps += 1
        work += 1 + track_euler(p, cfg, st, track)
        if k < n_out and t_out[k] <= st[S_T]:  # (no call, no array reference counting, otherwise)
            k = emit(p, cfg, st, track, t_out, y_out, e_out, k)
    refresh_track(st, track)
    return k, steps, work


# =======================================================================================
# Ensembles: many bodies, each with its own segments (impact sequences)
# =======================================================================================
@jit
def body_advance(cfg, probs, seg_t, first, last, cur, st, track, t_stop, t_out, y_out, e_out, k):
    """
    Advance one body through its segments probs[first:last] until t >= t_stop.

    A new segment starts where the propagator would start it (``Propagator.advance_to``).
    Returns (cur, k, steps).
    """
    steps = 0
    while True:
        k = emit(probs[cur], cfg, st, track, t_out, y_out, e_out, k)
        if st[S_T] >= t_stop or st[S_STATUS] == FAILED:
            break
        if st[S_STATUS] == FINISHED:
            if cur + 1 >= last:
                break
            cur += 1
            seg_init(probs[cur], cfg, st, st[S_T], seg_t[cur, 1])
            continue
        k, n, _ = advance(probs[cur], cfg, st, track, t_stop, t_out, y_out, e_out, k, np.inf)
        steps += n
    return cur, k, steps


@jit
def ensemble_advance(cfg, probs, seg_t, seg_ptr, cur, states, tracks, t_stop, t_out, y_out, e_out,
                     k_out, steps_out, b0, b1):
    """
    Run body_advance for bodies b0 .. b1-1.

    Releases the GIL: blocks of bodies run in parallel Python threads, see ensemble.py.
    """
    for b in range(b0, b1):
        c, k, n = body_advance(cfg, probs, seg_t, seg_ptr[b], seg_ptr[b + 1], cur[b], states[b],
                               tracks[b], t_stop, t_out, y_out[b], e_out[b], k_out[b])
        cur[b] = c
        k_out[b] = k
        steps_out[b] += n


@jit
def ensemble_init(cfg, probs, seg_t, seg_ptr, states, b0, b1):
    """seg_init of the first segment of bodies b0 .. b1-1 (their states hold y0)."""
    for b in range(b0, b1):
        s = seg_ptr[b]
        seg_init(probs[s], cfg, states[b], seg_t[s, 0], seg_t[s, 1])

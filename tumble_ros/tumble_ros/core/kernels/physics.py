"""
The physics every method runs: total torque, Euler-Liouville right-hand side, free flow.

Written once, in the subset numba compiles; the compiled loops inline these functions and the
reference steppers call them from Python (``dynamics``, ``integrators.splitting``). Arguments:
``p`` a segment's problem (layout :data:`~.layout.PR`), ``extra`` the extra torques
(:func:`~tumble_ros.core.torques.extra_torque_arrays`), t the absolute time [yr], q the
attitude quaternion (body -> orbital), omega [rad/yr] and torques in body axes.
"""
from __future__ import annotations

import math

from tumble_ros.core.compiling.jit import called, jit, jit_inline
from tumble_ros.core.kernels.layout import Array, Extra, PR
from tumble_ros.core.torques.frames import orbital_to_body
from tumble_ros.core.torques.gravity_gradient import sun_in_orbit_plane, tidal_torque
from tumble_ros.core.torques.pulses import pulse_torque
from tumble_ros.core.trig import sin_cos

__all__ = ['body_torque', 'torque_given_sun', 'plain_torque_given_sun', 'rhs', 'derivatives',
           'rhs_called', 'free_flow', 'axis_rotation', 'axis_turn', 'pi_turn', 'flow_pieces']


@jit_inline
def body_torque(p: Array, extra: Extra, t: float, q0: float, q1: float, q2: float,
                q3: float) -> tuple[float, float, float]:
    """
    Return the total torque on the body (body axes) at time t and attitude q.

    The sum of the components: the circular-orbit gravity gradient, the segment's pulse, and
    every extra torque (each called with its own parameter row).
    """
    sx, sy = sun_in_orbit_plane(p[PR.ORBIT_RATE], t)
    return torque_given_sun(p, extra, t, sx, sy, q0, q1, q2, q3)


@jit_inline
def torque_given_sun(p: Array, extra: Extra, t: float, sx: float, sy: float, q0: float,
                     q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """
    :func:`body_torque` given the Sun's direction (sx, sy, 0) in the orbital frame at t.

    (sx, sy) = ``sun_in_orbit_plane(p[PR.ORBIT_RATE], t)``: the same for every body at t, so
    an ensemble stepped in lockstep computes it once per stage (``kernels.lockstep``).
    """
    ux, uy, uz = orbital_to_body(sx, sy, 0.0, q0, q1, q2, q3)
    tx, ty, tz = tidal_torque(p[PR.TIDAL], p[PR.TIDAL + 1], p[PR.TIDAL + 2], ux, uy, uz)
    bx, by, bz = pulse_torque(p[PR.PULSE_BODY], p[PR.PULSE_BODY + 1], p[PR.PULSE_BODY + 2],
                              p[PR.HAS_ORBITAL], p[PR.PULSE_ORBITAL], p[PR.PULSE_ORBITAL + 1],
                              p[PR.PULSE_ORBITAL + 2], q0, q1, q2, q3)
    tx += bx
    ty += by
    tz += bz
    if extra is not None:  # (None: numba compiles the loop away)
        functions, parameters = extra
        for j in range(parameters.shape[0]):
            ex, ey, ez = functions[j](parameters[j], t, q0, q1, q2, q3)
            tx += ex
            ty += ey
            tz += ez
    return tx, ty, tz


@jit_inline
def plain_torque_given_sun(p: Array, sx: float, sy: float, q0: float, q1: float, q2: float,
                           q3: float) -> tuple[float, float, float]:
    """
    :func:`torque_given_sun` on a segment without orbital-frame pulse and without extra torque.

    p[PR.HAS_ORBITAL] 0 and ``extra`` None: the gravity gradient plus the body-fixed pulse,
    its operations in its order (the same bits), without its branches. For the loops over a
    block of bodies (``rk4.block_rhs``, ``splitting.block_step``): LLVM left
    torque_given_sun's test of p[PR.HAS_ORBITAL] inside the vectorised loop, ~20 % of an rk4
    right-hand side.
    """
    ux, uy, uz = orbital_to_body(sx, sy, 0.0, q0, q1, q2, q3)
    tx, ty, tz = tidal_torque(p[PR.TIDAL], p[PR.TIDAL + 1], p[PR.TIDAL + 2], ux, uy, uz)
    return tx + p[PR.PULSE_BODY], ty + p[PR.PULSE_BODY + 1], tz + p[PR.PULSE_BODY + 2]


@jit_inline
def rhs(p: Array, extra: Extra, t: float, st: Array, yo: int, oo: int) -> None:
    """
    Write f(t, y) for y = st[yo:yo+7] to st[oo:oo+7]: the quaternion-attitude equations.

    Euler's equations (paper eq 14, third line corrected: docs/paper.md, correction 1) with the
    total torque M: I dw/dt = (I w) x w + M, i.e. dwx/dt = (Iy - Iz)/Ix wy wz + Mx/Ix, ...; and
    the kinematics dq/dt = 1/2 q * (0, w).
    """
    wx = st[yo]
    wy = st[yo + 1]
    wz = st[yo + 2]
    q0 = st[yo + 3]
    q1 = st[yo + 4]
    q2 = st[yo + 5]
    q3 = st[yo + 6]
    tx, ty, tz = body_torque(p, extra, t, q0, q1, q2, q3)
    (st[oo], st[oo + 1], st[oo + 2], st[oo + 3], st[oo + 4], st[oo + 5],
     st[oo + 6]) = derivatives(p, wx, wy, wz, q0, q1, q2, q3, tx, ty, tz)


@jit_inline
def derivatives(p: Array, wx: float, wy: float, wz: float, q0: float, q1: float, q2: float,
                q3: float, tx: float, ty: float, tz: float
                ) -> tuple[float, float, float, float, float, float, float]:
    """Return f(t, y) of :func:`rhs` given the total torque (tx, ty, tz) at (t, y)."""
    return (p[PR.EULER] * wy * wz + tx * p[PR.INV_INERTIA],
            p[PR.EULER + 1] * wz * wx + ty * p[PR.INV_INERTIA + 1],
            p[PR.EULER + 2] * wx * wy + tz * p[PR.INV_INERTIA + 2],
            0.5 * (-q1 * wx - q2 * wy - q3 * wz),
            0.5 * (q0 * wx + q2 * wz - q3 * wy),
            0.5 * (q0 * wy - q1 * wz + q3 * wx),
            0.5 * (q0 * wz + q1 * wy - q2 * wx))


#: :func:`rhs` compiled on its own, for cold paths and for the reference steppers.
rhs_called = called(rhs)


@jit
def axis_rotation(axis: int, beta: float, px: float, py: float, pz: float, q0: float, q1: float,
                  q2: float, q3: float) -> tuple[float, float, float, float, float, float, float]:
    """Exact flow of 1/2 c pi_axis^2 (beta = c pi_axis a): pi turns by -beta, q by +beta."""
    s2, c2 = sin_cos(0.5 * beta)
    return axis_turn(axis, c2, s2, px, py, pz, q0, q1, q2, q3)


@jit_inline
def axis_turn(axis: int, c2: float, s2: float, px: float, py: float, pz: float, q0: float,
              q1: float, q2: float, q3: float
              ) -> tuple[float, float, float, float, float, float, float]:
    """:func:`axis_rotation` given c2 = cos(beta / 2), s2 = sin(beta / 2): no libm call."""
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
def pi_turn(c: float, s: float, px: float, py: float, pz: float, q0: float, q1: float,
            q2: float, q3: float) -> tuple[float, float, float, float]:
    """
    Turn q about pi: the |pi|^2 part of the free flow, given c = cos(half), s = sin(half) / |pi|.

    half = |pi| a / (2 I_ref) (:func:`free_flow`); no libm call.
    """
    r1 = s * px
    r2 = s * py
    r3 = s * pz
    n0 = q0 * c - q1 * r1 - q2 * r2 - q3 * r3
    n1 = q0 * r1 + q1 * c + q2 * r3 - q3 * r2
    n2 = q0 * r2 - q1 * r3 + q2 * c + q3 * r1
    n3 = q0 * r3 + q1 * r2 - q2 * r1 + q3 * c
    return n0, n1, n2, n3


@jit_inline
def flow_pieces(p: Array) -> tuple[int, int]:
    """
    Return the (first, second) axes of the free flow's axis pieces (-1: none).

    The axes i with c_i = p[PR.FLOW + i] != 0, at most two (c_ref is 0): :func:`free_flow`
    composes B_first(a/2) B_second(a) B_first(a/2), or B_first(a) alone.
    """
    first = -1
    second = -1
    for axis in range(3):
        if p[PR.FLOW + axis] != 0.0:
            if first < 0:
                first = axis
            else:
                second = axis
    return first, second


@jit_inline
def free_flow(p: Array, a: float, px: float, py: float, pz: float, q0: float, q1: float,
              q2: float, q3: float) -> tuple[float, float, float, float, float, float, float]:
    """
    Return the free rigid body's exact-per-piece flow over time a: (pi, q) after it.

    T = |pi|^2/(2 I_ref) + sum 1/2 c_i pi_i^2 (``integrators.splitting``): the |pi|^2 part
    turns q about pi, the axis pieces are composed symmetrically.
    """
    n = math.sqrt(px * px + py * py + pz * pz)
    if n > 0.0:
        half = 0.5 * (n * a * p[PR.INV_REF])
        s, c = sin_cos(half)
        q0, q1, q2, q3 = pi_turn(c, s / n, px, py, pz, q0, q1, q2, q3)
    first, second = flow_pieces(p)
    if second >= 0:  # Strang: B_first(a/2) B_second(a) B_first(a/2)
        cf = p[PR.FLOW + first]
        cs = p[PR.FLOW + second]
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = axis_rotation(first, cf * pi[first] * (0.5 * a), px, py, pz,
                                                   q0, q1, q2, q3)
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = axis_rotation(second, cs * pi[second] * a, px, py, pz, q0,
                                                   q1, q2, q3)
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = axis_rotation(first, cf * pi[first] * (0.5 * a), px, py, pz,
                                                   q0, q1, q2, q3)
    elif first >= 0:
        pi = (px, py, pz)
        px, py, pz, q0, q1, q2, q3 = axis_rotation(first, p[PR.FLOW + first] * pi[first] * a,
                                                   px, py, pz, q0, q1, q2, q3)
    return px, py, pz, q0, q1, q2, q3

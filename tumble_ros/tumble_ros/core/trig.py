"""
The kernels' sin and cos (and the Euler angles' atan2): plain arithmetic, the same bits vectorised.

Below the torques and the kernels in core (both import it): the flow's rotation angles and the
Sun's direction (``torques.gravity_gradient.sun_in_orbit_plane``) take :func:`sin_cos`.

Why not libm's
--------------
The splitting's free flow needs sin/cos of two or three angles a body and step. glibc's
``sincos`` is a call LLVM cannot vectorise (numba has no vector maths library here), so a block
of bodies stepped together (``kernels.lockstep``) stopped at each angle for a scalar call: about a
third of a body-step. glibc's vector ``libmvec`` or SVML would vectorise, but their last bits
differ from the scalar ``sin``/``cos`` a single body's run takes, and a tumbling body's phase
turns such a difference into a growing trajectory error. :func:`sin_cos` is written in plain
float64 arithmetic (no fused multiply-add: numba does not contract without ``fastmath``), so
LLVM vectorises it across bodies with exactly the scalar operations in every lane, and every
kernel calls it: an ensemble body keeps the bits of its own run.

The algorithm
-------------
FreeBSD's and musl's ``sin``/``cos`` (from Sun's fdlibm, whose coefficients these are): the
argument is reduced to r = x - n pi/2, |r| <= pi/4, in two parts (``PIO2_1`` holds pi/2's first
33 bits, so n ``PIO2_1`` is exact for |n| < 2^20; r = y0 + y1 carries ~85 bits), then the
minimax polynomials of ``__sin`` and ``__cos`` on [-pi/4, pi/4] (errors below 2^-58 and
2^-58.6 relative to the functions) with the tail y1, and the quadrant n mod 4 picks and signs
them. Every result is within 1 ulp of libm's, and ~97 % are libm's own bits
(tests/test_core_trig.py, from 1e-12 rad to the limit and beside every k pi/2). Arguments with
|x| >= :data:`REDUCED_LIMIT`, infinities and NaN go to libm (:func:`sin_cos`): the rotation
angles of a step are far below it.

atan2 for the Euler angles
--------------------------
:func:`atan2` is fdlibm's ``atan2``/``atan`` (FreeBSD's and musl's; the same coefficients) in
the same plain arithmetic, its branches turned into selects so that LLVM vectorises it: t = |y/x|
(one division), reduced by a second one to one of five intervals (atan t = atan c +
atan((t - c) / (1 + c t)) with c = 0, 1/2, 1, 3/2 or infinity, atan c in two parts), then
fdlibm's odd polynomial of degree 23 and the quadrant. Within 1 ulp of libm's ``atan2``, ~92 %
of the test's results libm's own bits, signed zeros, infinities and NaN as libm
(tests/test_core_trig.py). It is the Euler angles' (``kernels.tracking.euler_of``: every
sample's phi, psi and theta, and every track update), so that a sample's bodies are converted
together in one vectorised pass (``kernels.lockstep.block_euler``) with each body's own bits;
the samples' angles are then within 1 ulp of libm's conversion for phi and psi and 2 ulp for
theta (tests/test_core_tracking.py; docs/physics.md, Euler angles).
"""
from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit_inline

__all__ = ['sin_cos', 'sin_cos_reduced', 'scaled_sin_cos_rows', 'sin_cos_rows', 'REDUCED_LIMIT',
           'SMALL', 'atan2']

#: |x| [rad] below which :func:`sin_cos_reduced` is used (n pi/2 with |n| < 2^19 fits
#: PIO2_1's 33 bits exactly); libm above it.
REDUCED_LIMIT = 524288.0 * 1.5707963267948966
#: |x| [rad] below which x * 2/pi rounds to n = 0 (pi/4 = 0.785398...): no reduction needed.
SMALL = 0.785

_INV_PIO2 = 6.36619772367581382433e-01   # 2/pi
_TO_INT = 6755399441055744.0             # 1.5 * 2^52: x + it - it rounds x to an integer
_PIO2_1 = 1.57079632673412561417e+00     # first 33 bits of pi/2
_PIO2_2 = 6.07710050630396597660e-11     # the next 33 bits of pi/2
_PIO2_2T = 2.02226624879595063154e-21    # pi/2 - PIO2_1 - PIO2_2
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


@jit_inline
def _sin_cos_of_reduced(y0: float, y1: float) -> tuple[float, float]:
    """Return (sin, cos) of y0 + y1, |y0| <= pi/4 [rad]: fdlibm's ``__sin`` and ``__cos``."""
    z = y0 * y0
    zz = z * z
    rs = _S2 + z * (_S3 + z * _S4) + z * zz * (_S5 + z * _S6)
    v = z * y0
    s = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * _S1)
    rc = z * (_C1 + z * (_C2 + z * _C3)) + zz * zz * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    wc = 1.0 - hz
    c = wc + (((1.0 - wc) - hz) + (z * rc - y0 * y1))
    return s, c


@jit_inline
def sin_cos_reduced(x: float) -> tuple[float, float]:
    """
    Return (sin x, cos x) for |x| < :data:`REDUCED_LIMIT` [rad]: branch-free, vectorisable.

    Outside that range the result is meaningless (:func:`sin_cos` routes it to libm).
    """
    fn = (x * _INV_PIO2 + _TO_INT) - _TO_INT
    t = x - fn * _PIO2_1                 # exact: fn has at most 20 bits, PIO2_1 33
    w = fn * _PIO2_2                     # exact too
    r = t - w
    w = fn * _PIO2_2T - ((t - r) - w)    # what r lost, and the rest of pi/2
    y0 = r - w
    y1 = (r - y0) - w
    s, c = _sin_cos_of_reduced(y0, y1)
    # the quadrant n mod 4 from fn in floating point (an integer conversion and a switch kept
    # LLVM from vectorising the loop): odd n swaps sin and cos, n mod 4 in {2, 3} negates the
    # sine, n mod 4 in {1, 2} the cosine
    half_n = 0.5 * fn
    odd = half_n != math.floor(half_n)
    quarter_n = 0.25 * fn
    quadrant = quarter_n - math.floor(quarter_n)     # 0, 0.25, 0.5 or 0.75: exact
    sin_r = c if odd else s
    cos_r = s if odd else c
    sin_x = -sin_r if quadrant >= 0.5 else sin_r
    cos_x = -cos_r if (quadrant == 0.25) | (quadrant == 0.5) else cos_r
    return sin_x, cos_x


@jit_inline
def sin_cos(x: float) -> tuple[float, float]:
    """
    Return (sin x, cos x) [x in rad]: :func:`sin_cos_reduced`'s bits, or libm beyond its range.

    Below :data:`SMALL` it skips the reduction, whose result there is y0 = x, y1 = 0 and
    quadrant 0 exactly (the same bits, one chain of operations shorter: a body's rotation
    angles in a step are small, and the single-body loops take this function one call at a
    time).
    """
    if abs(x) < SMALL:
        return _sin_cos_of_reduced(x, 0.0)
    if abs(x) < REDUCED_LIMIT:
        return sin_cos_reduced(x)
    return math.sin(x), math.cos(x)


@jit_inline
def scaled_sin_cos_rows(scale: float, x: npt.NDArray[np.float64],
                        sin_out: npt.NDArray[np.float64], cos_out: npt.NDArray[np.float64],
                        m: int) -> None:
    """
    Write sin, cos of scale * x[i] [rad] to sin_out[i], cos_out[i], i < m: :func:`sin_cos`'s bits.

    A vectorised pass of :func:`sin_cos_reduced` over all m, then libm for the angles beyond
    its range (a check an angle; none in practice). Below :data:`SMALL` the reduction gives
    :func:`sin_cos`'s unreduced bits exactly (see there).
    """
    for i in range(m):
        s, c = sin_cos_reduced(scale * x[i])
        sin_out[i] = s
        cos_out[i] = c
    for i in range(m):
        angle = scale * x[i]
        if not abs(angle) < REDUCED_LIMIT:
            sin_out[i] = math.sin(angle)
            cos_out[i] = math.cos(angle)


@jit_inline
def sin_cos_rows(x: npt.NDArray[np.float64], sin_out: npt.NDArray[np.float64],
                 cos_out: npt.NDArray[np.float64], m: int) -> None:
    """
    Write sin, cos of x[i] [rad] to sin_out[i], cos_out[i], i < m: :func:`sin_cos`'s bits.

    For rows of angles mostly below :data:`SMALL` (a step's rotation angles): when every
    |x[i]| < SMALL, one vectorised pass of the polynomials without the reduction, whose result
    there is y0 = x, y1 = 0 and quadrant 0 exactly (:func:`sin_cos`'s short path, the same
    bits); otherwise :func:`scaled_sin_cos_rows`. The test is a count, which LLVM vectorises
    (a float comparison's ``or`` or ``max`` across lanes it would not, without ``fastmath``).
    """
    large = 0
    for i in range(m):
        large += 0 if abs(x[i]) < SMALL else 1    # (NaN: large)
    if large != 0:
        scaled_sin_cos_rows(1.0, x, sin_out, cos_out, m)
        return
    for i in range(m):
        s, c = _sin_cos_of_reduced(x[i], 0.0)
        sin_out[i] = s
        cos_out[i] = c


_ATAN_HI0 = 4.63647609000806093515e-01   # atan(1/2), its first 53 bits
_ATAN_HI1 = 7.85398163397448278999e-01   # atan(1)
_ATAN_HI2 = 9.82793723247329054082e-01   # atan(3/2)
_ATAN_HI3 = 1.57079632679489655800e+00   # atan(inf) = pi/2
_ATAN_LO0 = 2.26987774529616870924e-17   # ... and the rest of each
_ATAN_LO1 = 3.06161699786838301793e-17
_ATAN_LO2 = 1.39033110312309984516e-17
_ATAN_LO3 = 6.12323399573676603587e-17
_AT0 = 3.33333333333329318027e-01
_AT1 = -1.99999999998764832476e-01
_AT2 = 1.42857142725034663711e-01
_AT3 = -1.11111104054623557880e-01
_AT4 = 9.09088713343650656196e-02
_AT5 = -7.69187620504482999495e-02
_AT6 = 6.66107313738753120669e-02
_AT7 = -5.83357013379057348645e-02
_AT8 = 4.97687799461593236017e-02
_AT9 = -3.65315727442169155270e-02
_AT10 = 1.62858201153657823623e-02
_PI = 3.14159265358979311600e+00          # pi, its first 53 bits
_PI_LO = 1.22464679914735317720e-16       # pi - _PI
#: |y/x| above which atan2 is +-pi/2 whatever the sign of x (fdlibm's 2^60).
_HUGE_RATIO = 1152921504606846976.0


@jit_inline
def _atan_nonnegative(t: float) -> float:
    """Return atan t for t >= 0 (inf: pi/2; NaN: NaN) [rad]: fdlibm's ``atan``, branch-free."""
    small = t < 0.4375
    if t < 0.6875:       # atan(1/2) + atan((2t - 1) / (2 + t))
        num = 2.0 * t - 1.0
        den = 2.0 + t
        hi = _ATAN_HI0
        lo = _ATAN_LO0
    elif t < 1.1875:     # atan(1) + atan((t - 1) / (t + 1))
        num = t - 1.0
        den = t + 1.0
        hi = _ATAN_HI1
        lo = _ATAN_LO1
    elif t < 2.4375:     # atan(3/2) + atan((t - 3/2) / (1 + 3/2 t))
        num = t - 1.5
        den = 1.0 + 1.5 * t
        hi = _ATAN_HI2
        lo = _ATAN_LO2
    else:                # pi/2 + atan(-1 / t)   (also inf and NaN)
        num = -1.0
        den = t
        hi = _ATAN_HI3
        lo = _ATAN_LO3
    # below 7/16 no reduction: hi - ((r s - 0) - r) is fdlibm's r - r s, bit for bit
    num = t if small else num
    den = 1.0 if small else den
    hi = 0.0 if small else hi
    lo = 0.0 if small else lo
    r = num / den
    z = r * r
    w = z * z
    s1 = z * (_AT0 + w * (_AT2 + w * (_AT4 + w * (_AT6 + w * (_AT8 + w * _AT10)))))
    s2 = w * (_AT1 + w * (_AT3 + w * (_AT5 + w * (_AT7 + w * _AT9))))
    return hi - ((r * (s1 + s2) - lo) - r)


@jit_inline
def atan2(y: float, x: float) -> float:
    """
    Return the angle of point (x, y) [rad] in [-pi, pi], within 1 ulp of libm's ``atan2``.

    Branch-free, vectorisable. fdlibm's special cases through the one path: |y| = |x| = 0 or
    inf are given the ratio 0 or 1 (atan2(+-0, +-0) = +-0 or +-pi, atan2(+-inf, +-inf) =
    +-pi/4 or +-3 pi/4), x = 0 the ratio inf; a ratio above 2^60 (x = 0 or y infinite
    included) is +-pi/2 whatever the sign of x; NaN in, NaN out.
    """
    ax = abs(x)
    ay = abs(y)
    both_inf = (ax == math.inf) & (ay == math.inf)
    x_zero = ax == 0.0
    num = 1.0 if both_inf else ay
    den = 1.0 if both_inf | x_zero else ax    # (no division by zero: the Python path raises)
    t = num / den
    t = (0.0 if ay == 0.0 else ay * math.inf) if x_zero else t
    z = _atan_nonnegative(t)
    x_negative = (math.copysign(1.0, x) < 0.0) & (not t > _HUGE_RATIO)
    r = _PI - (z - _PI_LO) if x_negative else z
    return -r if math.copysign(1.0, y) < 0.0 else r

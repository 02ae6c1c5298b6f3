"""
The kernels' sin and cos: one function of plain arithmetic, the same bits one body or many.

Why not libm's
--------------
The splitting's free flow needs sin/cos of two or three angles a body and step. glibc's
``sincos`` is a call LLVM cannot vectorise (numba has no vector maths library here), so a block
of bodies stepped together (:mod:`.lockstep`) stopped at each angle for a scalar call: about a
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
"""
from __future__ import annotations

import math

from tumble_ros.core.jit import jit_inline

__all__ = ['sin_cos', 'sin_cos_reduced', 'REDUCED_LIMIT', 'SMALL']

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

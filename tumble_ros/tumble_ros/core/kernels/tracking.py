"""
Continuous Euler angles: the paper's (phi, psi, theta) followed through every step.

phi and psi are angles of a rotation and jump by 2 pi where atan2 wraps; the samples need them
continuous, so the track (phi, psi, theta) is updated often enough that no update turns phi or
psi by more than ~1 rad (:data:`UNWRAP_STEP`): a bound on their rate is |w| / sin(theta),
capped at |w| / :data:`UNWRAP_MIN_SIN` (below theta ~ 0.1 only phi + psi is well defined).
The reference path (``Propagator``) and the compiled loop (``stepping``) use these functions.

One conversion (:func:`euler_of`) serves the samples and the track updates, in plain float64
arithmetic: ``trig.atan2`` for phi, psi and theta, sin theta = sqrt(c20^2 + c21^2) where the
squares neither underflow nor overflow, the degenerate branch as selects. So it has no call
and LLVM vectorises it across a block's bodies (``lockstep.block_euler``), each lane with the
scalar function's bits: an ensemble body keeps its own run's outputs. The rare rest (theta
within ~3e-151 of 0 or pi, NaN, infinities) takes ``hypot`` (:func:`euler_band`). Its angles
are within 1 ulp of libm's ``atan2`` on the same matrix entries for phi and psi and 2 ulp for
theta (tests/test_core_tracking.py); the track only sets the 2 pi multiple
k = round((track - angle) / 2 pi) of a sample, and with the angle within ~1 rad of its track
an ulp cannot move k (docs/physics.md). The lockstep loop's track updates take the same phi
and psi without theta (:func:`track_angles`, :func:`follow`).
"""
from __future__ import annotations

import math

from tumble_ros.core.compiling.jit import jit, jit_inline
from tumble_ros.core.kernels.layout import Array, ST
from tumble_ros.core.trig import atan2

__all__ = ['UNWRAP_STEP', 'UNWRAP_MIN_SIN', 'MAX_TRACK_PIECES', 'unwrap_towards', 'euler_of',
           'euler_parts', 'euler_band', 'euler_finish', 'PLAIN_LOW', 'PLAIN_HIGH', 'follow',
           'track_angles', 'settle', 'TRACK_SKIP', 'TRACK_SET', 'TRACK_BAND',
           'unwrapped_euler', 'set_track', 'track_to', 'track_rate', 'track_pieces',
           'refresh_track']

#: Largest turn of phi or psi between two track updates [rad].
UNWRAP_STEP = 1.0
#: sin(theta) below which the rate bound stops growing.
UNWRAP_MIN_SIN = 0.1
#: Most pieces a single step is cut into to follow phi and psi (bounded work per step: a step
#: far too long for the spin, or a state running away, is followed in this many pieces).
MAX_TRACK_PIECES = 100_000
_TWO_PI = 2.0 * math.pi
_MIN_SIN_SQUARED = UNWRAP_MIN_SIN * UNWRAP_MIN_SIN


@jit
def unwrap_towards(angle: float, reference: float) -> float:
    """Return angle + 2 pi k nearest to ``reference`` [rad]."""
    return angle + _TWO_PI * round((reference - angle) / _TWO_PI)


@jit_inline
def _rotation_parts(q0: float, q1: float, q2: float, q3: float
                    ) -> tuple[float, float, float, float, float, float, float]:
    """Return C's entries (c00, c02, c10, c12, c20, c21, c22) of quaternion q (body to orbital)."""
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c00 = 1.0 - s * (q2 * q2 + q3 * q3)
    c02 = s * (q1 * q3 + q0 * q2)
    c10 = s * (q1 * q2 + q0 * q3)
    c12 = s * (q2 * q3 - q0 * q1)
    c20 = s * (q1 * q3 - q0 * q2)
    c21 = s * (q2 * q3 + q0 * q1)
    c22 = 1.0 - s * (q1 * q1 + q2 * q2)
    return c00, c02, c10, c12, c20, c21, c22


#: sin theta below which phi alone is defined (psi = 0): C's (c20, c21) of norm below it.
_DEGENERATE_SIN = 1e-300
#: max(|c20|, |c21|) within which sin theta is sqrt(c20^2 + c21^2) in plain arithmetic
#: (:func:`euler_parts`): the larger square is normal (>= 2^-1000: the smaller one's rounding,
#: even subnormal, is 2^-75 of it) and the sum finite. Outside it (theta within ~3e-151 of 0 or
#: pi, where the degenerate branch lies too) and for NaN, ``hypot`` (:func:`euler_band`).
PLAIN_LOW = 2.0 ** -500
PLAIN_HIGH = 2.0 ** 500


@jit_inline
def _phi_psi(c00: float, c02: float, c10: float, c12: float, c20: float, c21: float,
             degenerate: bool) -> tuple[float, float]:
    """Return phi, psi [rad] in [-pi, pi] from C's entries (psi = 0 if ``degenerate``): selects."""
    phi = atan2(c10 if degenerate else c02, c00 if degenerate else -c12)
    psi = atan2(c20, c21)
    return phi, 0.0 if degenerate else psi


@jit_inline
def euler_parts(q0: float, q1: float, q2: float, q3: float
                ) -> tuple[float, float, float, float]:
    """
    Return the paper's (phi, psi, theta) [rad] of quaternion q, wrapped, and 1.0 if they hold.

    0.0: max(|c20|, |c21|) is outside [:data:`PLAIN_LOW`, :data:`PLAIN_HIGH`] or NaN, and
    :func:`euler_band` gives the angles. No call, no branch (sin theta = sqrt(c20^2 + c21^2),
    ``trig.atan2``): the lockstep loop takes it vectorised on a block's columns
    (``lockstep.block_euler``).
    """
    c00, c02, c10, c12, c20, c21, c22 = _rotation_parts(q0, q1, q2, q3)
    a20 = abs(c20)
    a21 = abs(c21)
    plain = ((a20 <= PLAIN_HIGH) & (a21 <= PLAIN_HIGH)
             & ((a20 >= PLAIN_LOW) | (a21 >= PLAIN_LOW)))   # (NaN: False)
    theta = atan2(math.sqrt(c20 * c20 + c21 * c21), c22)
    phi, psi = _phi_psi(c00, c02, c10, c12, c20, c21, False)   # (sin theta >= PLAIN_LOW)
    return phi, psi, theta, 1.0 if plain else 0.0


@jit
def euler_band(q0: float, q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """
    :func:`euler_parts` where it does not hold: sin theta = ``hypot`` (c20, c21) [rad].

    Below :data:`_DEGENERATE_SIN` only phi is defined (psi = 0). Called, not inlined: theta
    within ~3e-151 of 0 or pi, or a state that ran away (NaN, infinities), only.
    """
    c00, c02, c10, c12, c20, c21, c22 = _rotation_parts(q0, q1, q2, q3)
    sth = math.hypot(c20, c21)
    phi, psi = _phi_psi(c00, c02, c10, c12, c20, c21, sth < _DEGENERATE_SIN)
    return phi, psi, atan2(sth, c22)


@jit_inline
def euler_finish(phi: float, psi: float, theta: float, plain: float, q0: float, q1: float,
                 q2: float, q3: float, phi_ref: float, psi_ref: float
                 ) -> tuple[float, float, float]:
    """
    Return :func:`euler_parts`' angles of q [rad] (:func:`euler_band`'s unless ``plain``).

    phi and psi unwrapped towards phi_ref, psi_ref: :func:`euler_of`'s second half.
    """
    if plain == 0.0:
        phi, psi, theta = euler_band(q0, q1, q2, q3)
    return unwrap_towards(phi, phi_ref), unwrap_towards(psi, psi_ref), theta


@jit
def euler_of(q0: float, q1: float, q2: float, q3: float, phi_ref: float,
             psi_ref: float) -> tuple[float, float, float]:
    """
    Return the paper's (phi, psi, theta) [rad] of quaternion (q0, q1, q2, q3).

    phi and psi are unwrapped towards phi_ref, psi_ref (z-x-z, orbital -> body; the
    rotation.matrix_to_euler of C^T: with its libm ``atan2`` and ``hypot``, wrapped phi and psi
    within 1 ulp, theta within 2, unwrapped within 2: tests/test_core_tracking.py). The one
    conversion, :func:`euler_parts`
    then :func:`euler_finish`: :func:`unwrapped_euler` (a state's row) and :func:`track_to`
    call it, and the lockstep loop takes its two halves on a block's columns
    (``lockstep.block_euler``, ``block_emit``). Called, not inlined: each inlined copy of its
    three ``trig.atan2`` costs seconds of a first run's compiling.
    """
    phi, psi, theta, plain = euler_parts(q0, q1, q2, q3)
    return euler_finish(phi, psi, theta, plain, q0, q1, q2, q3, phi_ref, psi_ref)


#: :func:`track_angles`' verdicts: set the track, leave it (a state that ran away), or take
#: the band's ``hypot`` (:func:`follow`).
TRACK_SKIP = 0.0
TRACK_SET = 1.0
TRACK_BAND = 2.0


@jit_inline
def track_angles(q0: float, q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """
    Return phi, psi [rad] in [-pi, pi] of quaternion q for a track, and what to do with them.

    The verdict: :data:`TRACK_SET`, :data:`TRACK_SKIP` (c22 NaN: theta would not be finite),
    or :data:`TRACK_BAND`: the degenerate branch is not decided without ``hypot`` (phi, psi
    then meaningless: :func:`follow` computes them again). No call, no branch: the lockstep
    loop takes it vectorised on the bodies due (``lockstep.block_track``).
    """
    c00, c02, c10, c12, c20, c21, c22 = _rotation_parts(q0, q1, q2, q3)
    a20 = abs(c20)
    a21 = abs(c21)
    # hypot(c20, c21) < 1e-300 is decided by max(|c20|, |c21|) <= hypot <= sqrt(2) max
    # outside [0.5e-300, 1e-300), by hypot inside (and NaN: neither comparison holds)
    regular = (a20 >= _DEGENERATE_SIN) | (a21 >= _DEGENERATE_SIN)
    degenerate = (a20 < 0.5 * _DEGENERATE_SIN) & (a21 < 0.5 * _DEGENERATE_SIN)
    phi, psi = _phi_psi(c00, c02, c10, c12, c20, c21, degenerate)
    verdict = TRACK_SKIP if math.isnan(c22) else TRACK_SET
    return phi, psi, verdict if regular | degenerate else TRACK_BAND


@jit_inline
def settle(phi: float, psi: float, verdict: float, track: Array) -> None:
    """Unwrap phi, psi towards the track and set it if ``verdict`` and they allow it."""
    phi = unwrap_towards(phi, track[0])
    psi = unwrap_towards(psi, track[1])
    if verdict == TRACK_SET and math.isfinite(phi) and math.isfinite(psi):
        track[0] = phi
        track[1] = psi


@jit
def follow(q0: float, q1: float, q2: float, q3: float, track: Array) -> None:
    """
    :func:`track_to` for a track whose theta is never read: phi and psi only, the same bits.

    The same phi, psi and the same rule (set unless phi, psi and theta are finite), without
    theta's ``atan2`` and mostly without ``hypot``: atan2(y, x) is NaN exactly when y or x is,
    and finite otherwise, so theta = atan2(sin theta, c22) is finite unless c22 is NaN or
    sin theta is, and a NaN sin theta (c20 or c21 NaN) makes psi NaN already. The branch
    hypot(c20, c21) < 1e-300 is decided by max(|c20|, |c21|) <= hypot <= sqrt(2) max
    outside [0.5e-300, 1e-300), by hypot inside (:func:`track_angles`). The lockstep loop's
    tracks (``lockstep.block_track``, ``block_refresh``), which no output reads but as the
    references of phi and psi, take it: track[2] keeps its first value there. Called, not
    inlined: it runs on the rare bodies ``lockstep.block_track``'s vectorised pass leaves (the
    hypot band) and once a body at the end of a call (``block_refresh``), and its four
    ``trig.atan2`` inlined into every method's copies of those loops cost ~15 s of compiling
    a method and variant (benchmarks/HISTORY.md, "The warm-up in parts").
    """
    phi, psi, verdict = track_angles(q0, q1, q2, q3)
    if verdict == TRACK_BAND:   # (also NaN: hypot NaN or inf, not below)
        phi, psi, theta = euler_band(q0, q1, q2, q3)
        # (theta NaN: c22 or hypot NaN; a NaN hypot, with c20 or c21 NaN, makes psi NaN too)
        verdict = TRACK_SKIP if math.isnan(theta) else TRACK_SET
    settle(phi, psi, verdict, track)


@jit
def unwrapped_euler(st: Array, o: int, track: Array) -> tuple[float, float, float]:
    """
    Return the paper's (phi, psi, theta) of quaternion st[o+3:o+7] [rad].

    phi and psi are unwrapped towards track[0], track[1] (:func:`euler_of`).
    """
    return euler_of(st[o + 3], st[o + 4], st[o + 5], st[o + 6], track[0], track[1])


@jit
def set_track(st: Array, o: int, track: Array) -> None:
    """
    Set track to the unwrapped Euler angles of st[o:o+7], unless they are not finite.

    Not finite: a dense output inside a step whose state ran away (skipped).
    """
    track_to(st[o + 3], st[o + 4], st[o + 5], st[o + 6], track)


@jit_inline
def track_to(q0: float, q1: float, q2: float, q3: float, track: Array) -> None:
    """
    Set track to the unwrapped Euler angles of quaternion q (:func:`set_track`'s rule).

    :func:`euler_of`'s, the samples' conversion: the track's phi and psi are the references
    towards which they are unwrapped.
    """
    phi, psi, theta = euler_of(q0, q1, q2, q3, track[0], track[1])
    if math.isfinite(phi) and math.isfinite(psi) and math.isfinite(theta):
        track[0] = phi
        track[1] = psi
        track[2] = theta


@jit_inline
def track_rate(wx: float, wy: float, wz: float, q0: float, q1: float, q2: float,
               q3: float) -> float:
    """Return the bound |w| / max(UNWRAP_MIN_SIN, sin theta) on how fast phi, psi turn [rad/yr]."""
    # one square root and one division (they were most of the bound's cost in a vectorised
    # pass): with n = |q|^2 and a = q1^2 + q2^2, cos theta = 1 - 2 a / n, so
    # n^2 sin^2 theta = 4 a (n - a) and |w| / max(m, sin theta) = |w| n / max(m n, n sin theta)
    w2 = wx * wx + wy * wy + wz * wz
    n = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    a = q1 * q1 + q2 * q2
    return math.sqrt(w2 * (n * n) / max(_MIN_SIN_SQUARED * (n * n), 4.0 * a * (n - a)))


@jit
def track_pieces(angle: float) -> int:
    """Return how many pieces a step is followed in (1 .. MAX_TRACK_PIECES), from its bound."""
    pieces = angle / UNWRAP_STEP
    # (not <=: also an infinite rate, |w| overflowing in a state running away)
    if not pieces <= MAX_TRACK_PIECES:
        return MAX_TRACK_PIECES
    return max(1, int(math.ceil(pieces)))


@jit
def refresh_track(st: Array, track: Array) -> None:
    """Bring a lazily updated track to the current state (see ``stepping.track_euler``)."""
    if st[ST.BUDGET] > 0.0:
        set_track(st, ST.Y, track)
        st[ST.BUDGET] = 0.0

"""
The Euler angles' conversion (core/kernels/tracking.py): plain arithmetic, within ulps of libm's.

Every sample's (phi, psi, theta) and every track update converts a quaternion by
``tracking.euler_of``: ``trig.atan2`` (fdlibm's, plain float64 arithmetic) for the three
angles and sin theta = sqrt(c20^2 + c21^2) where the squares neither underflow nor overflow,
so that the lockstep loop converts a block's bodies in one vectorised pass with each body's own
bits. Main's code took libm's ``atan2`` and ``hypot``; that conversion is written here
(:func:`libm_euler`) as the independent reference: phi and psi within 1 ulp, theta within 2.
The track is only the reference of a sample's unwrapping, k = round((track - angle) / 2 pi),
and the angle lies within ~1 rad of its track, so an ulp of the track cannot move k: no
sample's 2 pi multiple moves. Main's outputs are computed by the kernels' own Python source
with libm's conversion put back (a subprocess with numba disabled), not hard-coded.
"""
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from tumble_ros.core import kernels
from tumble_ros.core.compiling.jit import called, python_source
from tumble_ros.core.kernels import tracking
from tumble_ros.core.kernels.layout import BK, BT, ST

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')

#: Runs the mixed block of test_core_lockstep.py in lockstep and body by body, as plain Python,
#: every conversion (samples and tracks) libm's atan2 and hypot (main's code) if told 'libm';
#: prints the samples and how many of the atan2 calls differ from trig.atan2's bits.
_SUBPROCESS = r"""
import json, math, sys
import numpy as np
from tumble_ros.core import kernels
from tumble_ros.core import trig
from tumble_ros.core.kernels import lockstep, tracking
sys.path.insert(0, sys.argv[1])
from test_core_tracking import run_bodies
calls = [0, 0]
plain = trig.atan2
def libm_atan2(y, x):
    calls[0] += 1
    a, b = math.atan2(y, x), plain(y, x)
    calls[1] += int(a != b and not (math.isnan(a) and math.isnan(b)))
    return a
def libm_parts(q0, q1, q2, q3):
    # main's euler_of: hypot, the degenerate branch, atan2 (euler_band, its atan2 libm's)
    phi, psi, theta = tracking.euler_band(q0, q1, q2, q3)
    return phi, psi, theta, 1.0
if sys.argv[2] == 'libm':
    tracking.atan2 = libm_atan2
    tracking.euler_parts = lockstep.euler_parts = libm_parts
out = run_bodies(json.loads(sys.argv[3]))
out['compiled'] = kernels.COMPILED
out['calls'] = calls
print(json.dumps(out))
"""

CASES = [('splitting', 2e-3), ('splitting', 5e-2), ('rk4', 2e-3)]


def run_bodies(cases):
    """Return every case's Euler angles, omega and quaternion samples, lockstep and per body."""
    sys.path.insert(0, os.path.dirname(__file__))
    from test_core_lockstep import E, fig9, INTEGRATORS

    omega0 = np.array([[0.1, 0.1, 30.0], [0.01, -0.02, 0.3], [3.0, -2.0, 300.0],
                       [20.0, 5.0, -30.0], [1e-3, 0.0, 1e-3], [50.0, 50.0, 100.0],
                       [0.0, 0.0, -200.0], [30.0, 0.0, 0.5]])
    euler0 = np.array([[0.5, 0.0, 0.9], [1.0, 2.0, 1e-3], [0.3, -1.0, 1e-6],
                       [-2.0, 0.5, np.pi - 1e-3], [0.0, 0.0, 0.1], [3.0, 3.0, 1.5],
                       [-3.1, 3.1, 2e-2], [0.0, 0.0, 1.5]])
    t_eval = np.unique(np.concatenate([np.linspace(0.0, 1.0, 81), [0.1001, 0.33333]]))
    out = {}
    for method, step in cases:
        sc = fig9(method, step, duration=1.0)
        for loop in ('lockstep', 'compiled'):
            run = getattr(E, f'_ensemble_{loop}')
            ens = run(sc, t_eval, len(omega0), None, omega0, euler0, INTEGRATORS[method], None,
                      1, 1)
            out[f'{method} {step} {loop}'] = {name: getattr(ens, name).tolist()
                                              for name in ('euler', 'omega', 'quaternion')}
    return out


def subprocess_run(atan2):
    """run_bodies as plain Python (numba disabled), the track's atan2 libm's or trig's."""
    args = [sys.executable, '-c', _SUBPROCESS, os.path.dirname(__file__), atan2,
            json.dumps(CASES)]
    env = dict(os.environ, NUMBA_DISABLE_JIT='1')
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out['compiled'] is False
    return out


def ulps(got, want):
    """|got - want| in units of the last place of want (of 5e-324 at 0); NaN where both are."""
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    both = np.isnan(got) & np.isnan(want)
    spacing = np.spacing(np.maximum(np.abs(np.where(both, 1.0, want)), 5e-324))
    return np.where(both, np.nan, np.abs(got - want) / spacing)


@needs_numba
def test_every_sample_is_mains_conversion_within_its_ulps_and_no_2pi_multiple_moved():
    """
    The samples of main's conversion (libm's atan2 and hypot everywhere) and this one's.

    Spins from 1e-3 to ~300 rad/yr (phi or psi through tens of turns), theta near 0 and pi,
    ``splitting`` with one-piece track updates (the lockstep loop's gathered pass) and updates
    in pieces, ``rk4``; the lockstep and per-body loops, compiled here against plain Python
    with libm's conversion put back. omega and the quaternion bit for bit (the angles feed
    nothing back), phi, psi and theta within 2 ulp of main's (1 ulp of the wrapped angle and
    the 2 pi multiple's rounding): no 2 pi multiple moved, though the tracks and the samples
    differed in their last bits on the way.
    """
    here = run_bodies(CASES)
    main = subprocess_run('libm')
    n_calls, n_differ = main.pop('calls')
    main.pop('compiled')
    assert n_calls > 10_000 and n_differ > 100   # the conversions' bits were not main's
    assert sorted(here) == sorted(main)
    moved = 0
    for key, fields in here.items():
        for name, values in fields.items():
            a, b = np.array(values), np.array(main[key][name])
            assert a.shape == b.shape, (key, name)
            if name == 'euler':
                assert np.array_equal(np.isnan(a), np.isnan(b)), key
                assert np.nanmax(ulps(a, b)) <= 2.0, key
                moved += np.sum(a != b)
                continue
            assert np.array_equal(a, b, equal_nan=True), (key, name)
    assert moved > 100
    euler = np.array(here['splitting 0.002 lockstep']['euler'])
    assert np.ptp(euler[2, :, 1]) > 40 * np.pi       # psi of the fast body: many turns
    assert np.nanmin(euler[:, :, 2]) < 1e-2 and np.nanmax(euler[:, :, 2]) > np.pi - 1e-2


def quaternion_multiply(a, b):
    """Hamilton product a b of rows of quaternions (scalar first)."""
    a0, a1, a2, a3 = a.T
    b0, b1, b2, b3 = b.T
    return np.column_stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0])


def libm_euler(q, phi_ref=0.0, psi_ref=0.0):
    """
    Main's conversion of quaternion q: libm's atan2 and hypot on C's entries [rad].

    rotation.matrix_to_euler of C^T, written out on C's entries as the kernels compute them
    (their own function, run as Python: the same bits, so that what differs is the
    conversion), phi and psi unwrapped towards phi_ref, psi_ref as ``tracking.unwrap_towards``
    (not if not finite).
    """
    q0, q1, q2, q3 = (float(v) for v in q)
    c00, c02, c10, c12, c20, c21, c22 = python_source(tracking._rotation_parts)(q0, q1, q2, q3)
    sth = math.hypot(c20, c21)
    theta = math.atan2(sth, c22)
    if sth < 1e-300:
        phi, psi = math.atan2(c10, c00), 0.0
    else:
        phi, psi = math.atan2(c02, -c12), math.atan2(c20, c21)

    def unwrap(angle, reference):
        if not math.isfinite(angle):
            return angle
        return angle + 2.0 * math.pi * round((reference - angle) / (2.0 * math.pi))
    return unwrap(phi, phi_ref), unwrap(psi, psi_ref), theta


@needs_numba
def test_a_track_an_ulp_away_unwraps_a_sample_to_the_same_angles():
    """
    A sample after a track update, its attitude turned by up to ~1 rad: the same 2 pi multiple.

    Main's track update converted by libm's atan2 and hypot (:func:`libm_euler`), this
    code's ``set_track`` by ``tracking.euler_of``: on 20,000 random attitudes (references tens
    of turns away) the tracks differ in their last bit for > 1 %, the samples unwrapped
    towards them never; and the sample's angles are main's within 2 ulp.
    """
    rng = np.random.default_rng(5)
    n = 20_000
    q = rng.normal(size=(n, 4))
    turn = rng.normal(size=(n, 3))
    half = rng.uniform(0.0, 0.5, n)        # half the angle of a turn of up to 1 rad
    axis = turn / np.linalg.norm(turn, axis=1)[:, None]
    dq = np.column_stack([np.cos(half), np.sin(half)[:, None] * axis])
    sample = quaternion_multiply(q, dq)
    st = np.zeros(ST.SIZE)
    differ = 0
    for i in range(n):
        reference = np.array([rng.uniform(-200, 200), rng.uniform(-200, 200), 0.0])
        here = reference.copy()
        st[3:7] = q[i]
        tracking.set_track(st, 0, here)
        main = np.array(libm_euler(q[i], reference[0], reference[1]))
        differ += here[0] != main[0] or here[1] != main[1]
        st[3:7] = sample[i]
        got = tracking.unwrapped_euler(st, 0, here)
        want = tracking.unwrapped_euler(st, 0, main)
        assert got == want, (q[i], sample[i], reference)
        assert ulps(got, libm_euler(sample[i], main[0], main[1])).max() <= 2.0
    assert differ > 0.01 * n


#: Compiled on their own: the scalar conversion, its vectorisable half (and its verdict).
EULER_OF = called(tracking.euler_of)
EULER_PARTS = called(tracking.euler_parts)


def attitudes(seed=3, n=20_000):
    """
    Return quaternions of every kind the conversion meets (rows, scalar first).

    Random (scaled 1e-3 to 1e5), theta near 0 and near pi (down to 1e-17 rad), across the
    degenerate branch's 1e-300 and the plain range's 2^-500 (both sides), C's exact 0, 1 and
    -1, signed zeros, NaN and infinities.
    """
    rng = np.random.default_rng(seed)
    random = rng.normal(size=(n, 4)) * 10.0 ** rng.uniform(-3, 5, (n, 1))
    small = 10.0 ** rng.uniform(-17, -1, (n // 4, 1))
    near_0 = rng.normal(size=(n // 4, 4))
    near_0[:, 1:3] *= small                 # q1, q2 small: c22 ~ 1
    near_pi = rng.normal(size=(n // 4, 4))
    near_pi[:, [0, 3]] *= small             # q0, q3 small: c22 ~ -1
    edges = np.array([1e-300, 0.5e-300, tracking.PLAIN_LOW, 2.0 * tracking.PLAIN_LOW])
    tiny = np.concatenate([np.geomspace(1e-302, 1e-140, 400), edges,
                           np.nextafter(edges, 0.0), np.nextafter(edges, 1.0)])
    one, zero = np.ones_like(tiny), np.zeros_like(tiny)
    band = np.vstack([np.column_stack([one, zero, tiny, zero]),      # c20 = -2 tiny, c21 = 0
                      np.column_stack([one, tiny, tiny, zero]),      # |(c20, c21)| ~ 2.8 tiny
                      np.column_stack([tiny, one, zero, zero]),      # theta ~ pi: c21 = 2 tiny
                      np.column_stack([tiny, one, zero, tiny])])     # c20 = c21 = 2 tiny
    special = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-0.0, -0.0, 1.0, 0.0],
               [0.0, 0.0, 0.0, -1.0], [np.nan, 0.0, 0.0, 1.0], [1.0, np.nan, 0.0, 0.0],
               [np.inf, 0.0, 0.0, 0.0], [1.0, np.inf, 1.0, 0.0], [1.0, 1.0, -np.inf, 0.0],
               [1e200, 1e200, 0.0, 0.0], [1e200, 0.0, 0.0, 0.0]]
    return np.vstack([random, near_0, near_pi, band, special])


@needs_numba
def test_the_conversion_is_within_one_ulp_of_libms_for_phi_and_psi_and_two_for_theta():
    """
    ``tracking.euler_of`` against main's conversion (:func:`libm_euler`) on :func:`attitudes`.

    Wrapped (references 0): phi and psi within 1 ulp, theta within 2 (sqrt(c20^2 + c21^2)
    against hypot, then atan2), so within 4.5e-16 relative; unwrapped towards references
    hundreds of turns away, within 2 ulp of the result (the same 2 pi multiple). The degenerate
    branch (psi = 0) exactly where main's, NaN exactly where main's, both sides of the plain
    range's limit reached, and most results main's own bits.
    """
    q = attitudes()
    rng = np.random.default_rng(4)
    refs = rng.uniform(-3e3, 3e3, (len(q), 2))
    got = np.array([EULER_OF(*map(float, r), 0.0, 0.0) for r in q])
    want = np.array([libm_euler(r) for r in q])
    assert np.array_equal(np.isnan(got), np.isnan(want))
    bound = np.array([1.0, 1.0, 2.0])
    error = ulps(got, want)
    assert np.all(np.nanmax(error, axis=0) <= bound), np.nanmax(error, axis=0)
    finite = np.isfinite(want) & (want != 0.0)
    assert np.all(np.abs(got - want)[finite] <= 4.5e-16 * np.abs(want[finite]))
    assert np.mean(got == want) > 0.7 and np.mean(got != want) > 0.05
    assert np.array_equal(got[:, 1] == 0.0, want[:, 1] == 0.0)
    assert np.sum(want[:, 1] == 0.0) > 10   # (the degenerate branch, and psi = atan2(0, c21))
    unwrapped = np.array([EULER_OF(*map(float, r), a, b) for r, (a, b) in zip(q, refs)])
    main = np.array([libm_euler(r, a, b) for r, (a, b) in zip(q, refs)])
    assert np.nanmax(ulps(unwrapped, main)) <= 2.0
    assert np.nanmax(np.abs(unwrapped[:, :2])) > 2e3
    plain = np.array([EULER_PARTS(*map(float, r))[3] for r in q])
    tiny = (np.all(np.abs(q[:, 1:3]) < 1e-100, axis=1)
            | np.all(np.abs(q[:, [0, 3]]) < 1e-100, axis=1))
    assert 0 < np.sum(tiny & (plain == 1.0)) and 0 < np.sum(tiny & (plain == 0.0))
    assert np.all(plain[np.isnan(want).any(axis=1)] == 0.0)


@needs_numba
def test_the_vectorised_euler_pass_gives_the_scalar_bits():
    """
    ``lockstep.block_euler`` (a block's columns) gives ``euler_parts``' bits body by body.

    LLVM vectorises the pass: a copy compiled here has packed square roots and divisions.
    """
    import numba
    from tumble_ros.core.kernels.lockstep import block_euler

    q = attitudes(seed=6, n=2000)
    src = np.zeros((BK.SIZE, len(q)))
    src[BK.Y + 3:BK.Y + 7] = q.T
    tmp = np.zeros((BT.SIZE, len(q)))
    block_euler(src, tmp, len(q))
    scalar = np.array([EULER_PARTS(*map(float, r)) for r in q])
    assert tmp[BT.EULER:BT.EULER + 4].T.tobytes() == scalar.tobytes()

    @numba.njit(error_model='numpy')
    def many(q, out):
        for i in range(q.shape[1]):
            out[0, i], out[1, i], out[2, i], out[3, i] = tracking.euler_parts(
                q[0, i], q[1, i], q[2, i], q[3, i])

    out = np.empty((4, len(q)))
    many(np.ascontiguousarray(q.T), out)
    assert out.tobytes() == tmp[BT.EULER:BT.EULER + 4].tobytes()
    asm = next(iter(many.inspect_asm().values()))
    assert re.search(r'vsqrtpd\s+%[xyz]mm', asm) and re.search(r'vdivpd\s+%[xyz]mm', asm)


@pytest.mark.parametrize('budget', [0.0, 0.6])
@pytest.mark.parametrize('increment', [0.0, 0.4, 1.0])
def test_a_track_update_of_a_step_in_one_piece_converts_its_start_and_keeps_its_bound(
        budget, increment):
    """
    ``stepping.track_update`` of a step of bound <= 1 rad: one conversion, the bound kept.

    The track catches up to the step's start (unless it was left there: budget 0) and the
    step's bound becomes the budget, so the track stays within 1 rad of bound of the state
    (a budget of 0 here would let the next update come ~1 rad of bound later than that).
    """
    from tumble_ros.core.kernels import stepping

    rng = np.random.default_rng(7)
    start, end = rng.normal(size=4), rng.normal(size=4)
    st = np.zeros(ST.SIZE)
    st[ST.Y_OLD + 3:ST.Y_OLD + 7] = start
    st[ST.Y + 3:ST.Y + 7] = end
    st[ST.BUDGET] = budget
    track = np.array([123.4, -56.7, 0.8])
    want = track.copy()
    if budget > 0.0:
        converted = np.zeros(ST.SIZE)
        converted[3:7] = start
        tracking.set_track(converted, 0, want)
        assert not np.array_equal(want, track)     # (the catch-up moves it)
    work = python_source(stepping.track_update)(None, None, None, st, track, increment)
    assert work == 0
    assert track.tobytes() == want.tobytes()
    assert st[ST.BUDGET] == increment

"""
The Euler track's own atan2 (core/kernels/tracking.py, trig.atan2): no output bit moves.

A track update converts a quaternion with ``trig.atan2`` (plain arithmetic, vectorised across
the bodies due in the lockstep loop) where main's code took libm's ``atan2``; a sample's angles
keep libm's (``tracking.euler_of``). The track is only the reference of a sample's unwrapping,
k = round((track - angle) / 2 pi), and the angle lies within ~1 rad of its track, so an ulp of
the track cannot move k: every sample is main's. Main's outputs are computed here by the
kernels' own Python source with libm's ``atan2`` put back into the track (a subprocess with
numba disabled), not hard-coded.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from tumble_ros.core import kernels
from tumble_ros.core.kernels import tracking
from tumble_ros.core.kernels.layout import ST

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')

#: Runs the mixed block of test_core_lockstep.py in lockstep and body by body, as plain Python,
#: its tracks converted by libm's atan2 (main's code) unless told 'plain'; prints the samples
#: and how many of the track's atan2 calls differ from trig.atan2's bits.
_SUBPROCESS = r"""
import json, math, sys
import numpy as np
from tumble_ros.core import kernels
from tumble_ros.core import trig
from tumble_ros.core.kernels import tracking
sys.path.insert(0, sys.argv[1])
from test_core_tracking import run_bodies
calls = [0, 0]
plain = trig.atan2
def libm_atan2(y, x):
    calls[0] += 1
    a, b = math.atan2(y, x), plain(y, x)
    calls[1] += int(a != b and not (math.isnan(a) and math.isnan(b)))
    return a
if sys.argv[2] == 'libm':
    tracking.atan2 = libm_atan2
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


@needs_numba
def test_every_sample_is_mains_whose_tracks_took_libms_atan2():
    """
    The samples of bodies whose tracks took libm's atan2 (main) and trig's (here): identical.

    Spins from 1e-3 to ~300 rad/yr (phi or psi through tens of turns), theta near 0 and pi,
    ``splitting`` with one-piece updates (the lockstep loop's gathered pass) and updates in
    pieces, ``rk4``; the lockstep and per-body loops, compiled here against plain Python with
    libm's atan2 in the track. The tracks did differ in their last bits on the way.
    """
    here = run_bodies(CASES)
    main = subprocess_run('libm')
    n_calls, n_differ = main.pop('calls')
    main.pop('compiled')
    assert n_calls > 10_000 and n_differ > 100   # the tracks' bits were not main's
    assert sorted(here) == sorted(main)
    for key, fields in here.items():
        for name, values in fields.items():
            a, b = np.array(values), np.array(main[key][name])
            if name == 'euler':
                # theta reads no track; as plain Python it takes CPython's math.hypot, not
                # libm's (1 ulp apart at times): phi and psi, the unwrapped ones, bit for bit
                assert np.array_equal(a[..., :2], b[..., :2], equal_nan=True), key
                np.testing.assert_allclose(a[..., 2], b[..., 2], rtol=3e-16, atol=0)
                continue
            assert a.shape == b.shape and np.array_equal(a, b, equal_nan=True), (key, name)
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


@needs_numba
def test_a_track_an_ulp_away_unwraps_a_sample_to_the_same_angles():
    """
    A sample after a track update, its attitude turned by up to ~1 rad: main's angles.

    Main's track update is ``euler_of`` with libm's atan2 (the samples' conversion), this
    code's ``set_track`` takes ``trig.atan2``: on 20,000 random attitudes (theta from 1e-3 to
    pi - 1e-3, references tens of turns away) the tracks differ in their last bit for a few
    per cent, the samples unwrapped towards them never.
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
        here, main = reference.copy(), reference.copy()
        st[3:7] = q[i]
        tracking.set_track(st, 0, here)
        main[:] = tracking.unwrapped_euler(st, 0, reference)
        differ += here[0] != main[0] or here[1] != main[1]
        st[3:7] = sample[i]
        got = tracking.unwrapped_euler(st, 0, here)
        want = tracking.unwrapped_euler(st, 0, main)
        assert got == want, (q[i], sample[i], reference)
    assert differ > 0.01 * n

"""
The kernels' sin and cos (core/trig.py): within 1 ulp of libm's, the same bits vectorised.

libm (glibc) is the independent reference: its sin and cos are accurate to within an ulp.
Every kernel that turns a body or finds the Sun calls ``trig.sin_cos``; the vectorised passes
(the lockstep loop's ``splitting.block_sincos``, the ``dop853`` lanes' Sun direction
``gravity_gradient.sun_in_orbit_plane_rows``) must give exactly its bits, or an ensemble body
would drift from its own run (test_core_lockstep.py checks whole trajectories).
"""
import math

import numpy as np
import pytest

from tumble_ros.core import kernels, trig
from tumble_ros.core.compiling.jit import called, python_source
from tumble_ros.core.kernels.layout import BT

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')

#: The scalar function compiled on its own, and its Python source (the reference path).
SIN_COS = {'compiled': called(trig.sin_cos), 'python': python_source(trig.sin_cos)}


def arguments(seed=1, n=4000):
    """Arguments from 1e-12 rad to the reduced range's limit, both signs, k pi/2 +- 1 ulp."""
    rng = np.random.default_rng(seed)
    scales = 10.0 ** rng.uniform(-12, math.log10(trig.REDUCED_LIMIT), n)
    x = scales * rng.choice([-1.0, 1.0], n)
    k = np.arange(-2000, 2001) * (math.pi / 2)
    edge = np.linspace(-1.0, 1.0, 2001) * trig.SMALL * 1.02   # both sides of the short path
    return np.concatenate([x, k, np.nextafter(k, np.inf), np.nextafter(k, -np.inf), edge,
                           [0.0, -0.0, math.pi / 4, -math.pi / 4, 5e-324, 1e-300,
                            trig.SMALL, np.nextafter(trig.SMALL, 0.0)]])


def ulps(got, want):
    """|got - want| in units of the last place of want (of 5e-324 at 0)."""
    return np.abs(got - want) / np.spacing(np.maximum(np.abs(want), 5e-324))


@pytest.mark.parametrize('path', sorted(SIN_COS))
def test_sin_and_cos_are_within_one_ulp_of_libm(path):
    if path == 'compiled' and not kernels.COMPILED:
        pytest.skip('numba not available')
    x = arguments()
    pairs = np.array([SIN_COS[path](float(v)) for v in x])
    assert ulps(pairs[:, 0], np.sin(x)).max() <= 1.0
    assert ulps(pairs[:, 1], np.cos(x)).max() <= 1.0
    # (and most are libm's own bits: the polynomials are fdlibm's)
    assert np.mean(pairs[:, 0] == np.sin(x)) > 0.9


def test_signs_of_zero_and_exact_values():
    f = SIN_COS['python']
    assert f(0.0) == (0.0, 1.0) and math.copysign(1.0, f(0.0)[0]) == 1.0
    assert math.copysign(1.0, f(-0.0)[0]) == -1.0  # sin(-0) = -0, as libm
    assert f(1e-20) == (1e-20, 1.0)


@pytest.mark.parametrize('path', sorted(SIN_COS))
def test_huge_and_non_finite_arguments_are_libms(path):
    if path == 'compiled' and not kernels.COMPILED:
        pytest.skip('numba not available')
    for v in (trig.REDUCED_LIMIT, -trig.REDUCED_LIMIT * 3, 1e10, 1e300):
        assert SIN_COS[path](v) == (math.sin(v), math.cos(v))
    for v in (math.inf, -math.inf, math.nan):
        assert all(math.isnan(r) for r in SIN_COS['compiled'](v))


def block_arguments(rows):
    """Return the block pass's angles: all kinds, all below trig.SMALL, or one above them."""
    x = arguments(seed=2, n=1000)
    small = x[np.abs(x) < trig.SMALL]
    return {'all kinds': np.concatenate([x, [1e7, -1e12, math.inf, math.nan]]),
            'all small': small,    # (the pass without reduction)
            'one large': np.concatenate([small[:500], [-1.0], small[500:]]),   # (> pi/4)
            'one nan': np.concatenate([small, [math.nan]])}[rows]


@needs_numba
@pytest.mark.parametrize('rows', ['all kinds', 'all small', 'one large', 'one nan'])
def test_the_vectorised_block_pass_gives_the_scalar_bits(rows):
    from tumble_ros.core.kernels.splitting import block_sincos
    x = block_arguments(rows)
    assert x.size > 2000 and np.any(x < 0) and np.any(x == 0)
    tmp = np.zeros((BT.SIZE, x.size))
    tmp[BT.ANGLE] = x
    block_sincos(tmp, x.size)
    scalar = np.array([SIN_COS['compiled'](float(v)) for v in x])
    np.testing.assert_array_equal(tmp[BT.SIN], scalar[:, 0])
    np.testing.assert_array_equal(tmp[BT.COS], scalar[:, 1])
    # signed zeros too
    assert np.array_equal(np.signbit(tmp[BT.SIN]), np.signbit(scalar[:, 0]))


@needs_numba
def test_the_suns_direction_of_many_times_at_once_gives_the_scalar_bits():
    """The dop853 lanes' pass: every lane's Sun direction is the single body's, bit for bit."""
    from tumble_ros.core.compiling.jit import jit
    from tumble_ros.core.torques.gravity_gradient import (sun_in_orbit_plane,
                                                          sun_in_orbit_plane_rows)

    @jit
    def rows(rate, t, sx, sy, m):
        sun_in_orbit_plane_rows(rate, t, sx, sy, m)

    scalar_call = called(sun_in_orbit_plane)
    # times over 2000 yr and beyond the reduced range's limit (libm), non-finite ones too
    t = np.concatenate([np.abs(arguments(seed=4, n=1000)) / (2 * math.pi),
                        [0.0, -0.0, 2e5, 1e9, -3e12, math.inf, math.nan]])
    for rate in (2 * math.pi, 0.0172, 2.7e3):
        sx, sy = np.full(t.size + 1, 7.0), np.full(t.size + 1, 7.0)
        rows(rate, t, sx, sy, t.size)
        scalar = np.array([scalar_call(rate, float(v)) for v in t])
        np.testing.assert_array_equal(sx[:-1], scalar[:, 0])
        np.testing.assert_array_equal(sy[:-1], scalar[:, 1])
        assert np.array_equal(np.signbit(sx[:-1]), np.signbit(scalar[:, 0]))
        assert sx[-1] == sy[-1] == 7.0        # only the first m written
        # and the scalar is trig's sin/cos of rate * t, within an ulp of libm's
        ok = np.abs(rate * t) < trig.REDUCED_LIMIT
        for got, libm in ((scalar[ok, 0], np.sin(rate * t[ok])),
                          (scalar[ok, 1], np.cos(rate * t[ok]))):
            assert np.all(np.abs(got - libm) <= np.spacing(np.abs(libm)))


#: The track's atan2 compiled on its own, and its Python source.
ATAN2 = {'compiled': called(trig.atan2), 'python': python_source(trig.atan2)}


def atan2_arguments(seed=3, n=20000):
    """(y, x): every quadrant, ratios 1e-40 to 1e40, near +-pi, near the reduction's edges."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(-math.pi, math.pi, n)
    scale = 10.0 ** rng.uniform(-300, 300, n)
    ratio = 10.0 ** rng.uniform(-40, 40, n) * rng.choice([-1.0, 1.0], n)
    x = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-150, 150, n)
    # |y/x| on both sides of 7/16, 11/16, 19/16, 39/16 and 2^60 (fdlibm's thresholds)
    edges = np.array([0.4375, 0.6875, 1.1875, 2.4375, 2.0 ** 60])
    edge = np.concatenate([edges, np.nextafter(edges, 0.0), np.nextafter(edges, np.inf)])
    near_pi = 10.0 ** rng.uniform(-30, 0, n // 4)          # y -> +-0 with x < 0
    ys = [scale * np.sin(angle), ratio * x, edge, -edge, near_pi, -near_pi]
    xs = [scale * np.cos(angle), x, np.ones_like(edge), -np.ones_like(edge),
          -np.ones_like(near_pi), -np.ones_like(near_pi)]
    return np.concatenate(ys), np.concatenate(xs)


#: Arguments libm's atan2 answers exactly by C99's special cases: zeros, infinities, NaN.
SPECIAL = [0.0, -0.0, math.inf, -math.inf, math.nan, 1.0, -1.0, 5e-324, -1e308, 2.0 ** -60]


@pytest.mark.parametrize('path', sorted(ATAN2))
def test_atan2_is_within_one_ulp_of_libm(path):
    if path == 'compiled' and not kernels.COMPILED:
        pytest.skip('numba not available')
    y, x = atan2_arguments()
    got = np.array([ATAN2[path](float(a), float(b)) for a, b in zip(y, x)])
    want = np.array([math.atan2(a, b) for a, b in zip(y, x)])
    assert ulps(got, want).max() <= 1.0
    assert np.array_equal(np.signbit(got), np.signbit(want))
    # most are libm's own bits (fdlibm's polynomial; glibc's atan2 is correctly rounded)
    assert np.mean(got == want) > 0.8
    # every quadrant, |y/x| from tiny to huge, and both sides of +-pi were reached
    assert np.all(np.histogram(want, bins=8, range=(-math.pi, math.pi))[0] > 1000)
    assert np.abs(want).max() == math.pi and np.abs(got).max() == math.pi


@pytest.mark.parametrize('path', sorted(ATAN2))
def test_atan2_of_zeros_infinities_and_nan_is_libms(path):
    if path == 'compiled' and not kernels.COMPILED:
        pytest.skip('numba not available')
    for y in SPECIAL:
        for x in SPECIAL:
            got, want = ATAN2[path](y, x), math.atan2(y, x)
            if math.isnan(want):
                assert math.isnan(got), (y, x)
            elif 0.0 in (y, x) or math.isinf(y) or math.isinf(x):
                # C99's cases: exactly libm's, signed zeros, +-pi/4, +-3pi/4, +-pi/2, +-pi
                assert (got, math.copysign(1.0, got)) == (want, math.copysign(1.0, want)), (y, x)
            else:
                assert ulps(np.array([got]), np.array([want]))[0] <= 1.0, (y, x)


@needs_numba
def test_the_vectorised_atan2_gives_the_scalar_bits():
    """A loop over arrays (vectorised by LLVM: packed divisions) gives every scalar call's bits."""
    import numba

    @numba.njit(error_model='numpy')
    def many(y, x, out):
        for i in range(y.shape[0]):
            out[i] = trig.atan2(y[i], x[i])

    y, x = atan2_arguments(seed=4, n=2000)
    s, c = np.meshgrid(SPECIAL, SPECIAL)
    y, x = np.concatenate([y, s.ravel()]), np.concatenate([x, c.ravel()])
    out = np.empty_like(y)
    many(y, x, out)
    scalar = np.array([ATAN2['compiled'](float(a), float(b)) for a, b in zip(y, x)])
    assert out.tobytes() == scalar.tobytes()
    assert 'vdivpd' in next(iter(many.inspect_asm().values()))

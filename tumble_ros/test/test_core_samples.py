"""The compiled post-processing of an ensemble's samples (``kernels.samples``): numpy's bits."""
import numpy as np
import pytest

from tumble_ros.core import jacobi_integral
from tumble_ros.core.kernels import samples
from tumble_ros.core.model.rotation import continuous_quaternions, quaternions_to_matrices

INERTIA = np.array([0.37, 1.13, 1.71])
RATE = 2 * np.pi * 1.37


def same_bits(a, b):
    """Return True if a and b hold the same float64 bits (NaN included)."""
    return np.array_equal(np.asarray(a).view(np.int64), np.asarray(b).view(np.int64))


def random_samples(n, m, seed):
    """Return y_out (n, m, 7), e_out (n, m, 3), k_out (n,), times (m,): spins, turns, scales."""
    rng = np.random.default_rng(seed)
    y = rng.normal(size=(n, m, 7)) * rng.uniform(0.1, 40.0, size=(n, 1, 1))
    y[:, :, 3:] *= rng.uniform(0.5, 2.0, size=(n, m, 1))     # quaternions not of unit norm
    k_out = rng.integers(0, m + 1, size=n)
    k_out[: n // 3] = m
    return y, rng.normal(size=(n, m, 3)), k_out, np.sort(rng.uniform(0.0, 3.0, m))


def numpy_post(y, e, k_out, times):
    """Return the numpy post-processing, body by body (the code before ``ensemble_samples``)."""
    y, e, jac = y.copy(), e.copy(), np.full(y.shape[:2], np.nan)
    for b, kk in enumerate(k_out):
        y[b, kk:], e[b, kk:] = np.nan, np.nan
        if kk:
            q = y[b, :kk, 3:]
            jac[b, :kk] = jacobi_integral(times[:kk], y[b, :kk, :3], quaternions_to_matrices(q),
                                          INERTIA, RATE)
            y[b, :kk, 3:] = continuous_quaternions(q)
    return y, e, jac


def compiled_post(y, e, k_out, times, groups=1):
    """``ensemble_samples`` on copies of y, e, in ``groups`` calls."""
    y, e, jac = y.copy(), e.copy(), np.full(y.shape[:2], 7.0)
    n = y.shape[0]
    edges = np.linspace(0, n, groups + 1).astype(int)
    for b0, b1 in zip(edges[:-1], edges[1:]):
        samples.ensemble_samples(np.sin(RATE * times), np.cos(RATE * times), y, e, k_out, INERTIA,
                                 RATE, 1.5 * RATE**2, jac, b0, b1)
    return y, e, jac


@pytest.mark.parametrize('groups', [1, 7])
def test_ensemble_samples_give_numpys_bits(groups):
    y, e, k_out, times = random_samples(200, 30, seed=3)
    ref, got = numpy_post(y, e, k_out, times), compiled_post(y, e, k_out, times, groups)
    for name, a, b in zip(('y', 'euler', 'jacobi'), ref, got):
        assert same_bits(a, b), name
    # the case holds sign flips (q.q' < 0 between random samples), unreached samples, a body
    # that reached none, and quaternions away from unit norm: each path above is exercised
    continuous = ref[0][:, :, 3]
    flips = (np.isfinite(continuous) & (np.sign(continuous) != np.sign(y[:, :, 3]))).sum()
    assert flips > 100 and (k_out == 0).any() and np.isnan(ref[2]).sum() > 100


def test_unreached_samples_are_nan_whatever_the_memory_held():
    """The loops' outputs are allocated empty: every sample past a body's last is NaN."""
    y, e = np.full((3, 4, 7), 5.0), np.full((3, 4, 3), 5.0)
    k_out = np.array([4, 1, 0])
    jac = np.full((3, 4), 5.0)
    samples.ensemble_samples(np.zeros(4), np.ones(4), y, e, k_out, INERTIA, RATE,
                             1.5 * RATE**2, jac, 0, 3)
    for out in (y, e, jac):
        assert np.isfinite(out[0]).all() and np.isfinite(out[1, :1]).all()
        assert np.isnan(out[1, 1:]).all() and np.isnan(out[2]).all()
    assert (y[0, :, :3] == 5.0).all() and (y[0, :, 3:] == 0.5).all() and (e[0] == 5.0).all()


def test_without_euler_angles_nothing_else_changes():
    y, e, k_out, times = random_samples(50, 12, seed=4)
    with_e = compiled_post(y, e, k_out, times)
    without = compiled_post(y, np.empty((50, 0, 3)), k_out, times)
    assert same_bits(with_e[0], without[0]) and same_bits(with_e[2], without[2])


def test_continuity_and_jacobi_by_an_independent_computation():
    """Unit quaternions, q.q' >= 0 between samples, J from its definition (einsum, closed form)."""
    y, e, k_out, times = random_samples(40, 25, seed=5)
    k_out[:] = 25
    out, _, jac = compiled_post(y, e, k_out, times)
    q = out[:, :, 3:]
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, rtol=0, atol=1e-15)
    assert ((q[:, 1:] * q[:, :-1]).sum(axis=-1) >= 0).all()
    unit = y[:, :, 3:] / np.linalg.norm(y[:, :, 3:], axis=-1, keepdims=True)
    assert np.allclose(np.abs((q * unit).sum(axis=-1)), 1.0, rtol=0, atol=1e-14)   # same attitude
    # J = 1/2 w.I.w + 3/2 ws^2 u.I.u + ws (I w).z', u and z' the Sun and orbit normal in body axes
    c = np.array([[[1 - 2 * (b * b + d * d), 2 * (a * b - s * d), 2 * (a * d + s * b)],
                   [2 * (a * b + s * d), 1 - 2 * (a * a + d * d), 2 * (b * d - s * a)],
                   [2 * (a * d - s * b), 2 * (b * d + s * a), 1 - 2 * (a * a + b * b)]]
                  for s, a, b, d in unit.reshape(-1, 4)]).reshape(40, 25, 3, 3)
    sun = np.stack([np.sin(RATE * times), np.cos(RATE * times), np.zeros(25)], axis=-1)
    u = np.einsum('bkji,kj->bki', c, sun)
    w = y[:, :, :3]
    expected = (0.5 * np.einsum('bki,i,bki->bk', w, INERTIA, w)
                + 1.5 * RATE**2 * np.einsum('bki,i,bki->bk', u, INERTIA, u)
                + RATE * np.einsum('i,bki,bki->bk', INERTIA, w, c[:, :, 2, :]))
    np.testing.assert_allclose(jac, expected, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize('compiled', [False, True])
def test_the_matrix_is_rotations_bit_for_bit(compiled):
    """quaternion_matrix (one sample, compiled or its source) = quaternions_to_matrices, bits."""
    from tumble_ros.core.compiling.jit import python_source

    rng = np.random.default_rng(11)
    q = rng.normal(size=(500, 4)) * rng.uniform(0.5, 2.0, size=(500, 1))
    q[:5, 1:] = 0.0                                  # turns about nothing and one axis: zeros
    q[5:10, 2:] = -0.0
    expected = quaternions_to_matrices(q).reshape(-1, 9)
    one = samples.quaternion_matrix if compiled else python_source(samples.quaternion_matrix)
    got = np.array([one(*map(float, row)) for row in q])
    assert same_bits(got, expected)

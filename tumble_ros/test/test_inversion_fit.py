"""
The inversion's forward model and local fit (tumble_ros.inversion.model, .fit; issue 49).

A noiseless campaign made by the project's own forward model is fitted back to its truth from a
nearby start; the 1 sigma of the covariance is the scatter of fits over noise draws; the block
offsets come out linearly; the compiled brightness sums are the numpy laws' sums.
"""
import math

import numpy as np
import pytest

from tumble_ros.core.photometry import ellipsoid_mesh, law, LAWS
from tumble_ros.core.photometry.brightness import _numpy_brightness, brightness_in_body
from tumble_ros.core.photometry.kernel import COMPILED
from tumble_ros.inversion.campaign import Campaign
from tumble_ros.inversion.fit import fit_local
from tumble_ros.inversion.model import ForwardModel, ModelError, ModelOptions, \
    TumblerParameters

TRUTH = TumblerParameters.of('SAM', 27.38, 263.0, (0.61, 0.965),
                             (math.radians(250.0), math.radians(-55.0)), (0.5, 1.0),
                             axis_ratios=(0.8, 0.55))
START = TumblerParameters.of('SAM', 27.38 * 1.001, 263.0 * 1.01, (0.6, 0.95),
                             (math.radians(245.0), math.radians(-50.0)), (0.55, 1.05),
                             axis_ratios=(0.75, 0.6))


def geometry(nights: int = 10, per_night: int = 40, free: bool = True) -> Campaign:
    """Return a campaign's points (magnitudes 0): a night every 2 d, the geometry turning."""
    jd0 = 2460000.5
    t = np.concatenate([jd0 + 2.0 * k + np.linspace(0.0, 0.3, per_night) for k in range(nights)])
    angle = 0.01 * (t - jd0)
    sun = 1.1 * np.stack([np.cos(angle), np.sin(angle), np.full(t.size, 0.05)], 1)
    observer = 0.2 * np.stack([np.cos(angle + 0.4), np.sin(angle + 0.4),
                               np.full(t.size, 0.1)], 1)
    block = np.repeat(np.arange(nights), per_night)
    return Campaign(t, np.zeros(t.size), np.full(t.size, 0.01), sun, observer, block,
                    tuple(f'night {k}' for k in range(nights)), (free,) * nights)


def observed(points: Campaign, magnitude: np.ndarray) -> Campaign:
    """Return ``points`` with these magnitudes."""
    return Campaign(points.jd_tdb, magnitude, points.sigma, points.sun, points.observer,
                    points.block, points.block_names, points.free_offset)


def test_a_noiseless_campaign_is_fitted_back_to_its_truth():
    points = geometry()
    model = ForwardModel(points)
    magnitude = model.magnitudes(TRUTH) + 3.0 + 0.1 * points.block
    fit = fit_local(observed(points, magnitude), START)
    truth = dict(zip(['precession_period', 'rotation_period', 'i1_i3', 'i2_i3', 'pole_lambda',
                      'pole_beta', 'phi0', 'psi0', 'axis_b_a', 'axis_c_a'], TRUTH.vector()))
    assert fit.success and fit.chi2 < 1e-12
    for name, value in zip(fit.names, fit.values):
        assert value == pytest.approx(truth[name], rel=1e-6, abs=1e-6), name
    assert np.allclose(fit.block_offsets, 3.0 + 0.1 * np.arange(10), atol=1e-8)
    assert fit.dof == points.jd_tdb.size - 10 - 10
    assert any('far from 1' in w for w in fit.warnings)      # chi2/nu ~ 0: says so


def test_the_covariance_sigma_is_the_scatter_of_fits_over_noise_draws():
    points = geometry(nights=6, per_night=30)
    clean = ForwardModel(points).magnitudes(TRUTH)
    rng = np.random.default_rng(7)
    fits = [fit_local(observed(points, clean + rng.normal(0.0, 0.01, clean.size)), TRUTH,
                      max_nfev=20) for _ in range(16)]
    values = np.array([f.values for f in fits])
    sigma = np.median([f.sigma for f in fits], axis=0)
    scatter = values.std(axis=0, ddof=1)
    # 16 draws: the sample std is known to ~18 % (1 sigma); every parameter within 0.55..1.7
    ratio = scatter / sigma
    assert np.all((ratio > 0.55) & (ratio < 1.7)), dict(zip(fits[0].names, ratio))
    chi2 = np.array([f.chi2_reduced for f in fits])
    assert 0.8 < chi2.mean() < 1.2


def test_calibrated_blocks_share_one_offset():
    points = geometry(nights=3, per_night=20, free=False)
    model = ForwardModel(points)
    assert model.groups == 1
    magnitude = model.magnitudes(TRUTH) + 2.0
    offsets = ForwardModel(observed(points, magnitude)).block_offsets(TRUTH)
    assert np.allclose(offsets, 2.0, atol=1e-12)


def test_a_start_with_no_possible_state_is_refused_in_one_line():
    points = geometry(nights=2, per_night=10)
    with pytest.raises(ModelError, match='subdivisions'):
        ModelOptions(subdivisions=9)
    with pytest.raises(ModelError, match='fixed'):
        ModelOptions(fixed=('period',))
    with pytest.raises(ModelError, match='epoch_jd'):
        ForwardModel(points, epoch_jd=points.jd_tdb[0] + 1.0)


def test_fixed_parameters_stay_at_the_start():
    points = geometry(nights=4, per_night=20)
    magnitude = ForwardModel(points).magnitudes(TRUTH)
    options = ModelOptions(fixed=('i1_i3', 'i2_i3', 'axis_b_a', 'axis_c_a'))
    fit = fit_local(observed(points, magnitude), TRUTH, options, max_nfev=5)
    value, sigma = fit.value('i1_i3')
    assert 'i1_i3' not in fit.names and value == 0.61 and math.isnan(sigma)
    assert len(fit.names) == 6


@pytest.mark.skipif(not COMPILED, reason='the compiled sums need numba')
@pytest.mark.parametrize('name', sorted(LAWS))
def test_the_compiled_brightness_is_the_numpy_sum_of_every_law(name):
    rng = np.random.default_rng(3)
    sun = rng.normal(size=(500, 3))
    observer = rng.normal(size=(500, 3))
    sun /= np.linalg.norm(sun, axis=1)[:, None]
    observer /= np.linalg.norm(observer, axis=1)[:, None]
    mesh = ellipsoid_mesh((1.0, 0.7, 0.4), 2)
    compiled = brightness_in_body(sun, observer, mesh, name)
    reference = _numpy_brightness(sun, observer, mesh, law(name))
    assert np.allclose(compiled, reference, rtol=1e-13, atol=1e-15)
    assert np.any(reference == 0.0) or np.all(compiled > 0.0)


def test_the_posterior_sample_spreads_as_the_covariance():
    from tumble_ros.inversion.posterior import sample_posterior
    points = geometry(nights=3, per_night=20)
    options = ModelOptions(fixed=('i1_i3', 'i2_i3', 'axis_b_a', 'axis_c_a', 'phi0', 'psi0'))
    clean = ForwardModel(points, options).magnitudes(TRUTH)
    noisy = observed(points, clean + np.random.default_rng(2).normal(0.0, 0.01, clean.size))
    fit = fit_local(noisy, TRUTH, options)
    posterior = sample_posterior(noisy, fit, walkers=8, steps=260, burn=80, options=options)
    assert posterior.samples.shape == (8 * 180, 4) and 0.1 < posterior.acceptance < 0.9
    spread = posterior.samples.std(axis=0)
    # linear model near the minimum: the posterior's spread is the covariance's 1 sigma
    assert np.all((spread / fit.sigma > 0.5) & (spread / fit.sigma < 2.0)), spread / fit.sigma
    assert np.all(np.abs(posterior.samples.mean(axis=0) - fit.values) < fit.sigma)
    assert posterior.parameters(fit, 0).spin.mode == 'SAM'

"""
Injection and recovery (issue 49): the inversion on campaigns its own code did not make.

The campaigns come from synthetic_campaigns.py (scipy's DOP853 on Euler's equations, a surface
quadrature of the ellipsoid's brightness, Kepler geometry, nights with lunar and weather gaps,
0.01-0.03 mag noise, a free offset per night); inversion_recovery.py runs the fit.

* **Coverage** (the reported 1 sigma is the truth's scatter): a LAM tumbler (P_phi 9 h,
  P_psi 20 h) on 25 nights, fitted from the truth on COVERAGE_DRAWS noise draws (16; 64 with
  TUMBLE_ROS_LONG_INVERSION=1). Pooled over P_phi, P_psi, lambda, beta, I1/I3, I2/I3: the mean
  z^2 must lie in [0.45, 2.0] (1 if right; 4 if the 1 sigma were half the scatter, 0.25 if
  twice: both fail) and the fraction within 1 sigma in [0.5, 0.86] (0.68 if right; 0.38 and
  0.95 for 1 sigma wrong by 2x), within 3 sigma >= 0.95; the same z-scores scaled by 2 and by
  1/2 must fail the criteria (the draws are enough to see it).
* **A SAM** (P_phi 6.2 h, P_psi 28 h) on 30 nights of one apparition: the truth within 3 sigma.
* **A principal-axis rotator** (5.3 h) on 12 nights: the period search should say one period,
  no pair to fit. It does not (xfail, strict: the test's docstring says why).
* **Long** (TUMBLE_ROS_LONG_INVERSION=1, minutes each): the SAM's coverage; the SAM over two
  apparitions; Apophis (Pravec et al. 2014's state) sampled like 2020-21 (1,280 points on 67
  nights), its periods to the published precision at 1 sigma (P_phi 0.07 h / 3, P_psi 6 h / 3:
  Pravec et al.'s 3-sigma); over 2012-13 and 2020-21, to ~0.001 h and ~0.1 h (Durech et al. 2026,
  arXiv:2604.24566: 27.374 +- 0.001 h, 262.2 +- 0.1 h) with the cycle-count aliases across the
  8-year gap fitted and listed.
"""
from dataclasses import replace
import math
import os

import inversion_recovery as ir
import numpy as np
import pytest
import synthetic_campaigns as sc
from tumble_ros.inversion.fit import fit_local
from tumble_ros.inversion.search import period_candidates, SearchSettings

LONG = os.environ.get('TUMBLE_ROS_LONG_INVERSION', '') == '1'
COVERAGE_DRAWS = 64 if LONG else 16
long_only = pytest.mark.skipif(not LONG, reason='minutes: set TUMBLE_ROS_LONG_INVERSION=1')

LAM = sc.TrueSpin('LAM', 9.0, 20.0, (0.5, 0.8), (30.0, 40.0), (0.4, 2.0), True, 2459169.5)
LAM_SEASON = sc.Apparition(2459170.5, 2459230.5, 25, 400)
SAM = sc.TrueSpin('SAM', 6.2, 28.0, (0.55, 0.83), (123.0, -35.0), (0.7, 2.2), False, 2459169.5)
SAM_SEASONS = (sc.Apparition(2459170.5, 2459240.5, 30, 600),
               sc.Apparition(2459530.5, 2459600.5, 30, 600))
PA = sc.TrueSpin('PA', 5.3, 5.3, (0.5, 0.8), (60.0, 20.0), (1.0, 0.0), epoch_jd=2459169.5)
PA_SEASON = sc.Apparition(2459170.5, 2459190.5, 12, 200)


@pytest.fixture(scope='module')
def lam_fits():
    synthetic = sc.make_campaign(LAM, [LAM_SEASON], seed=11)
    return synthetic, ir.recover(synthetic, COVERAGE_DRAWS, seed=1000)


def covered(z: np.ndarray) -> bool:
    """Whether z-scores (draws, quantities) pass the coverage criteria (module docstring)."""
    within_1, within_3 = np.mean(np.abs(z) < 1.0), np.mean(np.abs(z) < 3.0)
    return bool(0.45 <= np.mean(z ** 2) <= 2.0 and 0.5 <= within_1 <= 0.86
                and within_3 >= 0.95)


def test_the_reported_sigma_covers_the_truth(lam_fits):
    synthetic, fits = lam_fits
    truth = ir.truth_parameters(synthetic)
    print(ir.table('LAM 9 h / 20 h, 25 nights', fits, truth))
    assert all(f.success for f in fits)
    z = ir.coverage(fits, truth).z
    assert covered(z), ir.table('coverage', fits, truth)
    # the draws are enough to see a 1 sigma wrong by 2x, either way
    assert not covered(2.0 * z) and not covered(0.5 * z)


def test_a_sam_is_recovered():
    synthetic = sc.make_campaign(SAM, SAM_SEASONS[:1], seed=12)
    fit = ir.recover(synthetic, 1, seed=2000)[0]
    z = ir.z_scores(fit, ir.truth_parameters(synthetic))
    print(ir.table('SAM 6.2 h / 28 h, one apparition', [fit], ir.truth_parameters(synthetic)))
    assert fit.success and np.all(np.abs(z) < 3.0)


@pytest.mark.xfail(strict=True, reason='issue 49: the period search reports two close periods '
                   'for a principal-axis rotator whose viewing geometry changes (2.631 and '
                   '2.650 h over 20 d), and the inversion has no principal-axis model to say '
                   'one period')
def test_a_principal_axis_rotator_has_one_period():
    """
    One period (half the 5.3-h turn: the ellipsoid's lightcurve repeats every half turn).

    The search is given its range (its default here starts at 7.5 h, its grid's size, above the
    lightcurve's 2.65 h). It fails today: the Fourier series of one fixed period cannot follow
    the changing geometry (the synodic drift of the phase, the amplitude with the aspect), the
    BIC takes a second period 1/span away for it (bic 2 periods -1443.6 < 1 period -1416.3),
    and every candidate is then a tumbler (LAM 1.32 / 2.65 h...).
    """
    synthetic = sc.make_campaign(PA, [PA_SEASON], seed=13, nu=128, nv=64)
    campaign = sc.draw(synthetic, np.random.default_rng(3000))
    candidates, solution = period_candidates(campaign, SearchSettings(period_range=(2.0, 12.0)))
    assert solution is not None and not solution.two_periods, (solution.p1, solution.p2)
    assert candidates == []
    found = min((abs(solution.p1 - p) / solution.p1_sigma, p) for p in (5.3 / 2, 5.3))
    assert found[0] < 3.0, (solution.p1, solution.p1_sigma)


@long_only
def test_the_reported_sigma_covers_the_truth_of_a_sam():
    synthetic = sc.make_campaign(SAM, SAM_SEASONS[:1], seed=12)
    truth = ir.truth_parameters(synthetic)
    fits = ir.recover(synthetic, COVERAGE_DRAWS, seed=6000)
    print(ir.table('SAM 6.2 h / 28 h, 30 nights', fits, truth))
    assert covered(ir.coverage(fits, truth).z), ir.table('coverage', fits, truth)


@long_only
def test_a_sam_over_two_apparitions():
    one = sc.make_campaign(SAM, SAM_SEASONS[:1], seed=12)
    two = sc.make_campaign(SAM, SAM_SEASONS, seed=12)
    fit_one = ir.recover(one, 1, seed=2000)[0]
    fit_two = ir.recover(two, 1, seed=2000)[0]
    truth = ir.truth_parameters(two)
    print(ir.table('SAM, two apparitions', [fit_two], truth))
    assert np.all(np.abs(ir.z_scores(fit_two, truth)) < 3.0)
    # a year more: the periods far better known
    assert fit_two.value('precession_period')[1] < 0.2 * fit_one.value('precession_period')[1]


def apophis(two_apparitions: bool) -> sc.SyntheticCampaign:
    """Pravec et al. 2014's state sampled like 2020-21 (and 2012-13)."""
    if two_apparitions:
        return sc.make_campaign(sc.APOPHIS_PRAVEC_2014,
                                [sc.APOPHIS_2012_13, sc.APOPHIS_2020_21], seed=2029)
    spin = replace(sc.APOPHIS_PRAVEC_2014, epoch_jd=sc.APOPHIS_2020_21.start_jd)
    return sc.make_campaign(spin, [sc.APOPHIS_2020_21], seed=2029)


@long_only
def test_apophis_one_apparition_to_the_published_precision():
    synthetic = apophis(False)
    fit = ir.recover(synthetic, 1, seed=4000)[0]
    truth = ir.truth_parameters(synthetic)
    print(ir.table('Apophis, 2020-21 sampling', [fit], truth))
    assert np.all(np.abs(ir.z_scores(fit, truth)) < 3.0)
    assert fit.value('precession_period')[1] <= 0.07 / 3 * 1.5
    assert fit.value('rotation_period')[1] <= 6.0 / 3 * 1.5


def cycle_aliases(fit, gap_h: float) -> list[tuple[float, float]]:
    """(P_phi, P_psi) one cycle more or less of either period across the gap [h]."""
    p_phi, p_psi = fit.value('precession_period')[0], fit.value('rotation_period')[0]
    out = []
    for n in (-1, 1):
        out.append((1.0 / (1.0 / p_phi + n / gap_h), p_psi))
        out.append((p_phi, 1.0 / (1.0 / p_psi + n / gap_h)))
    return out


@long_only
def test_apophis_two_apparitions_precision_and_aliases():
    synthetic = apophis(True)
    truth = ir.truth_parameters(synthetic)
    campaign = sc.draw(synthetic, np.random.default_rng(4001))
    best = fit_local(campaign, truth, epoch_jd=synthetic.truth.epoch_jd)
    print(ir.table('Apophis, 2012-13 + 2020-21 sampling', [best], truth))
    assert np.all(np.abs(ir.z_scores(best, truth)) < 3.0)
    assert best.value('precession_period')[1] <= 0.002
    assert best.value('rotation_period')[1] <= 0.2
    gap = (sc.APOPHIS_2020_21.start_jd - sc.APOPHIS_2012_13.end_jd) * 24.0
    threshold = best.chi2 + math.sqrt(2.0 * best.dof) * best.chi2_reduced
    for pair in cycle_aliases(best, gap):
        start = truth.with_values(('precession_period', 'rotation_period'), pair)
        alias = fit_local(campaign, start, epoch_jd=synthetic.truth.epoch_jd)
        print(f'alias start {pair[0]:.5f} h, {pair[1]:.3f} h -> '
              f"{alias.value('precession_period')[0]:.5f} h, "
              f"{alias.value('rotation_period')[0]:.3f} h, chi2 - best "
              f'{alias.chi2 - best.chi2:.1f} (accepted below {threshold - best.chi2:.1f})')
        assert alias.chi2 >= best.chi2 - 1e-6 * best.chi2

"""
Injection and recovery: the inversion's fit on the independent generator's campaigns.

The truth goes in through ``synthetic_campaigns`` (its own integration and brightness); the fit
(``tumble_ros.inversion``) comes back with values and 1 sigma. :func:`recover` runs the local
fit from the truth on many noise draws of one campaign (the coverage of the reported 1 sigma is
a property of the fit at its minimum: the global search is proven apart); :func:`coverage`
counts, per quantity, how often the truth lies within 1, 2, 3 sigma and the mean z^2 (1 when
the 1 sigma is right, 4 when it is half the truth's scatter, 0.25 when it is twice).

Quantities: P_phi, P_psi [h], L's ecliptic (lambda, beta) [rad], I1/I3, I2/I3. The shape (the
ellipsoid's b/a, c/a) and the phases are fitted too; the Lambert weight (0.1) and the linear
phase slope are held at the truth's (the fit's defaults hold them; with a free offset per night
the slope is not measured). Used by test_inversion_recovery.py and
benchmarks/inversion_recovery.py.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

import numpy as np

import synthetic_campaigns as sc
from tumble_ros.inversion.fit import fit_local, InversionFit
from tumble_ros.inversion.model import ModelOptions, PARAMETER_UNITS, TumblerParameters

__all__ = ['QUANTITIES', 'truth_parameters', 'z_scores', 'recover', 'Coverage', 'coverage',
           'table']

#: The recovered quantities the proof counts (names of ``model.PARAMETER_UNITS``).
QUANTITIES = ('precession_period', 'rotation_period', 'pole_lambda', 'pole_beta', 'i1_i3',
              'i2_i3')
_WRAPPED = ('pole_lambda', 'phi0', 'psi0')


def truth_parameters(synthetic: sc.SyntheticCampaign) -> TumblerParameters:
    """Return the injected state as the fit's parameters (angles [rad], phase slope [mag/rad])."""
    truth = synthetic.truth
    a, b, c = synthetic.semi_axes
    return TumblerParameters.of(truth.mode, truth.precession_period_h, truth.rotation_period_h,
                                truth.inertia_ratios,
                                (math.radians(truth.pole_deg[0]),
                                 math.radians(truth.pole_deg[1])),
                                truth.phases, truth.anti_aligned, (b / a, c / a),
                                sc.LAMBERT_WEIGHT, math.degrees(synthetic.phase_slope))


def z_scores(fit: InversionFit, truth: TumblerParameters,
             names: Sequence[str] = QUANTITIES) -> np.ndarray:
    """(fit - truth) / sigma of each name (angles wrapped to (-pi, pi])."""
    full = truth.vector()
    out = []
    for name in names:
        value, sigma = fit.value(name)
        diff = value - full[list(PARAMETER_UNITS).index(name)]
        if name in _WRAPPED:
            diff = (diff + math.pi) % (2 * math.pi) - math.pi
        out.append(diff / sigma)
    return np.array(out)


def recover(synthetic: sc.SyntheticCampaign, draws: int, seed: int,
            options: ModelOptions | None = None, max_nfev: int = 60
            ) -> list[InversionFit]:
    """Run the local fit from the truth on ``draws`` noise draws (seeds seed, seed + 1, ...)."""
    start = truth_parameters(synthetic)
    fits = []
    for k in range(draws):
        campaign = sc.draw(synthetic, np.random.default_rng(seed + k))
        fits.append(fit_local(campaign, start, options, epoch_jd=synthetic.truth.epoch_jd,
                              max_nfev=max_nfev))
    return fits


@dataclass(frozen=True)
class Coverage:
    """Per quantity: the fractions of draws with |z| < 1, 2, 3 and the mean z^2."""

    names: tuple[str, ...]
    z: np.ndarray                 # (draws, quantities)
    within: np.ndarray            # (3, quantities): |z| < 1, 2, 3
    mean_z2: np.ndarray           # (quantities,)

    @property
    def pooled_within(self) -> np.ndarray:
        """Fractions of all (draw, quantity) pairs within 1, 2, 3 sigma (1-sigma: 0.683)."""
        return np.array([np.mean(np.abs(self.z) < k) for k in (1, 2, 3)])

    @property
    def pooled_mean_z2(self) -> float:
        """Mean z^2 over every draw and quantity."""
        return float(np.mean(self.z ** 2))


def coverage(fits: Sequence[InversionFit], truth: TumblerParameters,
             names: Sequence[str] = QUANTITIES) -> Coverage:
    """Count the coverage of the fits' 1 sigma over the draws."""
    z = np.array([z_scores(fit, truth, names) for fit in fits])
    within = np.array([np.mean(np.abs(z) < k, axis=0) for k in (1, 2, 3)])
    return Coverage(tuple(names), z, within, np.mean(z ** 2, axis=0))


_DISPLAY = {'precession_period': ('P_phi [h]', 1.0), 'rotation_period': ('P_psi [h]', 1.0),
            'pole_lambda': ('lambda [deg]', 180 / math.pi),
            'pole_beta': ('beta [deg]', 180 / math.pi), 'i1_i3': ('I1/I3', 1.0),
            'i2_i3': ('I2/I3', 1.0)}


def table(title: str, fits: Sequence[InversionFit], truth: TumblerParameters,
          names: Sequence[str] = QUANTITIES) -> str:
    """Return the recovery table: truth, mean fit, median 1 sigma, coverage, mean z^2."""
    cov = coverage(fits, truth, names)
    full = truth.vector()
    lines = [f'{title}: {len(fits)} noise draws, chi2/nu median '
             f'{np.median([f.chi2_reduced for f in fits]):.3f}',
             f"  {'quantity':14s} {'truth':>12s} {'fit (mean)':>12s} {'1 sigma':>10s} "
             f"{'<1s':>5s} {'<2s':>5s} {'<3s':>5s} {'<z^2>':>6s}"]
    for k, name in enumerate(names):
        label, scale = _DISPLAY.get(name, (name, 1.0))
        values = np.array([f.value(name)[0] for f in fits])
        sigmas = np.array([f.value(name)[1] for f in fits])
        lines.append(f'  {label:14s} {full[list(PARAMETER_UNITS).index(name)] * scale:12.6g} '
                     f'{np.mean(values) * scale:12.6g} {np.median(sigmas) * scale:10.3g} '
                     f'{cov.within[0, k]:5.2f} {cov.within[1, k]:5.2f} {cov.within[2, k]:5.2f} '
                     f'{cov.mean_z2[k]:6.2f}')
    pooled = cov.pooled_within
    lines.append(f'  pooled: {pooled[0]:.2f} / {pooled[1]:.2f} / {pooled[2]:.2f} within 1/2/3 '
                 f'sigma (Gaussian: 0.68 / 0.95 / 1.00), mean z^2 {cov.pooled_mean_z2:.2f}')
    return '\n'.join(lines)

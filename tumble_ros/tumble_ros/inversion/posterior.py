"""
The posterior of a fit by MCMC (emcee's affine-invariant ensemble sampler), an option.

log p(x) = -chi^2(x) / 2 with flat priors inside the parameters' bounds (``model``'s), the
offsets solved at every sample as in the fit (the profiled likelihood); a parameter set with no
possible spin state (a P_psi no body of the ratios has, moments that break the triangle
inequality) has p = 0. The walkers start in a Gaussian ball of the fit's covariance (a tenth of
its 1 sigma), each where the model can be evaluated; the first ``burn`` steps are dropped.
What comes out is a sample of the free parameters (units of :data:`~.model.PARAMETER_UNITS`),
the states the photometry allows (an ensemble through a flyby, the spread of a prediction), the
samples with p = 0 left out. Cost: walkers x steps model evaluations (~0.1 s each at 2,000
points).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tumble_ros.inversion.campaign import Campaign
from tumble_ros.inversion.fit import InversionFit
from tumble_ros.inversion.model import bounds, ForwardModel, ModelError, ModelOptions, \
    parameters_or_none, TumblerParameters

__all__ = ['Posterior', 'sample_posterior']


@dataclass(frozen=True, eq=False)
class Posterior:
    """
    A posterior sample: ``samples`` (k, p) of the free parameters ``names``, burn-in dropped.

    ``acceptance`` the walkers' mean acceptance fraction; ``log_probability`` (k,) of each.
    """

    names: tuple[str, ...]
    samples: np.ndarray
    log_probability: np.ndarray
    acceptance: float

    def parameters(self, fit: InversionFit, k: int) -> TumblerParameters:
        """Return sample k as a model: the fit's mode and side of theta0, these values."""
        return fit.parameters.with_values(self.names, self.samples[k])


def sample_posterior(campaign: Campaign, fit: InversionFit, *, walkers: int | None = None,
                     steps: int = 200, burn: int = 50, seed: int = 1,
                     options: ModelOptions | None = None) -> Posterior:
    """
    Return emcee's sample of the posterior about ``fit`` (module docstring).

    ``walkers`` default 2 x parameters + 2; ``steps`` per walker, the first ``burn`` dropped;
    ``options`` the fit's model options (the same free parameters). ModelError for bad sizes.
    """
    import emcee

    names = fit.names
    if walkers is None:
        walkers = 2 * len(names) + 2
    if walkers < 2 * len(names) or steps <= burn or burn < 0:
        raise ModelError(f'posterior: needs walkers >= {2 * len(names)} and steps > burn >= 0, '
                         f'got {walkers}, {steps}, {burn}')
    model = ForwardModel(campaign, options or ModelOptions(), fit.epoch_jd)
    if model.options.free() != names:
        raise ModelError('posterior: the options free other parameters than the fit did')
    lower, upper = bounds(names)

    def log_probability(x: np.ndarray) -> float:
        if np.any(x < lower) or np.any(x > upper):
            return -np.inf
        f = model.try_residuals(parameters_or_none(fit.parameters, names, x))
        return -np.inf if f is None else -0.5 * float(f @ f)

    rng = np.random.default_rng(seed)
    spread = np.where(np.isfinite(fit.sigma) & (fit.sigma > 0), fit.sigma, 1e-6) * 0.1
    start = np.empty((walkers, len(names)))
    for w in range(walkers):            # each walker where the model can be evaluated
        for _ in range(100):
            start[w] = np.clip(fit.values + spread * rng.standard_normal(len(names)),
                               lower + 1e-12, upper - 1e-12)
            if np.isfinite(log_probability(start[w])):
                break
        else:
            start[w] = fit.values
    sampler = emcee.EnsembleSampler(walkers, len(names), log_probability)
    # (emcee draws from a numpy RandomState: seeded from ours, the chain is reproducible)
    state = emcee.State(start, random_state=np.random.RandomState(
        int(rng.integers(2**31))).get_state())
    sampler.run_mcmc(state, steps)
    chain = sampler.get_chain(discard=burn, flat=True)
    logp = sampler.get_log_prob(discard=burn, flat=True)
    possible = np.isfinite(logp)        # (a walker never leaves a possible state once in one)
    return Posterior(names, chain[possible], logp[possible],
                     float(np.mean(sampler.acceptance_fraction)))

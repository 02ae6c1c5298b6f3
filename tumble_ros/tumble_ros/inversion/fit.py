"""
The local fit: every free parameter by scipy's ``least_squares`` from a start, with 1 sigma.

The objective is chi^2 = sum ((data - model - offset) / sigma)^2 over the campaign's points,
the block offsets solved linearly inside the model (``model``): a variable-projection fit, so
the covariance of the nonlinear parameters from the profiled residuals' Jacobian J,
C = (J^T J)^-1, already accounts for the offsets. The Jacobian is by forward differences of
:data:`STEPS` (a step that leaves the possible states, e.g. a P_psi no body of the ratios has,
is taken backwards). 1 sigma = sqrt(diag C), scaled by sqrt(chi^2/nu) when chi^2/nu > 1 (errors
that understate the scatter); ``warnings`` say when chi^2/nu is far from 1, when the fit did
not converge, when a parameter sits on a bound or is not constrained.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import time
from typing import Callable

import numpy as np
from scipy.optimize import least_squares

from tumble_ros.inversion.campaign import Campaign
from tumble_ros.inversion.model import (bounds, ForwardModel, ModelError, ModelOptions,
                                        PARAMETER_UNITS, parameters_or_none, TumblerParameters)

__all__ = ['InversionFit', 'fit_local', 'STEPS', 'CHI2_FAR']

#: Forward-difference steps of the Jacobian per parameter (periods relative, others absolute).
STEPS: dict[str, float] = {
    'precession_period': 1e-7, 'rotation_period': 1e-7, 'i1_i3': 1e-5, 'i2_i3': 1e-5,
    'pole_lambda': 1e-5, 'pole_beta': 1e-5, 'phi0': 1e-5, 'psi0': 1e-5, 'axis_b_a': 1e-5,
    'axis_c_a': 1e-5, 'lambert_weight': 1e-4, 'phase_slope': 1e-4}
_RELATIVE = ('precession_period', 'rotation_period')
#: chi^2/nu outside [1/CHI2_FAR, CHI2_FAR] is reported as a misfit of the errors or the model.
CHI2_FAR = 2.0


@dataclass(frozen=True, eq=False)
class InversionFit:
    """
    One local solution.

    ``parameters`` the fitted model; ``names`` the free parameters, ``values`` and ``sigma``
    their values and 1 sigma (units: :data:`~.model.PARAMETER_UNITS`), ``covariance`` theirs;
    ``chi2`` the weighted sum of squares, ``dof`` = points - free parameters - offsets;
    ``block_offsets`` [mag] per block; ``epoch_jd`` t = 0 [JD TDB]; ``start`` where it began;
    ``label`` which candidate of a search it belongs to; ``nfev`` model evaluations,
    ``seconds`` the wall time; ``warnings`` one line each.
    """

    parameters: TumblerParameters
    names: tuple[str, ...]
    values: np.ndarray
    sigma: np.ndarray
    covariance: np.ndarray
    chi2: float
    dof: int
    block_offsets: np.ndarray
    epoch_jd: float
    start: TumblerParameters
    success: bool
    message: str
    nfev: int
    seconds: float
    label: str = ''
    warnings: tuple[str, ...] = ()

    @property
    def chi2_reduced(self) -> float:
        """Return chi^2 / nu (NaN without degrees of freedom)."""
        return self.chi2 / self.dof if self.dof > 0 else math.nan

    def value(self, name: str) -> tuple[float, float]:
        """Return (value, 1 sigma) of a parameter (sigma NaN for a fixed one)."""
        if name in self.names:
            k = self.names.index(name)
            return float(self.values[k]), float(self.sigma[k])
        return float(self.parameters.vector()[list(PARAMETER_UNITS).index(name)]), math.nan


Progress = Callable[[str, float], None]


def _jacobian(model: ForwardModel, start: TumblerParameters, names: tuple[str, ...],
              x: np.ndarray, f0: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Return d residuals / d x by forward differences (backwards where forward fails)."""
    jac = np.empty((f0.size, x.size))
    for k, name in enumerate(names):
        h = STEPS[name] * (abs(x[k]) if name in _RELATIVE else 1.0)
        column = None
        for step in (h, -h):
            if not lower[k] <= x[k] + step <= upper[k]:
                continue
            trial = x.copy()
            trial[k] += step
            f = model.try_residuals(parameters_or_none(start, names, trial))
            if f is not None:
                column = (f - f0) / step
                break
        jac[:, k] = 0.0 if column is None else column
    return jac


def fit_local(campaign: Campaign, start: TumblerParameters,
              options: ModelOptions | None = None, *, epoch_jd: float | None = None,
              max_nfev: int = 60, label: str = '', model: ForwardModel | None = None
              ) -> InversionFit:
    """
    Fit every free parameter from ``start`` (mode and the sign of theta0 stay the start's).

    ``options`` what is free and how fine (:class:`~.model.ModelOptions`); ``epoch_jd`` t = 0
    [JD TDB] (default: the first emission time); ``max_nfev`` the most iterations (each a
    Jacobian, ~one model evaluation per free parameter); ``model`` a forward model of the
    campaign to reuse. ModelError when the start itself cannot be evaluated.
    """
    began = time.perf_counter()
    model = model or ForwardModel(campaign, options or ModelOptions(), epoch_jd)
    names = model.options.free()
    index = [list(PARAMETER_UNITS).index(name) for name in names]
    lower, upper = bounds(names)
    x0 = np.clip(start.vector()[index], lower, upper)
    first = model.try_residuals(parameters_or_none(start, names, x0))
    if first is None:
        raise ModelError('start: the starting parameters give no possible spin state or '
                         'propagation')
    evaluations0 = model.evaluations
    cache: dict[bytes, np.ndarray] = {x0.tobytes(): first}

    def residuals(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in cache:
            f = model.try_residuals(parameters_or_none(start, names, x))
            cache.clear()
            cache[key] = np.full(first.size, np.nan) if f is None else f
        return cache[key]

    def jacobian(x: np.ndarray) -> np.ndarray:
        return _jacobian(model, start, names, x, residuals(x), lower, upper)

    solution = least_squares(residuals, x0, jac=jacobian, bounds=(lower, upper),
                             method='trf', x_scale='jac', max_nfev=max_nfev,
                             xtol=1e-10, ftol=1e-10, gtol=1e-10)
    x = solution.x
    params = start.with_values(names, x)
    f = model.residuals(params)
    jac = jacobian(x)
    chi2 = float(f @ f)
    dof = f.size - len(names) - model.groups
    covariance, unconstrained = _covariance(jac)
    scale = max(1.0, chi2 / dof) if dof > 0 else 1.0
    sigma = np.sqrt(np.maximum(np.diag(covariance), 0.0) * scale)
    values = params.vector()[index]
    warnings = _warnings(solution, names, values, lower, upper, unconstrained, chi2, dof)
    return InversionFit(params, names, values, sigma, covariance, chi2, dof,
                        model.block_offsets(params), float(model.epoch_jd or 0.0), start,
                        bool(solution.success), str(solution.message),
                        model.evaluations - evaluations0, time.perf_counter() - began, label,
                        warnings)


def _covariance(jac: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """Return (J^T J)^-1 by SVD, and the columns no data constrain (infinite variance)."""
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    tiny = s <= s.max() * 1e-12 if s.size else np.zeros(0, dtype=bool)
    inverse = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, s) ** 2)
    covariance = (vt.T * inverse) @ vt
    unconstrained = [int(np.argmax(np.abs(vt[k]))) for k in np.flatnonzero(tiny)]
    for k in unconstrained:
        covariance[k, k] = np.inf
    return covariance, unconstrained


def _warnings(solution: object, names: tuple[str, ...], values: np.ndarray, lower: np.ndarray,
              upper: np.ndarray, unconstrained: list[int], chi2: float,
              dof: int) -> tuple[str, ...]:
    """Return what could make this fit wrong, one line each."""
    out = []
    if not getattr(solution, 'success', False) or getattr(solution, 'status', 0) == 0:
        out.append(f'the fit stopped before converging ({getattr(solution, "message", "")})')
    if dof <= 0:
        out.append(f'no degrees of freedom ({dof}): more parameters than points')
    elif not 1.0 / CHI2_FAR <= chi2 / dof <= CHI2_FAR:
        out.append(f'chi2/nu = {chi2 / dof:.3g}, far from 1: the errors or the model do not '
                   'describe the data (sigma scaled by sqrt(chi2/nu) when > 1)')
    span = np.where(np.isfinite(upper - lower), upper - lower, 1.0)
    for k, name in enumerate(names):
        if np.isfinite(lower[k]) and values[k] - lower[k] < 1e-6 * span[k] or \
                np.isfinite(upper[k]) and upper[k] - values[k] < 1e-6 * span[k]:
            out.append(f'{name} = {values[k]:.6g} sits on its bound: the minimum lies beyond it')
    for k in unconstrained:
        out.append(f'{names[k]}: not constrained by the data (a direction of zero curvature)')
    return tuple(out)

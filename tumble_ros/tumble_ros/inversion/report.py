"""
The inversion's report: text for a reader, JSON for a program (``invert --json``).

Periods in hours, angles in degrees (the literature's units; the fit's vector is in radians),
each value with its 1 sigma; the chi^2, nu and chi^2/nu of every solution, which are accepted,
and the warnings (not unique, aliases, chi^2/nu far from 1, a fit that did not converge).
"""
from __future__ import annotations

import json
import math
from typing import Any

from tumble_ros.inversion.fit import InversionFit
from tumble_ros.inversion.model import PARAMETER_UNITS
from tumble_ros.inversion.search import InversionResult

__all__ = ['fit_record', 'format_fit', 'format_result', 'result_json']

_ANGLES = ('pole_lambda', 'pole_beta', 'phi0', 'psi0')


def _shown(name: str, value: float, sigma: float) -> tuple[float, float, str]:
    """Return a value and sigma in the shown unit (degrees for angles) and that unit."""
    if name in _ANGLES:
        return math.degrees(value), math.degrees(sigma), 'deg'
    return value, sigma, PARAMETER_UNITS[name]


def fit_record(fit: InversionFit) -> dict[str, Any]:
    """Return one solution as plain JSON values (angles in degrees, periods in hours)."""
    values = {}
    for name in PARAMETER_UNITS:
        value, sigma = fit.value(name)
        v, s, unit = _shown(name, value, sigma)
        values[name] = {'value': v, 'sigma': None if not math.isfinite(s) else s,
                        'unit': unit, 'free': name in fit.names}
    return {'label': fit.label, 'mode': fit.parameters.spin.mode,
            'anti_aligned': fit.parameters.spin.anti_aligned, 'parameters': values,
            'chi2': fit.chi2, 'dof': fit.dof, 'chi2_reduced': fit.chi2_reduced,
            'epoch_jd_tdb': fit.epoch_jd, 'block_offsets': [float(v) for v in fit.block_offsets],
            'converged': fit.success, 'evaluations': fit.nfev, 'seconds': fit.seconds,
            'warnings': list(fit.warnings)}


def format_fit(fit: InversionFit) -> str:
    """Return one solution as lines of text."""
    spin = fit.parameters.spin
    lines = [f'{spin.mode}{", theta0 > 90 deg" if spin.anti_aligned else ""}: chi2 = '
             f'{fit.chi2:.6g}, nu = {fit.dof}, chi2/nu = {fit.chi2_reduced:.4g}'
             + (f'  [{fit.label}]' if fit.label else '')]
    for name in PARAMETER_UNITS:
        value, sigma = fit.value(name)
        v, s, unit = _shown(name, value, sigma)
        spread = f' +- {s:.3g}' if math.isfinite(s) else ' (fixed)'
        lines.append(f'  {name:<18} {v:.8g}{spread} {unit}'.rstrip())
    lines += [f'  warning: {w}' for w in fit.warnings]
    return '\n'.join(lines)


def format_result(result: InversionResult) -> str:
    """Return the whole inversion as text: the accepted solutions first, then the others."""
    best = result.best
    lines = [f'inversion of {result.campaign_source or "a campaign"}: '
             f'{len(result.solutions)} distinct solutions from {len(result.candidates)} '
             f'candidates, {len(result.accepted)} accepted (chi2 <= {result.threshold:.6g}), '
             f'{result.seconds:.1f} s',
             f'epoch (t = 0): JD {best.epoch_jd:.8f} TDB; angles ecliptic J2000']
    lines += [f'warning: {w}' for w in result.warnings]
    for k, fit in enumerate(result.accepted, start=1):
        lines += ['', f'accepted solution {k}:', format_fit(fit)]
    others = [f for f in result.solutions if not any(f is a for a in result.accepted)]
    if others:
        lines += ['', 'rejected solutions (chi2, mode, P_phi, P_psi [h]):']
        for fit in others:
            spin = fit.parameters.spin
            lines.append(f'  {fit.chi2:.6g}  {spin.mode}  {fit.value("precession_period")[0]:.6g}'
                         f'  {fit.value("rotation_period")[0]:.6g}  [{fit.label}]')
    lines += ['', 'candidates (mode, P_phi, P_psi [h], best chi2 on the grid, after fits):']
    for c in result.candidates:
        pair = c.candidate
        lines.append(f'  {pair.mode}  {pair.precession_period:.6g}  '
                     f'{pair.rotation_period:.6g}  {c.chi2_grid:.6g}  {c.chi2_fit:.6g}  '
                     f'[{pair.label}]')
    return '\n'.join(lines)


def result_json(result: InversionResult) -> str:
    """Return the whole inversion as JSON text (non-finite numbers as null)."""
    document = {
        'source': result.campaign_source, 'seconds': result.seconds,
        'threshold': result.threshold, 'warnings': list(result.warnings),
        'accepted': [fit_record(f) for f in result.accepted],
        'solutions': [fit_record(f) for f in result.solutions],
        'candidates': [{'label': c.candidate.label, 'mode': c.candidate.mode,
                        'precession_period_h': c.candidate.precession_period,
                        'rotation_period_h': c.candidate.rotation_period,
                        'chi2_grid': c.chi2_grid, 'chi2_fit': c.chi2_fit}
                       for c in result.candidates]}
    return json.dumps(_finite(document), indent=1)


def _finite(value: Any) -> Any:
    """Return ``value`` with every non-finite float as None (JSON has no inf, NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value

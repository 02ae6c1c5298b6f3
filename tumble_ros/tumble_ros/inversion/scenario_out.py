"""
A fit as a scenario: the params file ``python -m tumble_ros fit.yaml`` (``make run``) runs.

The spin state is written as the params file's ``spin.*`` block (docs/spin_state.md) in hours
(``time_unit: h``), torque-free (``orbit_rate: 0``), its t = 0 the fit's epoch (stated in the
header, JD TDB); the run lasts the campaign's span (at least 2 P_psi) with 400 samples a
P_phi, DOP853 at 1e-11; the lightcurve's law is the fit's when it is one of the registry's
(c = 0.1: ``kaasalainen``), and the comparator runs the exact torque-free solution. The shape
(ellipsoid axis ratios), the law's weight and the offsets are in the header: the scenario's
body is its inertia (the fitted ratios), which a uniform ellipsoid of the fitted axes would
contradict.
"""
from __future__ import annotations

import math
from typing import Any

from tumble_ros.core.model.scattering import KAASALAINEN_LAMBERT_WEIGHT
from tumble_ros.core.units import HOURS_PER_YEAR
from tumble_ros.inversion.fit import InversionFit

__all__ = ['scenario_parameters', 'scenario_yaml']


def scenario_parameters(fit: InversionFit, span_hours: float = 0.0) -> dict[str, Any]:
    """Return the nested ``ros__parameters`` of ``fit``'s scenario (module docstring)."""
    spin = fit.parameters.spin
    p_phi = spin.precession_period * HOURS_PER_YEAR
    p_psi = spin.rotation_period * HOURS_PER_YEAR
    duration = max(float(span_hours), 2.0 * p_psi)
    law = 'kaasalainen' if abs(fit.parameters.lambert_weight - KAASALAINEN_LAMBERT_WEIGHT) \
        < 1e-12 else 'lommel_seeliger'
    return {
        'time_unit': 'h', 'orbit_rate': 0.0, 'duration': round(duration, 6),
        'output_interval': round(min(p_phi, p_psi) / 400.0, 9),
        'integrator': {'method': 'dop853', 'rtol': 1.0e-11, 'atol': 1.0e-11},
        'lightcurve': {'law': law},
        'spin': {'mode': spin.mode, 'precession_period': p_phi, 'rotation_period': p_psi,
                 'inertia_ratios': list(spin.inertia_ratios), 'pole': list(spin.pole),
                 'phases': list(spin.phases), 'anti_aligned': spin.anti_aligned}}


def _header(fit: InversionFit, title: str) -> str:
    """Return the comment lines above the parameters."""
    spin = fit.parameters.spin
    lon, lat = (math.degrees(a) for a in spin.pole)
    b, c = fit.parameters.axis_ratios
    lines = [f'# {title}',
             f"# t = 0 is JD {fit.epoch_jd:.8f} TDB (the fit's epoch); the orbital frame is "
             'ecliptic J2000:',
             f'# L towards (lambda, beta) = ({lon:.3f} deg, {lat:.3f} deg).',
             f'# chi2 = {fit.chi2:.6g} for nu = {fit.dof} (chi2/nu = {fit.chi2_reduced:.4g}); '
             f'{fit.label or "a local fit"}.',
             f'# Shape: ellipsoid axes 1 : {b:.4f} : {c:.4f} (along I1, I2, I3); scattering '
             f'S_LS + {fit.parameters.lambert_weight:.4g} S_L; phase slope '
             f'{fit.parameters.phase_slope:.4g} mag/rad.',
             '# The scenario is torque-free: what the fitted state does by itself '
             '(docs/inversion.md).']
    lines += [f'# warning: {w}' for w in fit.warnings]
    return '\n'.join(lines) + '\n'


def scenario_yaml(fit: InversionFit, span_hours: float = 0.0,
                  title: str = 'A tumbler fitted to photometry (python -m tumble_ros invert)'
                  ) -> str:
    """Return the params file's text of ``fit`` (load_scenario reads it; ``make run`` runs it)."""
    import yaml

    document = {'/**/comparator': {'ros__parameters': {'model': 'torque_free_exact'}},
                '/**/sim': {'ros__parameters': scenario_parameters(fit, span_hours)}}
    dumper = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)
    return _header(fit, title) + yaml.dump(document, Dumper=dumper, sort_keys=False)

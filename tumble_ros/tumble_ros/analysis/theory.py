"""
The theory's frequency lines for a recording, and the aliasing check of its sampling.

Frequencies in rad/yr of wx (body axes), from the scenario's initial state; the sampling
interval dt in simulated years, its Nyquist rate pi/dt in rad/yr.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from tumble_ros.core import make_model, ModelNotApplicable, Scenario
from tumble_ros.core.analytic import COS_THETA_TOL, SYMMETRY_TOL

from .timeaxis import Sampling

__all__ = ['AliasingCheck', 'TheoryLine', 'alias', 'check_aliasing', 'theory_lines']


@dataclass(frozen=True)
class TheoryLine:
    """A frequency [rad/yr] at which the theory expects wx to oscillate."""

    name: str
    omega: float
    meaning: str


def _symmetric(scenario: Scenario) -> bool:
    ix, iy, _ = scenario.inertia
    return abs(ix - iy) <= SYMMETRY_TOL * max(abs(ix), abs(iy))


def theory_lines(scenario: Scenario | None, omega: np.ndarray | None = None
                 ) -> tuple[list[TheoryLine], str]:
    """
    Return the frequencies the theory expects in wx and a one-line description of their basis.

    Symmetric body (Ix = Iy), from the scenario's inputs a = (Iz - Ix)/Ix, w0 = omega0[2],
    ws = orbit_rate, theta0 = euler0[2] (docs/analytic.md):

    - wE = |a w0|, the free (nutation) term of every linearised model;
    - the paper's forced lines |wE +- wA|, wA = 2 (ws + (w0 + wE)/cos theta0) (ERRATA 6),
      present if the body precessed as the paper assumes;
    - the fast-spin forced lines |w0| and |w0 -+ 2 ws|, and the nutation with the tidal
      shift |a w0 + dbar|, dbar = S (3 cos^2 theta0 - 1)/2, S = (3/2) ws^2 a/((1 + a) w0).

    Without torque (ws = 0) only wE (symmetric) or the Euler-Poinsot frequency 2 pi/period
    (asymmetric, ``torque_free_exact``). Asymmetric body with torque: an estimate, the
    Euler-equation rate max_i |Ij - Ik|/Ii * max|w| and the forcing |w| + 2 ws.
    """
    if scenario is None:
        return [], 'no scenario: the expected frequencies are unknown'
    ix, iy, iz = scenario.inertia
    ws = scenario.orbit_rate
    w0 = scenario.omega0[2]
    theta = scenario.euler0[2]
    lines: list[TheoryLine] = []
    if _symmetric(scenario):
        a = (iz - ix) / ix
        w_e = a * w0
        basis = (f'symmetric body: a = {a:.6g}, w0 = {w0:.6g} rad/yr, ws = {ws:.6g} rad/yr, '
                 f'theta0 = {theta:.6g} rad (scenario inputs)')
        lines.append(TheoryLine('wE', abs(w_e), 'free nutation wE = a w0'))
        if ws == 0.0:
            return lines, basis + '; no torque: wE only (exact)'
        if abs(math.cos(theta)) >= COS_THETA_TOL:
            w_a = 2.0 * (ws + (w0 + w_e) / math.cos(theta))
            lines.append(TheoryLine('|wA-wE|', abs(w_e - w_a),
                                    f"paper's forced term, wA = {w_a:.6g} rad/yr"))
            lines.append(TheoryLine('|wA+wE|', abs(w_e + w_a),
                                    f"paper's forced term, wA = {w_a:.6g} rad/yr"))
        lines.append(TheoryLine('|w0|', abs(w0), 'fast-spin forced term (spin)'))
        lines.append(TheoryLine('|w0-2ws|', abs(w0 - 2 * ws), 'fast-spin forced term'))
        lines.append(TheoryLine('|w0+2ws|', abs(w0 + 2 * ws), 'fast-spin forced term'))
        if w0 != 0.0:
            s = 1.5 * ws * ws * a / ((1.0 + a) * w0)
            dbar = s * (3.0 * math.cos(theta) ** 2 - 1.0) / 2.0
            lines.append(TheoryLine('|wE+dbar|', abs(w_e + dbar),
                                    f'fast-spin nutation with the tidal shift dbar = {dbar:.4g}'))
        return lines, basis
    moments = (ix, iy, iz)
    basis = f'asymmetric body: inertia {tuple(moments)}, ws = {ws:.6g} rad/yr'
    if ws == 0.0:
        try:
            model = make_model('torque_free_exact', scenario)
        except ModelNotApplicable as err:
            return [], basis + f'; no torque-free frequency: {err}'
        period = model.period
        if math.isfinite(period) and period > 0:
            lines.append(TheoryLine('Euler-Poinsot', 2 * math.pi / period,
                                    f'torque-free period {period:.6g} yr ({model.mode})'))
        return lines, basis + '; no torque: Euler-Poinsot motion (exact)'
    wmax = float(np.max(np.linalg.norm(omega, axis=1))) if omega is not None and len(omega) \
        else float(np.linalg.norm(scenario.omega0))
    rate = max(abs(moments[(i + 1) % 3] - moments[(i + 2) % 3]) / moments[i] for i in range(3))
    lines.append(TheoryLine('nutation (estimate)', rate * wmax,
                            'max |Ij - Ik|/Ii * max|w| (no linear theory for Ix != Iy)'))
    lines.append(TheoryLine('|w|+2ws (estimate)', wmax + 2 * ws, 'forcing, upper estimate'))
    return lines, basis + '; estimates only'


@dataclass(frozen=True)
class AliasingCheck:
    """pi/dt (the Nyquist rate of the sampling) against the fastest expected line."""

    dt: float | None
    nyquist: float | None                    # pi / dt [rad/yr]
    fastest: TheoryLine | None
    aliased: tuple[tuple[TheoryLine, float], ...]   # (line, where it appears: its alias) [rad/yr]
    warning: str | None


def alias(omega: float, nyquist: float) -> float:
    """Return where a line at ``omega`` appears when sampled at the Nyquist rate ``nyquist``."""
    period = 2.0 * nyquist
    return abs(omega - period * round(omega / period))


def check_aliasing(samp: Sampling, lines: list[TheoryLine]) -> AliasingCheck:
    """
    Check the sampling against the expected lines.

    WARNING when pi/dt is below any expected line (the fastest decides); each aliased line is
    listed with the frequency it masquerades as.
    """
    if samp.dt is None or not lines:
        return AliasingCheck(samp.dt, None, None, (), None)
    nyquist = math.pi / samp.dt
    fastest = max(lines, key=lambda line: line.omega)
    aliased = tuple((line, alias(line.omega, nyquist)) for line in lines
                    if line.omega > nyquist)
    warning = None
    if aliased:
        listing = '; '.join(f'{line.name} = {line.omega:.4g} rad/yr (appears at '
                            f'{seen:.4g})' for line, seen in aliased)
        warning = (f'sampling interval dt = {samp.dt:.4g} yr (Nyquist pi/dt = {nyquist:.4g} '
                   f'rad/yr) aliases {listing}: the spectrum and any slow amplitude change in '
                   f'the plots can be aliasing (ERRATA.md, last section); sample at dt < '
                   f'pi/{fastest.omega:.4g} = {math.pi / fastest.omega:.3g} yr, several times '
                   f'finer for plots')
    return AliasingCheck(samp.dt, nyquist, fastest, aliased, warning)

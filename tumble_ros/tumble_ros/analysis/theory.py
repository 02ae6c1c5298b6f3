"""
The theory's frequency lines for a recording, and the aliasing check of its sampling.

The lines are asked of the analytic models, not derived here
(``tumble_ros.core.analytic.characteristic_frequencies``). Frequencies in rad/yr of wx (body
axes), from the scenario's initial state; the sampling interval dt in simulated years, its
Nyquist rate pi/dt in rad/yr.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from tumble_ros.core import Scenario
from tumble_ros.core.analytic import characteristic_frequencies, Frequency

from .timeaxis import Sampling

__all__ = ['AliasingCheck', 'TheoryLine', 'alias', 'check_aliasing', 'theory_lines']

#: A frequency [rad/yr] at which the theory expects wx to oscillate: name, omega, meaning.
TheoryLine = Frequency


def theory_lines(scenario: Scenario | None, omega: np.ndarray | None = None
                 ) -> tuple[list[TheoryLine], str]:
    """
    Return the frequencies the theory expects in wx and a one-line description of their basis.

    They are the analytic models' (:func:`tumble_ros.core.analytic.characteristic_frequencies`,
    docs/analysis.md lists them): for a symmetric body wE, the paper's |wA -+ wE|, the fast-spin
    lines |w0|, |w0 -+ 2 ws| and |wE + dbar|; without torque wE or the Euler-Poinsot frequency;
    for an asymmetric body under torque two estimates, which use max|w| of ``omega`` (n, 3), the
    recorded w [rad/yr] (|omega0| without it). Without a scenario: no lines, and the basis
    says so.
    """
    if scenario is None:
        return [], 'no scenario: the expected frequencies are unknown'
    norms = (np.linalg.norm(omega, axis=1) if omega is not None and len(omega)
             else np.empty(0))
    norms = norms[np.isfinite(norms)]   # non-finite samples never set the expected lines
    omega_max = float(np.max(norms)) if len(norms) else None
    lines, basis = characteristic_frequencies(scenario, omega_max)
    return list(lines), basis


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
                            f'{seen:.4g} rad/yr)' for line, seen in aliased)
        warning = (f'sampling interval dt = {samp.dt:.4g} yr (Nyquist pi/dt = {nyquist:.4g} '
                   f'rad/yr) aliases {listing}: the spectrum and any slow amplitude change in '
                   f'the plots can be aliasing (docs/paper.md, conventions); sample at dt < '
                   f'pi / {fastest.name} = {math.pi / fastest.omega:.3g} yr, several times '
                   f'finer for plots')
    return AliasingCheck(samp.dt, nyquist, fastest, aliased, warning)

"""
The recorded lightcurve: its periods and its figure (``analyze RUN.mcap --lightcurve``).

The ``lightcurve`` topic's magnitudes (core/photometry, recorded per sample), reduced (the
distance modulus and a fitted phase function removed: :func:`reduced_lightcurve`), are searched
for one or two periods (:func:`tumble_ros.analysis.periods.search_periods`, times in hours) and
drawn: reduced magnitude against time with the fit, and the residuals. docs/analysis.md,
"Periods from a lightcurve".
"""
from __future__ import annotations

from dataclasses import replace
import math
from pathlib import Path

import numpy as np

from tumble_ros.core.units import HOURS_PER_YEAR
from tumble_ros.errors import AnalysisError
from tumble_ros.topics import LIGHTCURVE

from .periods import PeriodSolution, Progress, search_periods
from .recording import Recording
from .spin import spin_change

__all__ = ['FIGURE_NAME', 'PHASE_SPAN', 'SPIN_CHANGE', 'recorded_lightcurve', 'recorded_periods',
           'reduced_lightcurve', 'write_lightcurve_figure']

#: the figure's file name in the --figures directory
FIGURE_NAME = 'lightcurve.png'
#: the lightcurve topic's columns (topics.SAMPLE_TOPICS)
_BRIGHTNESS, _MAGNITUDE, _PHASE = 0, 1, 2
#: a phase angle that varies by more than this [rad] has its phase function removed
PHASE_SPAN = math.radians(1.0)
#: a period of the spin state that changes by more than this fraction is warned about
SPIN_CHANGE = 0.01


def recorded_lightcurve(rec: Recording) -> tuple[np.ndarray, np.ndarray]:
    """Return (t [h], magnitude [mag]) of the recording's lit samples; AnalysisError if none."""
    t, mag, _, _ = _lit(rec)
    return t, mag


def _lit(rec: Recording) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t [h], magnitude [mag], brightness, phase angle [rad]) of the lit samples."""
    if rec.lightcurve_t.size == 0:
        raise AnalysisError(f'{rec.path}: no {LIGHTCURVE} topic (lightcurve.enabled false, or a '
                            f'body that cannot exist): --lightcurve has nothing to search')
    mag = rec.lightcurve[:, _MAGNITUDE]
    lit = np.isfinite(mag) & (rec.lightcurve[:, _BRIGHTNESS] > 0.0)
    if lit.sum() < 20:
        raise AnalysisError(f'{rec.path}: the lightcurve has {int(lit.sum())} lit samples, '
                            f'need at least 20')
    return (rec.lightcurve_t[lit] * HOURS_PER_YEAR, mag[lit],
            rec.lightcurve[lit, _BRIGHTNESS], rec.lightcurve[lit, _PHASE])


def reduced_lightcurve(rec: Recording) -> tuple[np.ndarray, np.ndarray, str]:
    """
    Return (t [h], reduced magnitude [mag], what was removed) of the lit samples.

    The magnitude is -2.5 log10(B / B_ref) + 5 log10(r delta) (core/photometry): with the
    recorded brightness B, m + 2.5 log10 B is the distance modulus plus a constant, removed
    (the magnitude at the recording's nearest distances is kept). What the phase angle alpha
    does to B (the body's phase curve) is then removed: a quadratic a + b alpha + c alpha^2
    fitted by least squares to the reduced magnitudes, when alpha varies by more than
    PHASE_SPAN. What remains is the part of the brightness that the rotation makes (the shape
    seen at a changing aspect, to the quadratic's accuracy).
    """
    t, mag, brightness, phase = _lit(rec)
    modulus = mag + 2.5 * np.log10(brightness)
    reduced = mag - (modulus - modulus.min())
    parts = [f'reduced magnitudes: the distance modulus 5 log10(r delta) removed (it spans '
             f'{np.ptp(modulus):.3g} mag)']
    if np.ptp(phase) > PHASE_SPAN:
        design = np.column_stack([np.ones_like(phase), phase, phase * phase])
        coef = np.linalg.lstsq(design, reduced, rcond=None)[0]
        fitted = design @ coef
        reduced = reduced - (fitted - fitted.min())
        parts.append(f'a quadratic phase function of the phase angle '
                     f'({np.degrees(phase.min()):.1f} to {np.degrees(phase.max()):.1f} deg, '
                     f'{np.ptp(fitted):.3g} mag) removed')
    else:
        parts.append(f'the phase angle is fixed ({np.degrees(phase.mean()):.1f} deg)')
    return t, reduced, ', '.join(parts)


def _spin_warning(rec: Recording) -> str | None:
    """Why one pair of periods cannot describe the recording (the spin state changed), or None."""
    change, _ = spin_change(rec)
    if change is None:
        return None
    pairs = [(name, getattr(change.start, key), getattr(change.end, key))
             for name, key in (('P_phi', 'precession_period'), ('P_psi', 'rotation_period'))]
    moved = [(name, a * HOURS_PER_YEAR, b * HOURS_PER_YEAR) for name, a, b in pairs
             if a is not None and b is not None and math.isfinite(a) and math.isfinite(b)
             and abs(b - a) > SPIN_CHANGE * abs(a)]
    if not moved:
        return None
    return ('the spin state changed during the recording (' + ', '.join(
        f'{name} {a:.4g} -> {b:.4g} h' for name, a, b in moved) + '): no single pair of '
        'periods holds over it; search the lightcurve before and after the change')


def recorded_periods(rec: Recording, period_min: float | None = None,
                     period_max: float | None = None, progress: Progress | None = None
                     ) -> tuple[np.ndarray, np.ndarray, PeriodSolution]:
    """
    Return (t [h], reduced magnitude, the search's solution in [period_min, period_max] [h]).

    The search runs on :func:`reduced_lightcurve` (the solution's ``reduction`` says what
    was removed); a change of the spin state over the recording is one more warning.
    """
    t, mag, note = reduced_lightcurve(rec)
    try:
        sol = search_periods(t, mag, period_min=period_min, period_max=period_max,
                             unit=' h', progress=progress)
    except ValueError as err:
        raise AnalysisError(f'{rec.path}: lightcurve: {err}') from None
    spin = _spin_warning(rec)
    return t, mag, replace(sol, reduction=note,
                           warnings=((spin,) if spin else ()) + sol.warnings)


def write_lightcurve_figure(path: Path, t: np.ndarray, mag: np.ndarray, sol: PeriodSolution,
                            overwrite: bool = False) -> Path:
    """Draw magnitude vs time [h] with the fit, and the residuals, into ``path`` (PNG)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    path = Path(path)
    if path.is_symlink():
        raise AnalysisError(f'{path} is a symbolic link: refused')
    if path.exists() and not overwrite:
        raise AnalysisError(f'{path} exists (--overwrite replaces existing figures)')
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True,
                                      gridspec_kw={'height_ratios': [3, 1]})
    fine = np.linspace(t.min(), t.max(), 4000)
    top.plot(t, mag, '.', ms=2, color='0.3', label='magnitude')
    top.plot(fine, sol.model(fine), '-', lw=0.7, color='C3', label='fit')
    top.invert_yaxis()
    top.set_ylabel('reduced magnitude [mag]')
    periods = (f'P1 = {sol.p1:.5g} h, P2 = {sol.p2:.5g} h' if sol.two_periods
               else f'P = {sol.p1:.5g} h')
    top.set_title(f'{periods} (order {sol.order}, RMS {sol.rms:.3g} mag)')
    top.legend(loc='upper right')
    bottom.plot(t, mag - sol.model(t), '.', ms=2, color='0.3')
    bottom.set_ylabel('residual [mag]')
    bottom.set_xlabel('t [h]')
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

"""
The recorded lightcurve: its periods and its figure (``analyze RUN.mcap --lightcurve``).

The ``lightcurve`` topic's magnitudes (core/photometry, recorded per sample) are searched for one
or two periods (:func:`tumble_ros.analysis.periods.search_periods`, times in hours) and drawn:
magnitude against time with the fit, and the residuals. docs/analysis.md, "Periods from a
lightcurve".
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from tumble_ros.core.model.units import HOURS_PER_YEAR
from tumble_ros.errors import AnalysisError
from tumble_ros.topics import LIGHTCURVE

from .periods import PeriodSolution, search_periods
from .recording import Recording

__all__ = ['FIGURE_NAME', 'recorded_lightcurve', 'recorded_periods', 'write_lightcurve_figure']

#: the figure's file name in the --figures directory
FIGURE_NAME = 'lightcurve.png'
#: the lightcurve topic's magnitude column (topics.SAMPLE_TOPICS)
_MAGNITUDE = 1


def recorded_lightcurve(rec: Recording) -> tuple[np.ndarray, np.ndarray]:
    """Return (t [h], magnitude [mag]) of the recording's lit samples; AnalysisError if none."""
    if rec.lightcurve_t.size == 0:
        raise AnalysisError(f'{rec.path}: no {LIGHTCURVE} topic (lightcurve.enabled false, or a '
                            f'body that cannot exist): --lightcurve has nothing to search')
    mag = rec.lightcurve[:, _MAGNITUDE]
    lit = np.isfinite(mag)
    if lit.sum() < 20:
        raise AnalysisError(f'{rec.path}: the lightcurve has {int(lit.sum())} lit samples, '
                            f'need at least 20')
    return rec.lightcurve_t[lit] * HOURS_PER_YEAR, mag[lit]


def recorded_periods(rec: Recording, period_min: float | None = None,
                     period_max: float | None = None
                     ) -> tuple[np.ndarray, np.ndarray, PeriodSolution]:
    """Return (t [h], magnitude, the search's solution in [period_min, period_max] [h])."""
    t, mag = recorded_lightcurve(rec)
    try:
        return t, mag, search_periods(t, mag, period_min=period_min, period_max=period_max)
    except ValueError as err:
        raise AnalysisError(f'{rec.path}: lightcurve: {err}') from None


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
    top.set_ylabel('magnitude [mag]')
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

"""
The inversion's figures, as matplotlib Figures (no pyplot state) and PNG drawings.

* :func:`nights_figure`: each lightcurve block's data (with 1 sigma) and the best model, the
  block's offset applied, against hours from the block's first point;
* :func:`period_plane_figure`: every candidate's (P_phi, P_psi) [h], coloured by its best
  chi^2 after the local fits (log scale), the accepted solutions marked;
* :func:`poles_figure`: L's direction (lambda, beta) of every solution on the sky (Mollweide,
  ecliptic J2000), the accepted ones filled.
"""
from __future__ import annotations

import io
import math

from matplotlib.figure import Figure
import numpy as np

from tumble_ros.inversion.campaign import Campaign
from tumble_ros.inversion.fit import InversionFit
from tumble_ros.inversion.model import ForwardModel, ModelOptions
from tumble_ros.inversion.search import InversionResult

__all__ = ['nights_figure', 'period_plane_figure', 'poles_figure', 'figure_files',
           'MAX_PANELS']

#: The most blocks drawn (the first ones); a note says how many were left out.
MAX_PANELS = 36


def nights_figure(campaign: Campaign, fit: InversionFit,
                  options: ModelOptions | None = None) -> Figure:
    """Return each block's magnitudes [mag] and the fit's model, one panel a block."""
    model = ForwardModel(campaign, options or ModelOptions(), fit.epoch_jd)
    fitted = model.fitted(fit.parameters)
    blocks = [b for b in range(len(campaign.block_names)) if np.any(campaign.block == b)]
    shown = blocks[:MAX_PANELS]
    columns = min(6, len(shown))
    rows = math.ceil(len(shown) / columns)
    fig = Figure(figsize=(2.6 * columns, 2.0 * rows + 0.6), layout='constrained')
    for k, b in enumerate(shown):
        ax = fig.add_subplot(rows, columns, k + 1)
        mask = campaign.block == b
        hours = (campaign.jd_tdb[mask] - campaign.jd_tdb[mask][0]) * 24.0
        ax.errorbar(hours, campaign.magnitude[mask], campaign.sigma[mask], fmt='.', ms=2,
                    lw=0.5, color='0.3')
        ax.plot(hours, fitted[mask], color='C3', lw=1.0)
        ax.invert_yaxis()
        ax.set_title(campaign.block_names[b][:30], fontsize=7)
        ax.tick_params(labelsize=6)
    more = f' (first {len(shown)} of {len(blocks)} blocks)' if len(blocks) > len(shown) else ''
    fig.suptitle(f'data and model: chi2/nu = {fit.chi2_reduced:.3g}; hours from each '
                 f"block's start, magnitudes{more}", fontsize=9)
    return fig


def period_plane_figure(result: InversionResult) -> Figure:
    """Return the candidates' chi^2 over the (P_phi, P_psi) plane [h]."""
    fig = Figure(figsize=(6.5, 5.0), layout='constrained')
    ax = fig.add_subplot()
    for mode, marker in (('SAM', 'o'), ('LAM', 's')):
        picked = [c for c in result.candidates if c.candidate.mode == mode
                  and math.isfinite(c.chi2_fit)]
        if picked:
            points = ax.scatter([c.candidate.precession_period for c in picked],
                                [c.candidate.rotation_period for c in picked],
                                c=np.log10([c.chi2_fit for c in picked]), marker=marker,
                                cmap='viridis_r', label=f'{mode} candidates')
            fig.colorbar(points, ax=ax, label='log10 chi2 after the fits')
    for fit in result.accepted:
        ax.plot(fit.value('precession_period')[0], fit.value('rotation_period')[0], 'r+',
                ms=12)
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('P_phi [h]')
    ax.set_ylabel('P_psi [h]')
    ax.set_title('period plane: candidates (colour), accepted solutions (+)', fontsize=9)
    ax.legend(fontsize=7)
    return fig


def poles_figure(result: InversionResult) -> Figure:
    """Return L's direction of every solution on the sky (ecliptic, Mollweide)."""
    fig = Figure(figsize=(7.0, 4.0), layout='constrained')
    ax = fig.add_subplot(projection='mollweide')
    for fit in result.solutions:
        lon, lat = fit.parameters.spin.pole
        accepted = any(fit is a for a in result.accepted)
        ax.plot(-((lon + math.pi) % (2 * math.pi) - math.pi), lat,
                'o' if accepted else 'x', color='C3' if accepted else '0.5',
                ms=7 if accepted else 4)
    ax.grid(True, lw=0.3)
    ax.set_title("L's direction of the solutions (filled: accepted); ecliptic J2000, "
                 'longitude increasing to the left', fontsize=8)
    return fig


def figure_files(campaign: Campaign, result: InversionResult,
                 options: ModelOptions | None = None) -> list[tuple[str, bytes]]:
    """Return the three figures as (file name, PNG bytes)."""
    out = []
    for name, fig in (('nights.png', nights_figure(campaign, result.best, options)),
                      ('period_plane.png', period_plane_figure(result)),
                      ('poles.png', poles_figure(result))):
        buffer = io.BytesIO()
        fig.savefig(buffer, format='png', dpi=110)
        out.append((name, buffer.getvalue()))
    return out

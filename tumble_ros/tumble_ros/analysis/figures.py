"""
The paper's figures from a recording, as PNG files (matplotlib, Agg canvas: no display).

    from tumble_ros.analysis import load_recording, write_figures
    paths = write_figures(load_recording("run.mcap"), "figures/")

Every function takes a :class:`~tumble_ros.analysis.recording.Recording` and an output
directory (created if needed), writes its PNG file(s) there and returns the list of paths
written, empty when the recording lacks what the figure needs:

- :func:`plot_angular_velocity` ``omega.png``: wx, wy, wz against t (paper Figs 3-9), the
  analytic model's w overlaid as a bold line when the comparator recorded it (as the paper
  draws its analytic solution), impact pulses marked. The axes are scaled on the numeric
  solution: a model that leaves that range is clipped (its off-scale samples marked at the
  edge) and the time it left the numeric solution (``ErrorStats.t_departure``) drawn, so that
  a diverging model (Fig 9's grows to +-4,400 rad/yr about +-0.2) does not flatten the
  solution into a line under a band;
- :func:`plot_omega_windows` ``omega_windows.png``, for long runs (at least
  :data:`WINDOWS_FROM` samples): w at full resolution in zoomed windows of
  :data:`WINDOW_SAMPLES` samples: the start, each impact (up to :data:`MAX_IMPACT_WINDOWS`),
  the end; ``omega.png`` shows the whole run as an envelope;
- :func:`plot_wy_vs_wx` ``wy_vs_wx.png``: wy against wx (Fig 9, bottom);
- :func:`plot_error` ``error.png``: the comparator's error components and |error| against t;
- :func:`plot_impacts` ``impact_<k>_id<id>.png``: w around each impact with the pulse
  interval marked (Fig 10);
- :func:`plot_spectrum` ``spectrum_wx.png``: the amplitude spectrum of wx with the theory's
  lines and the Nyquist rate.

The figures are drawn on :class:`matplotlib.figure.Figure` with the Agg canvas directly, never
through pyplot, so no GUI backend is touched and nothing global is changed.

Files are never written through a symbolic link and, unless ``overwrite=True``, never replace an
existing file: every figure is drawn first, then all their names are checked, and only if none is
taken (:class:`FigureExistsError` names them) or a symbolic link (:class:`FigurePathError`) are
they written. The output directory itself must not be a symbolic link. Files are created with
O_CREAT | O_EXCL | O_NOFOLLOW relative to the directory's descriptor; with ``overwrite=True`` a
figure is written to a new temporary file and renamed over the old one (a rename replaces a
link, never what it points to): :mod:`.figure_files`, which needs no matplotlib.

:data:`FIGURES` names the figures :func:`write_figures` draws, in order; the main job draws them
in worker processes started before its recording (:mod:`.figure_pool`: the same bytes).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
import io
import os
from pathlib import Path
from typing import cast

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator
import numpy as np

from .comparator import comparator_errors
from .display import DisplayUnits, is_flyby, recording_units
from .figure_files import (check_outputs, Drawing, FigureExistsError, FigurePathError,
                           write_files)
from .impacts import impact_intervals
from .recording import Recording, ROOT_NAMESPACE
from .spectrum import spectrum
from .spin import closest_approach
from .summary import AnalysisSummary, analyze, SummaryParts
from .theory import theory_lines
from .timeaxis import runs


__all__ = ['FigureExistsError', 'FigurePathError', 'plot_angular_velocity', 'plot_error',
           'plot_impacts', 'plot_omega_windows', 'plot_spectrum', 'plot_wy_vs_wx',
           'write_figures', 'numeric_limits', 'check_outputs', 'write_files', 'FIGURES',
           'draw_figures', 'warm_up', 'omega_figure', 'wy_vs_wx_figure', 'error_figure',
           'spectrum_figure', 'time_axis']

DPI = 110
#: Above this many samples the wy-vs-wx path is drawn as a density image (_draw_path_density).
PATH_POINTS_MAX = 20_000
PATH_DENSITY_BINS = 500
#: Bins of a long time series' display envelope (about two per pixel column of a figure).
ENVELOPE_BINS = 2000
_LABELS = ('$\\omega_x$', '$\\omega_y$', '$\\omega_z$')
#: Long runs (this many samples or more) also get zoomed windows (omega_windows.png).
WINDOWS_FROM = 20_000
#: Samples in a zoomed window; at most this many impact windows.
WINDOW_SAMPLES = 400
MAX_IMPACT_WINDOWS = 4
#: Most per-impact figures (``impact_<k>_id<id>.png``) one recording gets: the first ones in
#: time. A run of 10,000 impacts would otherwise spend about an hour (~0.3 s each) drawing
#: them; every impact is still in the summary and in the recording.
MAX_IMPACT_FIGURES = 20
#: Margin around the numeric solution's range on the w axes (fraction of the range).
MARGIN = 0.08


def _new(rows: int = 1, height: float = 3.0, width: float = 9.0):
    fig = Figure(figsize=(width, height * rows), dpi=DPI, layout='constrained')
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    return fig, axes


class _UnitTicks(MaxNLocator):
    """Ticks at round values of a display unit on an axis whose data are in years."""

    def __init__(self, years_per_unit: float):
        super().__init__(nbins='auto', steps=[1, 2, 2.5, 5, 10])
        self.years_per_unit = years_per_unit

    # (matplotlib's stubs say Sequence[float]; MaxNLocator returns an array)
    def tick_values(self, vmin: float, vmax: float) -> np.ndarray:  # type: ignore[override]
        scale = self.years_per_unit
        return np.asarray(super().tick_values(vmin / scale, vmax / scale)) * scale


def _unit(rec: Recording) -> DisplayUnits:
    """Return the units the recording is shown in (:func:`.display.recording_units`)."""
    return recording_units(rec)


def _scaled_axis(axis, years_per_unit: float) -> None:
    """Tick an axis whose data are in years (or per year) at round values of another unit."""
    axis.set_major_locator(_UnitTicks(years_per_unit))
    axis.set_major_formatter(FuncFormatter(lambda x, _: f'{x / years_per_unit:.6g}'))


def time_axis(axes, unit: DisplayUnits) -> None:
    """
    Label the time axis of ``axes`` (the last one gets the label) in ``unit``.

    The data stay in years; below a year the ticks fall on round hours (days, ...) and read
    in them.
    """
    for ax in axes:
        if unit.time != 'yr':
            _scaled_axis(ax.xaxis, unit.years_per_time)
    axes[-1].set_xlabel(f't [{unit.time}]')


def _rate_axis(axis, unit: DisplayUnits, label: str) -> None:
    """Label an axis whose data are rates [rad/yr] in ``unit.rate`` (round ticks in it)."""
    if unit.time != 'yr':
        _scaled_axis(axis, 1.0 / unit.years_per_time)
    axis.set_label_text(f'{label} [{unit.rate}]')


def _t(value: float, unit: DisplayUnits, digits: int = 4) -> str:
    """Write a time [yr] in ``unit``, with its name."""
    return unit.time_text(value, digits)


def _png(fig: Figure, name: str) -> Drawing:
    buffer = io.BytesIO()
    _lay_out(fig)
    fig.savefig(buffer, format='png')
    return name, buffer.getvalue()


def _lay_out(fig: Figure) -> None:
    """
    Place the axes of ``fig`` by its layout engine now, then turn the engine off.

    ``savefig`` on a figure with a layout engine (our constrained layout) draws it twice: once
    with the renderer's drawing methods disabled, to run the layout (the aspect of each axes
    applied, the engine executed), then again for the pixels. The first draw also walks every
    artist for nothing (ticks, texts, lines, the density image resampled): 0.1 s of the
    windows figure. Here the aspect is applied and the engine executed as that first draw
    does, in the same order and with the same renderer (the canvas's), and savefig then draws
    once: the same PNG bytes, every figure of several runs (tests/test_figure_layout.py).
    Left to savefig as before when the rc parameters make savefig crop the figure
    (``savefig.bbox: tight``: it draws first anyway) or force a layout engine.
    """
    engine = fig.get_layout_engine()
    if engine is None or not _single_draw_ok():
        return
    renderer = cast(FigureCanvasAgg, fig.canvas).get_renderer()
    for ax in fig.axes:             # as Figure.draw does before its layout engine runs
        locator = ax.get_axes_locator()
        ax.apply_aspect(locator(ax, renderer) if locator is not None else None)
    engine.execute(fig)
    fig.set_layout_engine(None)     # laid out: savefig's single draw applies the aspect again


def _single_draw_ok() -> bool:
    """Tell whether savefig draws once on a figure without layout engine (the rc defaults)."""
    rc = matplotlib.rcParams
    return (rc['savefig.bbox'] is None and not rc['figure.autolayout']
            and not rc['figure.constrained_layout.use'])


def _label(rec: Recording) -> str:
    """Name the file, and the namespace analysed unless it is the root."""
    if rec.namespace == ROOT_NAMESPACE:
        return rec.path.name
    return f'{rec.path.name} {rec.namespace}'


def _title(rec: Recording) -> str:
    """Name the file; below it the scenario's parameters, in display units, 4 digits."""
    text = _label(rec)
    sc = rec.scenario
    if sc is not None:
        u = _unit(rec)
        ix, _, iz = sc.inertia
        w0 = ', '.join(f'{u.w(w):.4g}' for w in sc.omega0)
        text += (f'\nI = ({", ".join(f"{i:.4g}" for i in sc.inertia)}), a = {(iz - ix) / ix:.3g}, '
                 f'$\\theta_0$ = {sc.euler0[2]:.3g} rad, $\\omega_0$ = ({w0}) {u.rate}')
        if not sc.all_perturbers:
            text += f', $\\omega_s$ = {u.w(sc.orbit_rate):.3g} {u.rate}'
    return text


def _mark_closest_approach(ax, rec: Recording, label: bool) -> None:
    """Mark a flyby's closest approach (perigee for the Earth) with its time."""
    if not is_flyby(rec.scenario):
        return
    nearest = closest_approach(rec)
    if nearest is None:
        return
    t, km = nearest
    ax.axvline(t, color='tab:purple', lw=1.0, ls=':',
               label=f'closest approach, {km:,.0f} km at t = {_t(t, _unit(rec))}'
               if label else None)


def _mark_gaps(ax, t: np.ndarray, label: bool) -> None:
    """Shade where a comparison series has no samples (the model did not apply there)."""
    pieces = runs(t)
    for k, ((_, stop), (start, _)) in enumerate(zip(pieces[:-1], pieces[1:])):
        ax.axvspan(t[stop - 1], t[start], color='0.92', zorder=0,
                   label='no comparison (model not applicable)' if label and k == 0 else None)


def _mark_impacts(ax, rec: Recording) -> None:
    for k, (start, end) in enumerate(impact_intervals(rec)):
        ax.axvline(start, color='tab:red', lw=0.8, ls='--',
                   label='impact' if k == 0 else None)
        ax.axvspan(start, end, color='tab:red', alpha=0.25)


def plot_angular_velocity(rec: Recording, out_dir: str | os.PathLike[str], *,
                          overwrite: bool = False) -> list[Path]:
    """``omega.png``: the three components against t, the model's overlaid if recorded."""
    return write_files(_draw_angular_velocity(rec, model_departure(rec)), out_dir, overwrite)


def model_departure(rec: Recording) -> float | None:
    """Return when the recorded model left the numeric solution [yr], or None."""
    stats, _ = comparator_errors(rec)
    return stats.t_departure if stats is not None else None


def numeric_limits(y: np.ndarray) -> tuple[float, float]:
    """Return the axis range of a numeric series: its min and max with a :data:`MARGIN`."""
    finite = y[np.isfinite(y)]
    if not len(finite):
        return -1.0, 1.0
    lo, hi = float(finite.min()), float(finite.max())
    pad = MARGIN * (hi - lo) or MARGIN * max(abs(lo), abs(hi), 1e-12)
    return lo - pad, hi + pad


def _draw_model(ax, t: np.ndarray, y: np.ndarray, limits: tuple[float, float], label: str,
                off_label: bool) -> None:
    """Draw the model's samples within ``limits``; mark the others at the edge they left by."""
    lo, hi = limits
    inside = (y >= lo) & (y <= hi)
    ax.plot(t, np.where(inside, y, np.nan), lw=2.0, color='black', alpha=0.6, label=label)
    off = ~inside & np.isfinite(y)      # (NaN: a gap in the series, not off scale)
    if off.any():
        ax.plot(t[off], np.clip(y[off], lo, hi), ls='', marker='|', ms=4, color='tab:gray',
                alpha=0.5, label='model off scale' if off_label else None)
    ax.set_ylim(lo, hi)


def _draw_angular_velocity(rec: Recording, departure: float | None = None) -> list[Drawing]:
    return [_png(omega_figure(rec, departure), 'omega.png')]


def omega_figure(rec: Recording, departure: float | None = None) -> Figure:
    """
    Draw ``omega.png``'s figure: wx, wy, wz [display rate] against t, the model's if recorded.

    ``departure``: the time [yr] the model left the numeric solution, drawn when given.
    """
    fig, axes = _new(3, 2.4)
    has_model = len(rec.model_t) > 0
    for i, ax in enumerate(axes):
        ax.plot(*envelope(rec.t, rec.omega[:, i]), lw=0.6, color='tab:blue', label='numeric')
        limits = numeric_limits(rec.omega[:, i])
        if has_model:
            _mark_gaps(ax, rec.model_t, i == 0)
            _draw_model(ax, *gapped_envelope(rec.model_t, rec.model_omega[:, i]), limits,
                        'analytic model' + (f' ({", ".join(rec.error_models)})'
                                            if rec.error_models else ''), i == 0)
        ax.set_ylim(*limits)
        if departure is not None:
            ax.axvline(departure, color='tab:orange', lw=1.0, ls='-.',
                       label=f'model left the solution (t = {_t(departure, _unit(rec))})'
                       if i == 0 else None)
        _mark_impacts(ax, rec)
        _mark_closest_approach(ax, rec, i == 0)
        _rate_axis(ax.yaxis, _unit(rec), _LABELS[i])
        ax.grid(True, lw=0.3)
    time_axis(axes, _unit(rec))
    if has_model or rec.impacts or is_flyby(rec.scenario):
        axes[0].legend(loc='upper right', fontsize='small')
    axes[0].set_title(_title(rec), fontsize='small')
    return fig


def plot_omega_windows(rec: Recording, out_dir: str | os.PathLike[str], *,
                       overwrite: bool = False) -> list[Path]:
    """``omega_windows.png``: w at full resolution at the start, each impact and the end."""
    return write_files(_draw_omega_windows(rec), out_dir, overwrite)


def _windows(rec: Recording) -> list[tuple[str, float, float]]:
    """Return the zoomed windows of a long run: (title, t0, t1) [yr]."""
    dt = float(np.median(np.diff(rec.t)))
    span = WINDOW_SAMPLES * dt
    windows = [('start', rec.t[0], rec.t[min(rec.n - 1, WINDOW_SAMPLES)])]
    for event in rec.impacts[:MAX_IMPACT_WINDOWS]:
        windows.append((f'impact {event.id}', event.start - span / 2, event.end + span / 2))
    windows.append(('end', rec.t[max(0, rec.n - 1 - WINDOW_SAMPLES)], rec.t[-1]))
    return windows


def _draw_omega_windows(rec: Recording) -> list[Drawing]:
    if rec.n < WINDOWS_FROM:
        return []
    windows = _windows(rec)
    fig = Figure(figsize=(3.2 * len(windows) + 1.0, 7.2), dpi=DPI, layout='constrained')
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, len(windows), squeeze=False)
    for col, (name, t0, t1) in enumerate(windows):
        sel = (rec.t >= t0) & (rec.t <= t1)
        msel = (rec.model_t >= t0) & (rec.model_t <= t1)
        for i in range(3):
            ax = axes[i, col]
            ax.plot(rec.t[sel], rec.omega[sel, i], lw=0.7, color='tab:blue', label='numeric')
            limits = numeric_limits(rec.omega[sel, i])
            if msel.any():
                _draw_model(ax, *gapped_envelope(rec.model_t[msel], rec.model_omega[msel, i]),
                            limits, 'analytic model', i == 0)
            ax.set_ylim(*limits)
            for start, end in impact_intervals(rec):
                if end >= t0 and start <= t1:
                    ax.axvspan(start, end, color='tab:red', alpha=0.3)
                    ax.axvline(start, color='tab:red', lw=0.8, ls='--')
            ax.set_xlim(t0, t1)
            ax.grid(True, lw=0.3)
            ax.tick_params(labelsize='x-small')
            _rate_axis(ax.yaxis, _unit(rec), _LABELS[i] if col == 0 else '')
            if col:
                ax.set_ylabel('')
        unit = _unit(rec)
        axes[0, col].set_title(f'{name}: t = {unit.t(t0):.6g} .. {_t(t1, unit, 6)}',
                               fontsize='small')
        time_axis(axes[:, col], unit)
    axes[0, 0].legend(loc='upper right', fontsize='x-small')
    fig.suptitle(f'{_label(rec)}: $\\omega$ at full resolution ({WINDOW_SAMPLES} samples a '
                 'window; omega.png: the whole run)', fontsize='small')
    return [_png(fig, 'omega_windows.png')]


def plot_wy_vs_wx(rec: Recording, out_dir: str | os.PathLike[str], *,
                  overwrite: bool = False) -> list[Path]:
    """``wy_vs_wx.png``: the transverse angular velocity's path (paper Fig 9, bottom)."""
    return write_files(_draw_wy_vs_wx(rec), out_dir, overwrite)


def _draw_wy_vs_wx(rec: Recording) -> list[Drawing]:
    return [_png(wy_vs_wx_figure(rec), 'wy_vs_wx.png')]


def wy_vs_wx_figure(rec: Recording) -> Figure:
    """Draw ``wy_vs_wx.png``'s figure: wy against wx [display rate], start and end marked."""
    fig, (ax,) = _new(1, 6.0, 6.5)
    x, y = rec.omega[:, 0], rec.omega[:, 1]
    if len(x) > PATH_POINTS_MAX:
        _draw_path_density(ax, x, y)
    else:
        ax.plot(x, y, lw=0.4, color='tab:blue')
    ax.plot(rec.omega[:1, 0], rec.omega[:1, 1], 'o', color='tab:green', label='start')
    ax.plot(rec.omega[-1:, 0], rec.omega[-1:, 1], 's', color='tab:red', label='end')
    ax.set_aspect('equal', adjustable='datalim')
    _rate_axis(ax.xaxis, _unit(rec), _LABELS[0])
    _rate_axis(ax.yaxis, _unit(rec), _LABELS[1])
    ax.grid(True, lw=0.3)
    ax.legend(loc='upper right', fontsize='small')
    unit = _unit(rec)
    ax.set_title(f'{_label(rec)}: $\\omega_y$ vs $\\omega_x$, t = {unit.t(rec.t[0]):.4g} .. '
                 f'{_t(rec.t[-1], unit)}', fontsize='small')
    return fig


def envelope(t: np.ndarray, y: np.ndarray, bins: int = ENVELOPE_BINS
             ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the points of a long time series a line plot needs: each bin's first, min and max.

    A plot ~1000 pixels wide cannot show more than a min and a max per pixel column; drawing
    200,001 points cost Agg ~0.7 s a figure for the same picture. The series is cut into
    ``bins`` bins of consecutive samples, and each bin's first, lowest and highest samples are
    kept, in time order, with the last sample: every extreme survives (a spike of one sample
    too). Shorter series (and NaN gaps, for which the bins are not safe) are returned whole.
    """
    n = len(t)
    if n <= 4 * bins or not np.isfinite(y).all():
        return t, y
    size = -(-n // bins)
    full = (n // size) * size
    blocks = y[:full].reshape(-1, size)
    starts = np.arange(0, full, size)
    keep = np.concatenate([starts, starts + blocks.argmin(axis=1), starts + blocks.argmax(axis=1),
                           np.arange(full, n), [n - 1]])
    keep = np.unique(keep)
    return t[keep], y[keep]


def gapped_envelope(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return :func:`envelope` of each run of samples without a gap, joined by NaN.

    A line plot then breaks where the series has no samples (:func:`.timeaxis.runs`) instead
    of drawing a straight line across: the analytic model and its error are not published
    where the model does not apply (an encounter window).
    """
    pieces = runs(t)
    if len(pieces) == 1:
        return envelope(t, y)
    ts: list[np.ndarray] = []
    ys: list[np.ndarray | list[float]] = []
    for a, b in pieces:
        et, ey = envelope(t[a:b], y[a:b])
        ts += [et, et[-1:]]
        ys += [ey, [np.nan]]
    return np.concatenate(ts[:-1]), np.concatenate(ys[:-1])


def _draw_path_density(ax, x: np.ndarray, y: np.ndarray) -> None:
    """
    Draw where a long path goes as an image: samples per pixel, log scale, equal axes.

    A line through 200,000 samples of a tumbling body winds thousands of times over the same
    ring: Agg took ~15-20 s to stroke it (the whole rest of ``analyze`` takes ~2 s) and drew a
    solid blob. The occupancy image shows the same ring, and where the path dwells.
    """
    cx, cy = (x.min() + x.max()) / 2, (y.min() + y.max()) / 2
    half = max(x.max() - x.min(), y.max() - y.min(), 1e-300) / 2 * 1.02
    extent = (cx - half, cx + half, cy - half, cy + half)
    counts, _, _ = np.histogram2d(x, y, bins=PATH_DENSITY_BINS,
                                  range=[extent[:2], extent[2:]])
    shown = np.ma.masked_equal(counts.T, 0)
    image = ax.imshow(np.ma.log10(shown), origin='lower', extent=extent, cmap='Blues',
                      interpolation='nearest', aspect='equal', vmin=-0.5)
    ax.figure.colorbar(image, ax=ax, shrink=0.7,
                       label=f'log10 samples per pixel ({len(x):,} samples)')


def plot_error(rec: Recording, out_dir: str | os.PathLike[str], *,
               overwrite: bool = False) -> list[Path]:
    """``error.png``: error components and |error| against t; nothing without a comparator."""
    return write_files(_draw_error(rec), out_dir, overwrite)


def _draw_error(rec: Recording) -> list[Drawing]:
    fig = error_figure(rec)
    return [] if fig is None else [_png(fig, 'error.png')]


def error_figure(rec: Recording) -> Figure | None:
    """Draw ``error.png``'s figure: w - w_model and its norm against t; None without a model."""
    t_vec, vec = rec.error_t, rec.error
    if not len(t_vec) and len(rec.model_t):
        _, ia, ib = np.intersect1d(rec.model_t, rec.t, return_indices=True)
        t_vec, vec = rec.t[ib], rec.omega[ib] - rec.model_omega[ia]
    if len(rec.norm_t):
        t_norm, norm = rec.norm_t, rec.error_norm
    elif len(t_vec):
        t_norm, norm = t_vec, np.linalg.norm(vec, axis=1)
    else:
        return None
    fig, (ax1, ax2) = _new(2, 2.8)
    if len(t_vec):
        for i in range(3):
            ax1.plot(*gapped_envelope(t_vec, vec[:, i]), lw=0.7,
                     label=_LABELS[i].replace('omega', 'Delta\\omega'))
    _rate_axis(ax1.yaxis, _unit(rec), '$\\omega - \\omega_{model}$')
    ax2.plot(*gapped_envelope(t_norm, norm), lw=0.8, color='black')
    _rate_axis(ax2.yaxis, _unit(rec), '|error|')
    time_axis((ax1, ax2), _unit(rec))
    for ax in (ax1, ax2):
        _mark_gaps(ax, t_norm, ax is ax1)
        _mark_impacts(ax, rec)
        _mark_closest_approach(ax, rec, ax is ax1)
        ax.grid(True, lw=0.3)
    if ax1.get_legend_handles_labels()[0]:
        ax1.legend(loc='upper left', fontsize='small')
    models = ', '.join(rec.error_models) or (rec.comparator_status.values.get('model', '')
                                             if rec.comparator_status else '')
    ax1.set_title(f'{_label(rec)}: numeric - analytic model {models}', fontsize='small')
    return fig


def plot_impacts(rec: Recording, out_dir: str | os.PathLike[str], *, samples: int = 25,
                 overwrite: bool = False) -> list[Path]:
    """
    Plot ``impact_<k>_id<id>.png`` per impact event (paper Fig 10).

    The first :data:`MAX_IMPACT_FIGURES` impacts in time get one each.

    Each shows w over +-``samples`` sampling intervals (at least +-10 pulse lengths) around the
    pulse, the pulse interval shaded and its edges drawn.
    """
    return write_files(_draw_impacts(rec, samples), out_dir, overwrite)


def _draw_impacts(rec: Recording, samples: int = 25) -> list[Drawing]:
    drawings: list[Drawing] = []
    if rec.n < 2:
        return drawings
    dt = float(np.median(np.diff(rec.t)))
    for k, event in enumerate(rec.impacts[:MAX_IMPACT_FIGURES]):
        half = max(samples * dt, 10 * event.duration)
        lo, hi = event.start - half, event.end + half
        sel = (rec.t >= lo) & (rec.t <= hi)
        fig, axes = _new(3, 2.2)
        for i, ax in enumerate(axes):
            ax.plot(rec.t[sel], rec.omega[sel, i], '.-', lw=0.8, ms=3, color='tab:blue',
                    label='numeric samples')
            if len(rec.model_t):
                msel = (rec.model_t >= lo) & (rec.model_t <= hi)
                ax.plot(rec.model_t[msel], rec.model_omega[msel, i], lw=2.0, color='black',
                        alpha=0.5, label='analytic model')
            ax.axvspan(event.start, event.end, color='tab:red', alpha=0.3,
                       label=f'pulse [{_unit(rec).t(event.start):.9g}, '
                             f'{_t(event.end, _unit(rec), 9)}]')
            ax.axvline(event.start, color='tab:red', lw=0.8, ls='--')
            ax.axvline(event.end, color='tab:red', lw=0.8, ls=':')
            _rate_axis(ax.yaxis, _unit(rec), _LABELS[i])
            ax.grid(True, lw=0.3)
            ax.set_xlim(lo, hi)
        axes[0].legend(loc='upper left', fontsize='x-small')
        time_axis(axes, _unit(rec))
        u = _unit(rec)
        d = u.w(np.asarray(event.delta_omega))
        axes[0].set_title(
            f'{_label(rec)}: impact {event.id}, {event.frame} torque '
            f'({", ".join(f"{c:.3g}" for c in u.torque(np.asarray(event.torque)))}) '
            f'{u.torque_unit} for '
            f'{_t(event.duration, u, 3)}; $\\Delta\\omega$ = ({d[0]:.4g}, {d[1]:.4g}, '
            f'{d[2]:.4g}) {u.rate}', fontsize='small')
        drawings.append(_png(fig, f'impact_{k}_id{event.id}.png'))
    return drawings


def plot_spectrum(rec: Recording, out_dir: str | os.PathLike[str],
                  summary: AnalysisSummary | None = None, *,
                  overwrite: bool = False) -> list[Path]:
    """
    Plot ``spectrum_wx.png``: the amplitude spectrum of wx (as in the summary).

    The theory's lines are dashed, the Nyquist rate pi/dt marked; nothing is drawn for fewer
    than 8 samples.
    """
    return write_files(_draw_spectrum(rec, summary), out_dir, overwrite)


def _draw_spectrum(rec: Recording, summary: AnalysisSummary | SummaryParts | None
                   ) -> list[Drawing]:
    drawn = spectrum_figure(rec, summary)
    return [] if drawn is None else [_png(drawn[0], f'spectrum_{drawn[1]}.png')]


def spectrum_figure(rec: Recording, summary: AnalysisSummary | SummaryParts | None = None
                    ) -> tuple[Figure, str] | None:
    """
    Draw ``spectrum_wx.png``'s figure and name its component; None when there is no spectrum.

    The amplitude spectrum [display rate] of wx with the theory's lines and the peaks, as in
    the summary (``summary``, or computed); none for a flyby or fewer than 8 samples.
    """
    if summary is not None:
        spec, lines = summary.spectrum, list(summary.theory)
    else:
        lines, _ = theory_lines(rec.scenario, rec.omega)
        spec = spectrum(rec.t, rec.omega[:, 0], lines)
    if spec is None or is_flyby(rec.scenario):
        return None         # a flyby is one passage: no line to resolve in 144 h
    u = _unit(rec)
    fig, (ax,) = _new(1, 3.5)
    positive = spec.amplitude > 0       # (drawn in display units: rad/yr, rad/d, ...)
    ax.semilogy(u.w(spec.omega_axis[positive]), u.w(spec.amplitude[positive]), lw=0.8,
                color='tab:blue', label=f'|FFT| of {spec.component} ({spec.window} window)')
    for k, line in enumerate(lines):
        if line.omega <= spec.nyquist:
            color, style = _line_style(k)
            ax.axvline(u.w(line.omega), color=color, lw=0.8, ls=style,
                       label=f'{line.name} = {u.w(line.omega):.4g} {u.rate}')
    for peak in spec.peaks:
        ax.plot(u.w(peak.omega), u.w(peak.amplitude), 'v', color='black', ms=5)
    # Zoom on the interesting part: the lines and peaks, unless they fill the band anyway.
    interesting = [line.omega for line in lines if line.omega <= spec.nyquist]
    interesting += [peak.omega for peak in spec.peaks]
    right = spec.nyquist
    if interesting and 1.3 * max(interesting) < spec.nyquist:
        right = max(1.3 * max(interesting), 20 * spec.resolution, 1.0)
    ax.set_xlim(0, u.w(min(right, spec.nyquist)))
    ax.set_xlabel(f'$\\omega$ [{u.rate}]  (Nyquist $\\pi/dt$ = {u.rate_text(spec.nyquist, 4)})')
    ax.set_ylabel(f'amplitude [{u.rate}]')
    ax.grid(True, lw=0.3)
    ax.legend(loc='upper right', fontsize='x-small')
    ax.set_title(f'{_label(rec)}: spectrum of {spec.component}, resolution '
                 f'{u.rate_text(spec.resolution, 3)}', fontsize='small')
    return fig, spec.component


#: The theory lines' colours: the spectrum's blue left out, and brown and grey, which read as
#: red and black in a thin dashed line (the default run's |wA+wE| and |w0-2ws| looked alike).
_LINE_COLORS = ('tab:orange', 'tab:green', 'tab:red', 'tab:purple', 'tab:cyan', 'tab:olive',
                'tab:pink', 'black')
#: Their dashes, cycled at the same time: 8 colours x 3 styles give 24 different lines.
_LINE_STYLES = ('--', ':', '-.')


def _line_style(k: int) -> tuple[str, str]:
    """Return the (colour, line style) of the k-th theory line: no two of 24 lines alike."""
    return _LINE_COLORS[k % len(_LINE_COLORS)], _LINE_STYLES[k % len(_LINE_STYLES)]


def _departure_of(summary: AnalysisSummary | SummaryParts) -> float | None:
    return summary.comparator.t_departure if summary.comparator is not None else None


#: The figures :func:`write_figures` draws, in the order they are written: name -> drawer of
#: (recording, its summary) -> the drawings (none when the recording lacks what it needs). The
#: summary may be its :class:`~.summary.SummaryParts`: the same values (the main job's figures
#: start before the analysis, :mod:`.figure_pool`).
FIGURES: dict[str, Callable[[Recording, AnalysisSummary | SummaryParts], list[Drawing]]] = {
    'omega': lambda rec, summary: _draw_angular_velocity(rec, _departure_of(summary)),
    'omega_windows': lambda rec, summary: _draw_omega_windows(rec),
    'wy_vs_wx': lambda rec, summary: _draw_wy_vs_wx(rec),
    'error': lambda rec, summary: _draw_error(rec),
    'impacts': lambda rec, summary: _draw_impacts(rec),
    'spectrum': _draw_spectrum,
}


def draw_figures(rec: Recording, summary: AnalysisSummary | SummaryParts,
                 names: Iterable[str] = tuple(FIGURES)) -> dict[str, list[Drawing]]:
    """Draw the figures ``names`` (keys of :data:`FIGURES`); return name -> its drawings."""
    return {name: FIGURES[name](rec, summary) for name in names}


def figure_order() -> tuple[str, ...]:
    """Return the names of :data:`FIGURES` in the order their files are written."""
    return tuple(FIGURES)


def warm_up() -> None:
    """
    Draw and encode a small figure with text and mathematics, to throw away.

    The first figure of a process loads the fonts and the mathtext parser (~0.15 s); a
    :class:`~.figure_pool.FigurePool` worker does it while it waits. Only matplotlib's caches
    change (the same figures after it, byte for byte: tests/test_figure_pool.py).
    """
    fig, (ax,) = _new(1, 1.0, 2.0)
    ax.plot([0.0, 1.0], [0.0, 1.0], lw=0.6)
    ax.set_ylabel(f'{_LABELS[0]} [rad/yr]')
    ax.set_xlabel('t [yr]')
    ax.set_title('$\\theta_0$ = 0.9 rad, $\\omega_0$', fontsize='small')
    _png(fig, 'warm-up.png')


def write_figures(rec: Recording, out_dir: str | os.PathLike[str],
                  summary: AnalysisSummary | None = None, *,
                  overwrite: bool = False) -> list[Path]:
    """
    Write every figure the recording supports; return the paths written.

    All are drawn before any is written: an existing file (without ``overwrite``) or a link
    refuses them all. (:meth:`.figure_pool.FigurePool.write_figures`: the same, drawn in
    worker processes.)
    """
    if summary is None:
        summary = analyze(rec)
    drawn = draw_figures(rec, summary)
    return write_files([drawing for name in FIGURES for drawing in drawn[name]], out_dir,
                       overwrite)

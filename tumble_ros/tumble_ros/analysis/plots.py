"""
Figures for a notebook: a simulation's result or a recording in, a matplotlib Figure out.

    from tumble_ros.core import load_scenario, simulate
    from tumble_ros.analysis.plots import omega_figure
    sc = load_scenario("tumble_ros/config/fig4.yaml")
    fig = omega_figure(simulate(sc), sc, model="paper")     # shown by Jupyter; fig.savefig(...)

Each function takes a source: a :class:`~tumble_ros.core.SimulationResult` (with its scenario,
for the units, the title and the theory's lines), a :class:`~.recording.Recording`, or the path
of an MCAP recording; and draws what :mod:`.figures` writes as PNG files, with the same code
(:func:`.figures.omega_figure`, ...): the same picture as ``analyze --figures``. The figures are
:class:`matplotlib.figure.Figure` objects on the Agg canvas (no pyplot state is touched); Jupyter
displays one returned by a cell, ``fig.savefig(path)`` writes it. Times [yr] and rates [rad/yr]
are shown in the display units of :mod:`.display` (hours for a flyby).
"""
from __future__ import annotations

import os
from pathlib import Path

from matplotlib.figure import Figure
import numpy as np

from tumble_ros.core import make_model, Scenario, SimulationResult
from tumble_ros.errors import AnalysisError

from . import figures
from .recording import load_recording, Recording

__all__ = ['as_recording', 'error_figure', 'omega_figure', 'spectrum_figure', 'wy_vs_wx_figure']

#: What a figure can be drawn from.
Source = SimulationResult | Recording | str | os.PathLike

#: The name a result's figures carry in their titles (a recording's: its file name).
RESULT_NAME = 'simulate'


def as_recording(source: Source, scenario: Scenario | None = None, *,
                 model: str | None = None) -> Recording:
    """
    Return ``source`` as a :class:`~.recording.Recording`, the arrays the figures draw.

    A result becomes one whose ``/angular_velocity``, attitude and Euler angles are its samples
    and, with ``model`` (a name of ``tumble_ros.core.analytic.MODELS``, needs ``scenario``),
    whose comparison is that analytic model at the same times, anchored at t = 0. A path is read
    (:func:`~.recording.load_recording`); a recording is returned as it is.
    AnalysisError for a model without a scenario, or a scenario or model given with a recording.
    """
    if isinstance(source, SimulationResult):
        return _from_result(source, scenario, model)
    if scenario is not None or model is not None:
        raise AnalysisError('scenario, model: only for a SimulationResult (a recording carries '
                            f'its own); got a {type(source).__name__}')
    if isinstance(source, Recording):
        return source
    if isinstance(source, (str, os.PathLike)):
        return load_recording(source)
    raise AnalysisError(f'source: a SimulationResult, a Recording or the path of an MCAP '
                        f'recording; got a {type(source).__name__}')


def _from_result(result: SimulationResult, scenario: Scenario | None,
                 model: str | None) -> Recording:
    t = np.asarray(result.t, dtype=float)
    rec = Recording(path=Path(RESULT_NAME), finalised=True, problem=None, topics={},
                    seconds_per_year=1.0, seconds_per_year_source='default', t=t,
                    omega=np.asarray(result.omega, dtype=float),
                    stamp_ns=np.round(t * 1e9).astype(np.int64), scenario=scenario)
    if len(result.quaternion):
        rec.quaternion_t, rec.quaternion = t, np.asarray(result.quaternion, dtype=float)
    if len(result.euler):
        rec.euler_t, rec.euler = t, np.asarray(result.euler, dtype=float)
    if model is not None:
        if scenario is None:
            raise AnalysisError(f"model: {model!r} needs the result's scenario (scenario=...)")
        rec.model_t, rec.model_omega = t, make_model(model, scenario).omega(t)
        rec.error_models = (model,)
    return rec


def omega_figure(source: Source, scenario: Scenario | None = None, *,
                 model: str | None = None) -> Figure:
    """Draw wx, wy, wz against t (paper Figs 3-9), ``model``'s w overlaid: ``omega.png``."""
    rec = as_recording(source, scenario, model=model)
    return figures.omega_figure(rec, figures.model_departure(rec))


def wy_vs_wx_figure(source: Source, scenario: Scenario | None = None) -> Figure:
    """Draw wy against wx, start and end marked (paper Fig 9, bottom): ``wy_vs_wx.png``."""
    return figures.wy_vs_wx_figure(as_recording(source, scenario))


def error_figure(source: Source, scenario: Scenario | None = None, *,
                 model: str | None = None) -> Figure:
    """
    Draw w - w_model and its norm against t: ``error.png``.

    AnalysisError when there is no model: a recording without the comparator's topics, or a
    result without ``model``.
    """
    fig = figures.error_figure(as_recording(source, scenario, model=model))
    if fig is None:
        raise AnalysisError('model: no analytic model to compare with (a result needs '
                            "model=..., a recording the comparator's topics)")
    return fig


def spectrum_figure(source: Source, scenario: Scenario | None = None) -> Figure:
    """
    Draw the amplitude spectrum of wx with the theory's lines: ``spectrum_wx.png``.

    AnalysisError when there is none: fewer than 8 samples, or a flyby (one passage).
    """
    drawn = figures.spectrum_figure(as_recording(source, scenario))
    if drawn is None:
        raise AnalysisError('source: no spectrum to draw (fewer than 8 samples, or a flyby: '
                            'one passage has no line to resolve)')
    return drawn[0]

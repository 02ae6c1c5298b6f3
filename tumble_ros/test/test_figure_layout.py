"""
The figures laid out before savefig (figures._lay_out) against savefig's own layout pass.

With a layout engine, matplotlib's savefig draws a figure twice (the first time with drawing
disabled, to run the layout); :func:`tumble_ros.analysis.figures._lay_out` runs the layout as
that first draw does and leaves savefig one draw. Proven here: every figure of three runs
(Fig 9 over 200 yr: the zoomed windows, the density path, a departing model; Fig 10: impacts;
the Apophis flyby: the closest approach, display units in hours) is the
same PNG byte for byte either way; savefig draws once after it and twice without it; with the
rc parameters that make savefig draw first anyway (``savefig.bbox: tight``) or force a layout,
nothing is changed.
"""
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure
import pytest

from tumble_ros.analysis import analyze, load_recording
from tumble_ros.analysis import figures
from tumble_ros.core import load_scenario
from tumble_ros.runs.offline import record_offline

CONFIG = Path(__file__).resolve().parents[1] / 'config'


@pytest.fixture(scope='module')
def recordings(tmp_path_factory):
    """Fig 9 over 200 yr (20,001 samples), Fig 10 (impacts), the Apophis flyby over 144 h."""
    tmp = tmp_path_factory.mktemp('layout')
    fig9 = load_scenario(CONFIG / 'fig9.yaml').replace(duration=200.0)
    paths = [record_offline(fig9, tmp / 'fig9.mcap').output,
             record_offline(load_scenario(CONFIG / 'fig10.yaml'), tmp / 'fig10.mcap').output,
             record_offline(load_scenario(CONFIG / 'apophis_2029.yaml'),
                            tmp / 'apophis.mcap').output]
    return [load_recording(path) for path in paths]


def _drawn(rec):
    summary = analyze(rec)
    return [drawing for name in figures.FIGURES
            for drawing in figures.draw_figures(rec, summary, [name])[name]]


def test_the_same_png_bytes_as_savefigs_own_layout(recordings, monkeypatch):
    once = [_drawn(rec) for rec in recordings]
    monkeypatch.setattr(figures, '_lay_out', lambda fig: None)    # savefig lays out itself
    twice = [_drawn(rec) for rec in recordings]
    names = [[name for name, _ in drawn] for drawn in once]
    assert names == [[name for name, _ in drawn] for drawn in twice]
    assert 'omega_windows.png' in names[0] and 'impact_0_id0.png' in names[1]
    assert names[2] == ['omega.png', 'wy_vs_wx.png']            # a flyby: no spectrum
    for a, b in zip(once, twice):
        for (name, data), (_, expected) in zip(a, b):
            assert data == expected, name


def _draws(monkeypatch):
    """Count Figure.draw calls (savefig's layout pass and its drawing)."""
    calls = []
    real = Figure.draw

    def draw(fig, renderer):
        calls.append(fig)
        return real(fig, renderer)
    monkeypatch.setattr(Figure, 'draw', draw)
    return calls


def _small_figure():
    fig, (ax,) = figures._new(1, 2.0, 3.0)
    ax.plot([0.0, 1.0], [0.0, 2.0])
    ax.set_title('$\\omega_x$', fontsize='small')
    ax.set_aspect('equal', adjustable='datalim')
    return fig


def test_savefig_draws_once_after_it(monkeypatch):
    calls = _draws(monkeypatch)
    figures._png(_small_figure(), 'a.png')
    assert len(calls) == 1
    calls.clear()
    monkeypatch.setattr(figures, '_lay_out', lambda fig: None)
    figures._png(_small_figure(), 'a.png')
    assert len(calls) == 2


@pytest.mark.parametrize('key, value', [('savefig.bbox', 'tight'), ('figure.autolayout', True),
                                        ('figure.constrained_layout.use', True)])
def test_left_to_savefig_when_the_rc_parameters_ask_for_more(monkeypatch, key, value):
    monkeypatch.setitem(matplotlib.rcParams, key, value)
    fig = _small_figure()
    engine = fig.get_layout_engine()
    figures._lay_out(fig)
    assert fig.get_layout_engine() is engine    # untouched: savefig lays it out as before

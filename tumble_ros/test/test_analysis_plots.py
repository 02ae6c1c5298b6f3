"""The notebook's figures (analysis.plots): a result or a recording in, a Figure out."""
import io
from pathlib import Path

from matplotlib.figure import Figure
import numpy as np
import pytest

from tumble_ros.analysis import load_recording, write_figures
from tumble_ros.analysis.plots import (as_recording, error_figure, omega_figure,
                                       spectrum_figure, wy_vs_wx_figure)
from tumble_ros.core import load_scenario, make_model, simulate
from tumble_ros.errors import AnalysisError

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = ROOT / 'tumble_ros' / 'test' / 'data' / 'golden.mcap'
FIG4 = ROOT / 'tumble_ros' / 'config' / 'fig4.yaml'


@pytest.fixture(scope='module')
def run():
    scenario = load_scenario(FIG4).replace(duration=0.2)
    return scenario, simulate(scenario)


def line(ax, label):
    return next(artist for artist in ax.lines if artist.get_label() == label)


def test_a_results_omega_figure_draws_its_samples_and_the_model(run):
    scenario, result = run
    fig = omega_figure(result, scenario, model='paper')
    assert isinstance(fig, Figure)
    axes = fig.axes
    assert len(axes) == 3
    expected = make_model('paper', scenario).omega(result.t)
    for i, ax in enumerate(axes):
        numeric = line(ax, 'numeric')          # [rad/yr], the axis ticks in display units
        np.testing.assert_array_equal(numeric.get_ydata(), result.omega[:, i])
    model = line(axes[0], 'analytic model (paper)')
    np.testing.assert_array_equal(model.get_ydata(), expected[:, 0])
    assert 'simulate' in axes[0].get_title()


def test_a_recordings_figure_is_the_png_that_analyze_writes(tmp_path):
    """The same code draws both: the figure saved is omega.png's bytes from write_figures."""
    written = {p.name: p.read_bytes() for p in write_figures(load_recording(GOLDEN), tmp_path)}
    for figure, name in ((omega_figure(GOLDEN), 'omega.png'),
                         (wy_vs_wx_figure(str(GOLDEN)), 'wy_vs_wx.png'),
                         (spectrum_figure(load_recording(GOLDEN)), 'spectrum_wx.png')):
        buffer = io.BytesIO()
        figure.savefig(buffer, format='png')
        assert buffer.getvalue() == written[name], name


def test_the_error_and_spectrum_of_a_result(run):
    scenario, result = run
    fig = error_figure(result, scenario, model='paper')
    norm = fig.axes[1].lines[0].get_ydata()
    expected = np.linalg.norm(result.omega - make_model('paper', scenario).omega(result.t), axis=1)
    np.testing.assert_allclose(norm, expected, rtol=1e-12)
    spectrum = spectrum_figure(result, scenario)
    labels = [artist.get_label() for artist in spectrum.axes[0].lines]
    assert any(label.startswith('wE = ') for label in labels), labels    # the theory's lines


def test_what_cannot_be_drawn_is_refused_in_one_line(run):
    scenario, result = run
    with pytest.raises(AnalysisError, match='^model: no analytic model'):
        error_figure(result, scenario)
    with pytest.raises(AnalysisError, match="^model: 'paper' needs the result's scenario"):
        omega_figure(result, model='paper')
    with pytest.raises(AnalysisError, match='^scenario, model: only for a SimulationResult'):
        omega_figure(GOLDEN, scenario)
    with pytest.raises(AnalysisError, match='^source: a SimulationResult, a Recording .* got a '
                                            'list'):
        omega_figure([1.0, 2.0])
    with pytest.raises(AnalysisError, match='^model: no analytic model'):
        error_figure(GOLDEN)                      # golden.mcap has no comparator topics


def test_a_recording_is_drawn_as_it_is():
    rec = load_recording(GOLDEN)
    assert as_recording(rec) is rec

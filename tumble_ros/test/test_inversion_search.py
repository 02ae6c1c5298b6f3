"""
The inversion's global search, its outputs and the invert command (issue 49).

The search on a campaign the project's forward model made finds the truth (or a solution as
good) among its accepted solutions; the scenario YAML of a fit loads with load_scenario into
the fit's own spin state; the report is valid JSON; ``invert`` writes its files and refuses bad
input in one line.
"""
import json
import math

import numpy as np
import pytest

from test_inversion_fit import geometry, observed, TRUTH
from tumble_ros.cli import invert as invert_cli
from tumble_ros.core.model.scenario import load_scenario
from tumble_ros.inversion.fit import fit_local
from tumble_ros.inversion.model import ForwardModel, ModelError
from tumble_ros.inversion.report import format_result, result_json
from tumble_ros.inversion.scenario_out import scenario_yaml
from tumble_ros.inversion.search import (_readings, fibonacci_sphere, invert, period_candidates,
                                         SearchSettings)


@pytest.fixture(scope='module')
def noisy():
    points = geometry(nights=7, per_night=25)
    clean = ForwardModel(points).magnitudes(TRUTH)
    noise = np.random.default_rng(1).normal(0.0, 0.01, clean.size)     # data, drawn once
    return observed(points, clean + noise)


@pytest.fixture(scope='module')
def searched(noisy):
    settings = SearchSettings(periods=((27.38, 263.0),), modes=('SAM',), starts=4, max_nfev=60)
    return invert(noisy, settings)


def test_the_search_accepts_a_solution_as_good_as_the_truth(noisy, searched):
    f = ForwardModel(noisy).residuals(TRUTH)
    truth_chi2 = float(f @ f)
    best = searched.best
    assert best.chi2 <= truth_chi2 + 1e-6 * truth_chi2
    assert best.chi2 <= searched.threshold and searched.accepted[0] is best
    assert best.value('precession_period')[0] == pytest.approx(27.38, rel=2e-3)
    chi2 = [s.chi2 for s in searched.solutions]
    assert chi2 == sorted(chi2)
    assert all(s.chi2 > searched.threshold for s in searched.solutions
               if not any(s is a for a in searched.accepted))
    assert len(searched.candidates) == 1
    if len(searched.accepted) > 1:
        assert any('not unique' in w for w in searched.warnings)


def test_the_report_names_every_solution_and_is_json(searched):
    text = format_result(searched)
    assert 'accepted solution 1' in text and 'precession_period' in text
    document = json.loads(result_json(searched))
    assert len(document['solutions']) == len(searched.solutions)
    first = document['accepted'][0]['parameters']
    assert first['pole_beta']['unit'] == 'deg'
    assert first['precession_period']['value'] == pytest.approx(
        searched.best.value('precession_period')[0])


def test_the_scenario_yaml_loads_into_the_fits_spin_state(searched, tmp_path):
    fit = searched.best
    path = tmp_path / 'fit.yaml'
    path.write_text(scenario_yaml(fit, span_hours=400.0))
    scenario = load_scenario(path)
    expected = fit.parameters.spin.scenario_fields()
    assert np.allclose(scenario.inertia, expected['inertia'], rtol=1e-12)
    assert np.allclose(scenario.omega0, expected['omega0'], rtol=1e-9)
    assert np.allclose(scenario.euler0, expected['euler0'], atol=1e-9)
    assert scenario.time_unit == 'h' and scenario.orbit_rate == 0.0
    assert scenario.duration * 8766.0 == pytest.approx(max(400.0, 2 * 263.0), rel=0.02)


def test_period_readings_and_the_pole_grid():
    readings = dict(_readings(1 / 10.0, 1 / 40.0))
    assert readings['(P1, P2)'] == pytest.approx((10.0, 40.0))
    assert readings['(P2, P1)'] == pytest.approx((40.0, 10.0))
    assert readings['(1/(f1-f2), P2)'] == pytest.approx((1 / (0.1 - 0.025), 40.0))
    poles = np.array(fibonacci_sphere(50))
    z = np.sin(poles[:, 1])
    assert abs(z.mean()) < 1e-12 and np.all(np.abs(poles[:, 1]) <= math.pi / 2)


def test_a_pair_no_tumbler_has_is_not_a_candidate(noisy):
    # P_psi / P_phi = 1.01: below every SAM's and LAM's bound for the ratios tried
    candidates, _ = period_candidates(noisy, SearchSettings(periods=((10.0, 10.1),)))
    assert candidates == []
    with pytest.raises(ModelError, match='--periods'):
        invert(noisy, SearchSettings(periods=((10.0, 10.1),)))
    with pytest.raises(ModelError, match='poles'):
        SearchSettings(poles=0)
    with pytest.raises(ModelError, match='modes'):
        SearchSettings(modes=('XAM',))


def test_the_invert_command_writes_its_files(noisy, searched, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(invert_cli, 'load_campaign', lambda files, fmt, eph: noisy)
    out = tmp_path / 'out'
    code = invert_cli.main(['obs.txt', '--periods', '27.38,263', '--modes', 'SAM',
                            '--poles', '4', '--phases', '2', '--starts', '1', '--out',
                            str(out), '--json', '--quiet'])
    assert code in (0, 1)
    document = json.loads(capsys.readouterr().out)
    assert document['accepted']
    names = {p.name for p in out.iterdir()}
    assert {'report.txt', 'report.json', 'fit.yaml', 'nights.png', 'period_plane.png',
            'poles.png'} <= names
    load_scenario(out / 'fit.yaml')
    # a second run refuses to overwrite, before any work
    assert invert_cli.main(['obs.txt', '--out', str(out), '--quiet']) == 2
    assert 'error:' in capsys.readouterr().err
    assert invert_cli.main(['obs.txt', '--poles', '0', '--quiet']) == 2


def test_a_fit_from_a_grid_start_keeps_its_mode(noisy):
    start = TRUTH
    fit = fit_local(noisy, start, max_nfev=3)
    assert fit.parameters.spin.mode == 'SAM'
    assert fit.parameters.spin.anti_aligned == start.spin.anti_aligned


def test_the_period_search_gets_hours_and_block_means_removed(noisy, monkeypatch):
    from types import SimpleNamespace

    from tumble_ros.inversion import search
    seen = {}

    def fake(t, y, sigma, p_min, p_max, **kwargs):
        seen.update(t=t, y=y, unit=kwargs['unit'])
        mirror = SimpleNamespace(label='(f2, f1)', p1=263.0, p2=27.38)
        return SimpleNamespace(p1=27.38, p2=263.0, mirrors=(mirror,), alternatives=(),
                               warnings=('a warning',), aliases=('P1',))
    monkeypatch.setattr(search, 'search_periods', fake)
    candidates, solution = period_candidates(noisy, SearchSettings(modes=('SAM',)))
    assert seen['unit'] == 'h' and seen['t'][0] == 0.0
    assert seen['t'][-1] == pytest.approx(noisy.span_days * 24.0)
    for b in range(len(noisy.block_names)):
        assert np.average(seen['y'][noisy.block == b],
                          weights=noisy.sigma[noisy.block == b] ** -2) == pytest.approx(0.0,
                                                                                        abs=1e-12)
    pairs = [(c.precession_period, c.rotation_period) for c in candidates]
    assert pairs[0] == pytest.approx((27.38, 263.0))          # the search's own reading first
    assert len({(round(a, 6), round(b, 6)) for a, b in pairs}) == len(pairs)  # no repeats
    assert all(c.mode == 'SAM' for c in candidates)
    warnings = search._result_warnings((fit_local(noisy, TRUTH, max_nfev=1),), solution)
    assert 'period search: a warning' in warnings and any('alias' in w for w in warnings)


def test_the_invert_command_samples_the_posterior_and_runs_the_flyby(
        noisy, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(invert_cli, 'load_campaign', lambda files, fmt, eph: noisy)
    out = tmp_path / 'out'
    code = invert_cli.main(['obs.txt', '--periods', '27.38,263', '--modes', 'SAM',
                            '--poles', '2', '--phases', '1', '--starts', '1', '--out',
                            str(out), '--no-figures', '--quiet', '--posterior', '4',
                            '--flyby', 'apophis_2029', '--flyby-samples', '1'])
    assert code in (0, 1)
    printed = capsys.readouterr().out
    assert 'flyby: model' in printed and 'nominal' in printed and 'posterior 1' in printed
    with np.load(out / 'posterior.npz') as data:
        assert data['samples'].shape[1] == len(data['names']) == 10
    assert (out / 'flyby.txt').read_text().startswith('flyby: model')
    assert invert_cli.main(['obs.txt', '--flyby', 'no_such_scenario', '--quiet']) == 2
    assert 'no_such_scenario' in capsys.readouterr().err

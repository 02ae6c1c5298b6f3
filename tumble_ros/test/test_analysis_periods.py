"""
Periods from a lightcurve (analysis/periods.py): the two-period Fourier series of Pravec et al.

Synthetic doubly periodic signals with known frequencies, noise and the gaps of a night-time
campaign are recovered within their stated uncertainty; the grid's normal equations equal a
direct least-squares fit; a single period is reported as one; the mirror bases of the lattice
are listed. The closed loop: the Apophis tumbler simulated torque-free, seen by a synthetic
campaign (core/photometry), gives back its periods; the same after the simulated 2029 flyby
against the spin state from omega; a principal-axis rotator gives one period.
"""
import math
from pathlib import Path
import re

import numpy as np
import pytest

from tumble_ros.analysis.periods import (_degenerate, _grid_rss, campaign_times, combination,
                                         harmonics, search_periods)
from tumble_ros.core import load_scenario, simulate
from tumble_ros.core.model.rotation import quaternion_to_euler
from tumble_ros.core.model.spinstate import spin_state
from tumble_ros.core.photometry import LightcurveSettings, synthetic_lightcurve
from tumble_ros.core.units import HOURS_PER_YEAR

CONFIG = Path(__file__).resolve().parents[1] / 'config' / 'apophis_2029.yaml'
H = HOURS_PER_YEAR


def doubly_periodic(t, f1, f2, terms):
    """Sum a cos(2 pi (j f1 + k f2) t + phase) over terms (j, k, a, phase)."""
    return sum(a * np.cos(2.0 * np.pi * (j * f1 + k * f2) * t + p) for j, k, a, p in terms)


TERMS = [(2, 0, 0.25, 0.3), (1, 0, 0.08, 1.0), (0, 2, 0.10, 2.0), (1, -1, 0.06, 0.5),
         (2, 1, 0.04, 4.0), (1, 2, 0.03, 2.5)]


def test_the_grid_equals_a_direct_least_squares_fit_at_every_trial():
    rng = np.random.default_rng(1)
    t = campaign_times(rng, 10)
    y = doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    w = rng.uniform(0.5, 2.0, t.size)
    f1s, f2s = np.array([0.2, 0.21, 0.1833]), np.array([0.073, 0.05, 0.031, 0.2])
    grid = _grid_rss(t, y, w, f1s, f2s, 3)
    for i, f1 in enumerate(f1s):
        for j, f2 in enumerate(f2s[:3]):
            sw = np.sqrt(w)
            cols = [np.ones_like(t)]
            for jj, kk in harmonics(3):
                phase = 2 * np.pi * (jj * f1 + kk * f2) * t
                cols += [np.cos(phase), np.sin(phase)]
            design = np.column_stack(cols)
            coef = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)[0]
            rss = float(np.sum(w * (y - design @ coef) ** 2))
            assert grid[i, j] == pytest.approx(rss, rel=1e-6, abs=1e-9)


def direct_rss(t, y, w, f1, f2, order):
    """Return the weighted RSS of the series at (f1, f2) by np.linalg.lstsq (design matrix)."""
    sw = np.sqrt(w)
    cols = [np.ones_like(t)]
    for jj, kk in harmonics(order):
        phase = 2 * np.pi * (jj * f1 + kk * f2) * t
        cols += [np.cos(phase), np.sin(phase)]
    design = np.column_stack(cols)
    coef = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)[0]
    return float(np.sum(w * (y - design @ coef) ** 2))


@pytest.mark.parametrize('order', [1, 2, 3])
def test_the_fast_grid_equals_lstsq_at_every_order_and_skips_only_degenerate_pairs(order):
    # the Cholesky pivot of the augmented normal matrix, from one real matrix product of the
    # recurrence-built exponentials, against lstsq on np.cos / np.sin columns
    rng = np.random.default_rng(11 + order)
    t = campaign_times(rng, 9) + 3.7          # not from 0: the phases are not trivial
    y = doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    w = rng.uniform(0.5, 2.0, t.size)
    span = float(t.max() - t.min())
    f1s = np.array([0.2, 0.2071, 0.31])
    f2s = np.array([1 / 13.7, 0.0655, 0.1, 0.1035, 0.2071])   # 0.1 = f1/2, 0.2071 = f1
    fast = _grid_rss(t, y, w, f1s, f2s, order, span)
    degenerate = _degenerate(f1s[:, None], f2s[None, :], order, span)
    assert degenerate[1, 4] and degenerate[0, 2] == (order >= 2) and not degenerate[0, 0]
    assert np.all(np.isinf(fast[degenerate])) and np.all(np.isfinite(fast[~degenerate]))
    for i, j in zip(*np.nonzero(~degenerate)):
        assert fast[i, j] == pytest.approx(direct_rss(t, y, w, f1s[i], f2s[j], order),
                                           rel=1e-6, abs=1e-12), (order, f1s[i], f2s[j])
    # without the span every pair is computed (a degenerate one too: ridge, else LU)
    every = _grid_rss(t, y, w, f1s, f2s, order)
    assert np.all(np.isfinite(every))
    np.testing.assert_allclose(every[~degenerate], fast[~degenerate], rtol=1e-12)
    assert every[0, 4] == pytest.approx(direct_rss(t, y, w, 0.2, 0.2071, order), rel=1e-6)


def test_the_grid_is_the_same_in_chunks_of_one_f2(monkeypatch):
    # every chunk on its own (its own degenerate mask, products and factorisations)
    from tumble_ros.analysis import periods
    rng = np.random.default_rng(6)
    t = campaign_times(rng, 9)
    y = doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    w = np.ones(t.size)
    span = float(t.max() - t.min())
    f1s, f2s = np.array([0.2, 0.1, 0.31]), np.linspace(0.02, 0.4, 23)
    whole = _grid_rss(t, y, w, f1s, f2s, 3, span)
    monkeypatch.setattr(periods, '_CHUNK', 1)
    one_by_one = _grid_rss(t, y, w, f1s, f2s, 3, span)
    assert np.isinf(whole).sum() > 0 and np.isfinite(whole).sum() > 40
    np.testing.assert_array_equal(np.isinf(one_by_one), np.isinf(whole))
    finite = np.isfinite(whole)
    np.testing.assert_allclose(one_by_one[finite], whole[finite], rtol=1e-6)   # rounding / cond


def test_the_grid_falls_back_to_lu_when_cholesky_fails(monkeypatch):
    # a chunk whose factorisation fails is solved by LU: the same RSS as lstsq
    rng = np.random.default_rng(4)
    t = campaign_times(rng, 9)
    y = doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    w = rng.uniform(0.5, 2.0, t.size)
    f1s, f2s = np.array([0.2, 0.31]), np.array([1 / 13.7, 0.0655])

    def refuse(matrix):
        raise np.linalg.LinAlgError('refused by the test')
    monkeypatch.setattr(np.linalg, 'cholesky', refuse)
    grid = _grid_rss(t, y, w, f1s, f2s, 2)
    for i, j in np.ndindex(grid.shape):
        assert grid[i, j] == pytest.approx(direct_rss(t, y, w, f1s[i], f2s[j], 2), rel=1e-6)


def test_two_known_periods_are_recovered_through_noise_and_gaps_within_their_uncertainty():
    rng = np.random.default_rng(7)
    t = campaign_times(rng, 12)
    p1, p2 = 5.0, 13.7
    y = doubly_periodic(t, 1 / p1, 1 / p2, TERMS) + rng.normal(0.0, 0.01, t.size)
    sol = search_periods(t + 2460000.0 * 24.0, y, np.full(t.size, 0.01), period_min=2.0,
                         period_max=60.0)
    assert sol.two_periods
    assert abs(sol.p1 - p1) < 3.0 * sol.p1_sigma and sol.p1_sigma < 0.002 * p1
    assert abs(sol.p2 - p2) < 3.0 * sol.p2_sigma and sol.p2_sigma < 0.002 * p2
    assert sol.rms == pytest.approx(0.01, rel=0.15)
    strongest = sol.harmonics[0]
    assert (strongest.j, strongest.k) == (2, 0)
    assert strongest.amplitude == pytest.approx(0.25, rel=0.05)
    # the model reproduces the noise-free signal
    tm = np.linspace(t[0], t[-1], 500) + 2460000.0 * 24.0
    truth = doubly_periodic(tm - 2460000.0 * 24.0 - 0.0, 1 / p1, 1 / p2, TERMS)
    resid = sol.model(tm) - truth
    assert np.std(resid[(tm - tm[0] < 30.0)]) < 0.01


def test_the_mirror_bases_of_the_lattice_are_listed_with_their_rms():
    rng = np.random.default_rng(8)
    t = campaign_times(rng, 12)
    y = doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    sol = search_periods(t, y, period_min=2.0, period_max=60.0)
    labels = {m.label: m for m in sol.mirrors}
    # the basis found, or one listed among its mirrors, is the true one (1/5 h, 1/13.7 h)
    bases = [(sol.p1, sol.p2)] + [(m.p1, m.p2) for m in sol.mirrors]
    assert any(sorted(b) == pytest.approx([5.0, 13.7], rel=1e-3) for b in bases), bases
    assert {'(f1 - f2, f2)', '(f1, f1 - f2)', '(f2, f1)', '(f1 + f2, f2)'} <= set(labels)
    f1, f2 = 1 / sol.p1, 1 / sol.p2
    assert labels['(f1 - f2, f2)'].p1 == pytest.approx(1 / (f1 - f2))
    assert labels['(f2, f1)'].rms == pytest.approx(sol.rms, rel=1e-9)   # the same series
    assert all(m.rms >= sol.rms * (1 - 1e-9) for m in sol.mirrors)


def test_a_single_period_is_reported_as_one():
    rng = np.random.default_rng(9)
    t = campaign_times(rng, 12)
    p = 6.3
    y = (0.3 * np.cos(4 * np.pi * t / p + 0.2) + 0.05 * np.cos(2 * np.pi * t / p + 1.0)
         + 0.02 * np.cos(6 * np.pi * t / p) + rng.normal(0.0, 0.015, t.size))
    sol = search_periods(t, y, period_min=2.0, period_max=60.0)
    assert not sol.two_periods and math.isnan(sol.p2)
    assert abs(sol.p1 - p) < 3.0 * sol.p1_sigma and sol.p1_sigma < 0.001 * p
    assert sol.bic_two > sol.bic_one - 10.0
    assert {(h.j, h.k) for h in sol.harmonics} == {(1, 0), (2, 0), (3, 0)} or sol.order >= 3


@pytest.mark.parametrize('kwargs, match', [
    ({'magnitude': np.zeros(5)}, 'magnitude'),
    ({'sigma': -np.ones(40)}, 'sigma'),
    ({'period_min': 50.0, 'period_max': 10.0}, 'period_min'),
])
def test_bad_inputs_are_refused_naming_the_argument(kwargs, match):
    args = {'t': np.linspace(0.0, 100.0, 40), 'magnitude': np.sin(np.linspace(0, 30, 40))}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        search_periods(args.pop('t'), args.pop('magnitude'), **args)


def test_combination_names_the_small_integer_combination():
    assert combination(1 / 30.565, 1 / 27.374, 1 / 262.2) == (1, -1)
    assert combination(2 / 30.565, 1 / 27.374, 1 / 262.2) == (2, -2)
    assert combination(1 / 17.0, 1 / 27.374, 1 / 262.2) is None


# ---- the closed loop: the simulated tumbler seen by a synthetic campaign ----

# Sun and observer 37 deg from the ecliptic south (near L), 25 deg phase angle: a geometry in
# which the rotation's signal is strong enough; seen from L's equator, the lightcurve is nearly
# periodic in 1/P_phi - 1/P_psi alone (docs/analysis.md, "Periods from a lightcurve").
ALPHA = math.radians(25.0)
SETTINGS = LightcurveSettings(sun=(0.6, 0.0, -0.8),
                              observer=(0.6 * math.cos(ALPHA), 0.6 * math.sin(ALPHA), -0.8))


def campaign(scenario, rng, nights=28, noise=0.01):
    """Return the tumbler's synthetic lightcurve over a campaign [h], Gaussian noise [mag]."""
    th = campaign_times(rng, nights, per_hour=10.0)
    sc = scenario.replace(orbit=None, duration=(th[-1] + 1.0) / H)
    run = simulate(sc, th / H)
    assert run.success
    record = synthetic_lightcurve(sc, th / H, run.quaternion, SETTINGS)
    return th, record.magnitude + rng.normal(0.0, noise, th.size)


def assert_tumbler_found(sol, p_phi, p_psi):
    """
    1/P_phi - 1/P_psi is a period (or a mirror's) within 1 %, the strongest harmonic at twice it.

    1/P_phi, too, is a combination of f1 and f2 within 1 % (in the lattice), and P_phi and P_psi
    are each a period of the basis found or of a listed mirror basis, within 1 %.
    """
    assert sol.two_periods
    f1, f2 = 1.0 / sol.p1, 1.0 / sol.p2
    f_phi, f_psi = 1.0 / p_phi, 1.0 / p_psi
    g = f_phi - f_psi
    assert combination(g, f1, f2, largest=2) is not None, (sol.p1, sol.p2)
    assert combination(f_phi, f1, f2, largest=2) is not None, (sol.p1, sol.p2)
    # one of the periods (or of a listed mirror basis) is 1/(1/P_phi - 1/P_psi) itself
    periods = [sol.p1, sol.p2] + [p for m in sol.mirrors for p in (m.p1, m.p2)]
    assert min(abs(p * g - 1.0) for p in periods) < 0.01
    assert min(abs(p / p_phi - 1.0) for p in periods) < 0.01, periods
    assert min(abs(p / p_psi - 1.0) for p in periods) < 0.01, periods
    strongest = abs(sol.harmonics[0].frequency)
    assert abs(strongest / (2.0 * g) - 1.0) < 0.01


@pytest.fixture(scope='module')
def apophis():
    return load_scenario(CONFIG)


def test_the_apophis_tumbler_is_found_in_its_lightcurve_before_the_flyby(apophis):
    th, mag = campaign(apophis, np.random.default_rng(29))
    sol = search_periods(th, mag, np.full(th.size, 0.01), period_min=10.0, period_max=600.0)
    assert_tumbler_found(sol, 27.374, 262.2)
    g = 1 / 27.374 - 1 / 262.2
    assert abs(1 / g - 30.565) < 0.005                    # Pravec et al. 2014: 30.56 +- 0.01 h


def test_the_apophis_tumbler_is_found_after_the_simulated_flyby(apophis):
    flyby = simulate(apophis)
    assert flyby.success
    omega, q = flyby.omega[-1], flyby.quaternion[-1]
    after = spin_state(omega, apophis.inertia, q)
    assert after.mode == 'SAM'
    p_phi, p_psi = after.precession_period * H, after.rotation_period * H
    assert abs(p_phi - 27.374) > 0.01 or abs(p_psi - 262.2) > 1.0    # the flyby changed it
    start = apophis.replace(omega0=tuple(omega), euler0=quaternion_to_euler(q))
    th, mag = campaign(start, np.random.default_rng(2029))
    sol = search_periods(th, mag, np.full(th.size, 0.01), period_min=10.0, period_max=600.0)
    assert_tumbler_found(sol, p_phi, p_psi)


def test_a_principal_axis_rotator_gives_one_period(apophis):
    # the same body spinning about its largest moment at 30 h
    rate = 2.0 * math.pi / (30.0 / H)
    sc = apophis.replace(omega0=(0.0, 0.0, rate), euler0=(0.3, 0.0, 0.5))
    th, mag = campaign(sc, np.random.default_rng(3), nights=20, noise=0.015)
    sol = search_periods(th, mag, np.full(th.size, 0.015), period_min=10.0, period_max=600.0)
    assert not sol.two_periods
    # an elongated body: two maxima per turn, the fit may lock on the half period's harmonics
    assert min(abs(sol.p1 - 30.0), abs(2.0 * sol.p1 - 30.0)) < 3.0 * sol.p1_sigma + 0.003


# ---- a user's photometry: the CSV reader and `analyze --photometry` ----

def write_campaign_csv(path, header='JD,mag,err', err=True):
    rng = np.random.default_rng(5)
    t = campaign_times(rng, 12)
    y = 15.0 + doubly_periodic(t, 1 / 5.0, 1 / 13.7, TERMS) + rng.normal(0.0, 0.01, t.size)
    lines = ['# a comment', header]
    for a, b in zip(t, y):
        lines.append(f'{2460000.5 + a / 24.0:.8f},{b:.5f}' + (',0.01' if err else ''))
    path.write_text('\n'.join(lines) + '\n')
    return t, y


def test_the_csv_reader_reads_julian_days_into_hours_with_errors(tmp_path):
    from tumble_ros.analysis.photometry_file import read_photometry
    t, y = write_campaign_csv(tmp_path / 'obs.csv')
    data = read_photometry(tmp_path / 'obs.csv')
    assert data.time_column == 'jd'
    np.testing.assert_allclose(data.t - data.t[0], t - t[0], atol=1e-5)
    np.testing.assert_allclose(data.magnitude, y, atol=1e-5)
    assert data.sigma is not None and np.all(data.sigma == 0.01)
    write_campaign_csv(tmp_path / 'h.csv', header='time_h,Magnitude', err=False)
    assert read_photometry(tmp_path / 'h.csv').sigma is None


@pytest.mark.parametrize('text, match', [
    ('', 'empty'),
    ('when,mag\n1,2\n', 'no time column'),
    ('jd,flux\n1,2\n', 'no magnitude column'),
    ('jd,mag\n' + '1,2\n' * 5, 'need at least 20'),
    ('jd,mag\n1,bright\n', 'line 2: mag = .bright. is not a number'),
    ('jd,mag,err\n' + '1,2,0.01\n' * 20 + '1,2,0\n',
     r'line 22: err = 0 must be in \[1e-06, 100\] mag'),
    ('jd,mag\n1\n', 'line 2: 1 fields'),
    ('jd,mjd,mag\n1,2,3\n', 'several time columns'),
])
def test_a_bad_csv_is_refused_naming_line_and_column(tmp_path, text, match):
    from tumble_ros.analysis.photometry_file import read_photometry
    from tumble_ros.errors import AnalysisError
    path = tmp_path / 'bad.csv'
    path.write_text(text)
    with pytest.raises(AnalysisError, match=match):
        read_photometry(path)


def test_analyze_prints_the_periods_of_a_csv(tmp_path, capsys):
    from tumble_ros.analysis.cli import command
    write_campaign_csv(tmp_path / 'obs.csv')
    # (from 3 h: the basis found, 3.66 h and 5 h, is inside; from 2 h, the same at 1.6x the CPU)
    assert command(['--photometry', str(tmp_path / 'obs.csv'), '--period-range', '3',
                    '60']) == 0
    out = capsys.readouterr().out
    assert 'two periods' in out and 'mirror bases' in out
    # the lattice (1/5 h, 1/13.7 h), whichever basis is printed
    assert command(['--photometry', str(tmp_path / 'obs.csv'), '--period-range', '3', '60',
                    '--json']) == 0
    import json
    sol = json.loads(capsys.readouterr().out)
    f1, f2 = 1 / sol['p1'], 1 / sol['p2']
    assert combination(1 / 5.0, f1, f2, largest=2, rel_tol=1e-3) is not None
    assert combination(1 / 13.7, f1, f2, largest=2, rel_tol=1e-3) is not None
    assert command(['--photometry', str(tmp_path / 'missing.csv')]) == 1
    assert re.search(r'ERROR: .*missing\.csv: no such file', capsys.readouterr().err)
    assert command(['--period-range', '2', '60', 'run.mcap']) == 1
    assert '--period-range needs --photometry' in capsys.readouterr().err


def test_analyze_finds_the_periods_of_a_recorded_lightcurve_and_draws_it(apophis, tmp_path,
                                                                         capsys):
    from tumble_ros.analysis.cli import command
    from tumble_ros.runs.offline import record_offline
    # Apophis ten times faster (P_phi = 2.7374 h, P_psi = 26.22 h) over 5 days, 0.1 h steps
    # (over 10 days, the same search took 2.8x the CPU)
    sc = apophis.replace(orbit=None, duration=120.0 / H, output_interval=0.1 / H,
                         omega0=tuple(10.0 * np.asarray(apophis.omega0)), lightcurve=SETTINGS)
    record_offline(sc, tmp_path / 'run.mcap', markers=False)
    figures = tmp_path / 'figs'
    assert command([str(tmp_path / 'run.mcap'), '--lightcurve', '--period-range', '1', '60',
                    '--figures', str(figures), '--quiet']) == 0
    out = capsys.readouterr().out
    assert 'periods of the recorded lightcurve topic' in out and 'two periods' in out
    png = figures / 'lightcurve.png'
    assert f'lightcurve: {png}' in out and png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    # 1/P_phi and the strongest term 2 (1/P_phi - 1/P_psi) are in the lattice found, 1 %
    line = next(text for text in out.splitlines() if 'two periods' in text)
    p1, p2 = (float(line.split('P1 = ')[1].split()[0]), float(line.split('P2 = ')[1].split()[0]))
    assert combination(2 / 3.0565, 1 / p1, 1 / p2, largest=2) is not None, (p1, p2)
    assert combination(1 / 2.7374, 1 / p1, 1 / p2, largest=2) is not None, (p1, p2)
    # a second run keeps the figure unless --overwrite (refused before the search)
    only = tmp_path / 'only'
    only.mkdir()
    (only / 'lightcurve.png').write_bytes(b'keep')
    assert command([str(tmp_path / 'run.mcap'), '--lightcurve', '--figures', str(only),
                    '--quiet']) == 1
    assert 'lightcurve.png exists' in capsys.readouterr().err
    assert (only / 'lightcurve.png').read_bytes() == b'keep'
    assert [p.name for p in only.iterdir()] == ['lightcurve.png']      # nothing else written

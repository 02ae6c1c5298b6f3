"""
Honest period analysis (issue 47): what the search cannot know, it says.

The data are made here, independently of analysis/periods.py: a campaign's times (nights of a
few hours, one a day, some clouded) and sums of cosines in the two frequencies. A two-period
campaign (7.35 h, 18.9 h, 14 nights) gives its true pair, or lists it among the alternatives,
with the one-day aliases listed and the day named among the sampling's periodicities, from the
default period range whose grid is bounded; a geometry-dominated curve (a flyby's distance
trend of several magnitudes over a small rotation) is warned about, and a recording's is
searched reduced, saying so; a span shorter than the period is warned about; a period on the
day is flagged; the progress printer.
"""
import io
import math

import numpy as np
import pytest

from tumble_ros.analysis import periods
from tumble_ros.analysis.periods import (DAYS_IN_HOURS, GRID_BUDGET, search_periods,
                                         stderr_search_progress)


def nightly_times(rng, nights, per_hour=10.0, night=(5.0, 8.0), clouded=0.15):
    """Return times [h]: a night of 5-8 h a day at random instants, some lost to clouds."""
    out = []
    for k in range(nights):
        if rng.random() < clouded:
            continue
        length = rng.uniform(*night)
        start = 24.0 * k + rng.uniform(0.0, 8.0 - length)
        out.append(start + np.sort(rng.uniform(0.0, length, int(length * per_hour))))
    return np.concatenate(out)


def series(t, f1, f2, terms):
    """Return the sum of a cos(2 pi (j f1 + k f2) t + phase) over the terms (j, k, a, phase)."""
    return sum(a * np.cos(2.0 * np.pi * (j * f1 + k * f2) * t + p) for j, k, a, p in terms)


TERMS = [(2, 0, 0.22, 0.3), (1, 0, 0.07, 1.0), (0, 2, 0.09, 2.0), (1, -1, 0.05, 0.5),
         (2, 1, 0.04, 4.0), (0, 1, 0.03, 2.5), (1, 1, 0.03, 1.2)]


def listed_pairs(sol):
    """Return every pair the solution offers: its own, its mirror bases', its alternatives'."""
    return ([(sol.p1, sol.p2)] + [(m.p1, m.p2) for m in sol.mirrors]
            + [(a.p1, a.p2) for a in sol.alternatives])


def test_a_two_period_campaign_gives_its_true_pair_from_the_bounded_default_range(monkeypatch):
    rng = np.random.default_rng(47)
    t = nightly_times(rng, 14)
    y = 15.0 + series(t, 1 / 7.35, 1 / 18.9, TERMS) + rng.normal(0.0, 0.01, t.size)
    trials = {}
    grid = periods._grid_rss

    def counted(t_, y_, w_, f1s, f2s, order, *args, **kwargs):
        trials[order] = f1s.size * f2s.size
        return grid(t_, y_, w_, f1s, f2s, order, *args, **kwargs)
    monkeypatch.setattr(periods, '_grid_rss', counted)
    sol = search_periods(t, y, np.full(t.size, 0.01), named_periods=DAYS_IN_HOURS, unit=' h')
    # the true pair is the solution or listed (a mirror basis or an alternative), 0.2 %
    assert any(sorted(p) == pytest.approx([7.35, 18.9], rel=2e-3) for p in listed_pairs(sol)), \
        listed_pairs(sol)
    assert sol.two_periods and sol.chi2 == pytest.approx(1.0, abs=0.15)
    # the day is named among the sampling's periodicities, its aliases are among the
    # alternatives (each refitted: an RMS), sorted by their fit
    assert ('solar day', 24.0) in sol.sampling
    day_aliases = [a for a in sol.alternatives if 'solar day' in a.label]
    assert day_aliases and all(a.rms > 0.0 for a in day_aliases)
    assert [a.rms for a in sol.alternatives] == sorted(a.rms for a in sol.alternatives)
    # the default range: from 4 median steps (0.4 h) up, raised to hold the grid to its budget
    step = float(np.median(np.diff(t)))
    assert sol.period_range[0] > 4.0 * step and sol.period_range[1] == pytest.approx(np.ptp(t))
    assert 'raised' in sol.range_note
    assert 0 < trials[3] <= GRID_BUDGET


def test_a_period_on_the_day_is_flagged_and_warned_about():
    # a rotator at 24.05 h seen one night a day: within 1/span of the sampling's own period
    rng = np.random.default_rng(3)
    t = nightly_times(rng, 14)
    f = 1 / 24.05
    y = (0.2 * np.cos(4 * np.pi * f * t) + 0.05 * np.cos(2 * np.pi * f * t + 1.0)
         + rng.normal(0.0, 0.01, t.size))
    sol = search_periods(t, y, np.full(t.size, 0.01), period_min=3.0, period_max=100.0,
                         named_periods=DAYS_IN_HOURS, unit=' h')
    assert sol.aliases and 'solar day' in sol.aliases[0], (sol.p1, sol.aliases)
    assert any('periodicity of the sampling' in w for w in sol.warnings)
    text = periods.format_periods(sol)
    assert 'WARNING' in text and 'on solar day' in text


def flyby(t, perigee=72.0, closest=0.00026, speed=0.0001):
    """Return a flyby's distance [au] at t [h]: a straight line past the observer."""
    return np.hypot(closest, speed * (t - perigee))


def test_a_geometry_dominated_curve_is_warned_about():
    # 6 days every 0.1 h: 5 log10(delta) spans ~6 mag, the rotation 0.1 mag at 7 h
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 144.0, 0.1)
    y = 5 * np.log10(flyby(t)) + 0.1 * np.cos(4 * np.pi * t / 7.0) + rng.normal(0, 0.01, t.size)
    assert np.ptp(5 * np.log10(flyby(t))) > 5.0
    sol = search_periods(t, y, period_min=2.0, period_max=40.0)
    assert any('more than a rotation makes' in w and 'flyby' in w for w in sol.warnings), \
        sol.warnings


def recording_of(tmp_path, t, brightness, magnitude, phase):
    """Return a Recording of a lightcurve topic only (t [h], its first three columns)."""
    from tumble_ros.analysis.recording import Recording
    from tumble_ros.core.units import HOURS_PER_YEAR
    columns = np.zeros((t.size, 8))
    columns[:, 0], columns[:, 1], columns[:, 2] = brightness, magnitude, phase
    empty = np.empty(0)
    return Recording(path=tmp_path / 'run.mcap', finalised=True, problem=None, topics={},
                     seconds_per_year=1.0, seconds_per_year_source='default', t=empty,
                     omega=np.empty((0, 3)), stamp_ns=empty.astype(np.int64),
                     lightcurve_t=t / HOURS_PER_YEAR, lightcurve=columns)


def test_a_recorded_flyby_is_searched_reduced_and_says_so(tmp_path):
    from tumble_ros.analysis.lightcurve import recorded_periods
    t = np.arange(0.0, 144.0, 0.1)
    phase = np.radians(20.0 + 60.0 * np.exp(-((t - 72.0) / 20.0) ** 2))
    # the rotation (7 h, two maxima a turn) times a phase darkening, at the flyby's distance
    # (and 1 % noise: the brightness of a real recording carries none, and the BIC then keeps
    # raising the order: docs/analysis.md, "Limits")
    brightness = ((1.0 + 0.1 * np.cos(4 * np.pi * t / 7.0)) * (1.0 - 0.8 * phase / np.pi)
                  * (1.0 + np.random.default_rng(6).normal(0.0, 0.01, t.size)))
    magnitude = -2.5 * np.log10(brightness) + 5 * np.log10(flyby(t))
    rec = recording_of(tmp_path, t, brightness, magnitude, phase)
    _, reduced, sol = recorded_periods(rec, 2.0, 40.0)
    assert 'distance modulus' in sol.reduction and 'phase function' in sol.reduction
    assert np.ptp(reduced) < 0.5 < 5.0 < np.ptp(magnitude)
    assert not any('flyby' in w for w in sol.warnings), sol.warnings
    found = [sol.p1, 2 * sol.p1] if not sol.two_periods else [sol.p1, sol.p2, 2 * sol.p1]
    assert min(abs(p - 7.0) for p in found) < 0.01, (sol.p1, sol.p2)
    assert 'searched: reduced magnitudes' in periods.format_periods(sol)


def test_a_span_shorter_than_the_period_is_warned_about():
    # 10 h of data of a 30-h rotator: the default range stops at the span
    rng = np.random.default_rng(8)
    t = np.sort(rng.uniform(0.0, 10.0, 200))
    y = 0.3 * np.cos(2 * np.pi * t / 30.0 + 0.4) + rng.normal(0.0, 0.01, t.size)
    sol = search_periods(t, y, np.full(t.size, 0.01), unit=' h')
    assert any('span' in w for w in sol.warnings), sol.warnings
    # asked for periods up to 60 h: what is found beyond half the span is not measured
    wide = search_periods(t, y, np.full(t.size, 0.01), period_min=1.0, period_max=60.0,
                          unit=' h')
    assert wide.p1 > 5.0 and any('longer than half the span' in w for w in wide.warnings), \
        (wide.p1, wide.warnings)


def test_an_explicit_range_too_big_for_the_span_is_refused():
    t = np.linspace(0.0, 1e7, 50)
    with pytest.raises(ValueError, match='period_min, period_max: .* trial frequencies'):
        search_periods(t, np.sin(t), period_min=0.5, period_max=100.0)


@pytest.mark.parametrize('kwargs, match', [
    ({'magnitude': np.full(40, 1e300)}, 'magnitude: 1e.300 is not a magnitude'),
    ({'sigma': np.full(40, 1e-300)}, r'sigma: need 40 finite errors in \[1e-06, 100\]'),
])
def test_absurd_values_are_refused_without_numpy_warnings(kwargs, match):
    import warnings
    args = {'t': np.linspace(0.0, 100.0, 40), 'magnitude': np.sin(np.linspace(0, 30, 40))}
    args.update(kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        with pytest.raises(ValueError, match=match):
            search_periods(args.pop('t'), args.pop('magnitude'), **args)


def test_the_progress_printer_is_silent_at_first_then_prints_each_stage():
    quiet, loud = io.StringIO(), io.StringIO()
    for stream, after in ((quiet, 3600.0), (loud, 0.0)):
        report = stderr_search_progress(after=after, every=3600.0, stream=stream)
        report('1-period scan', 0.0)
        report('2-period grid, order 1', 0.1)
        report('2-period grid, order 1', 0.2)        # the same stage, within `every`: not
        report('alternatives', 1.0)
    assert quiet.getvalue() == ''
    lines = loud.getvalue().splitlines()
    assert [line.split(',')[0] for line in lines] == ['period search: 1-period scan',
                                                      'period search: 2-period grid',
                                                      'period search: alternatives']
    assert lines[1].startswith('period search: 2-period grid, order 1, 10%')


def test_the_json_of_a_solution_has_no_nan(tmp_path, capsys):
    # one period: p2, its sigma and the chi-square without errors are null, not NaN
    import json
    from tumble_ros.analysis.cli import command
    rng = np.random.default_rng(2)
    t = nightly_times(rng, 6)
    y = (15.0 + 0.3 * np.cos(4 * np.pi * t / 6.3) + 0.05 * np.cos(2 * np.pi * t / 6.3)
         + rng.normal(0.0, 0.01, t.size))
    path = tmp_path / 'obs.csv'
    path.write_text('time_h,mag\n' + ''.join(f'{a:.5f},{b:.4f}\n' for a, b in zip(t, y)))
    assert command(['--photometry', str(path), '--period-range', '3', '20', '--json',
                    '--quiet']) == 0
    data = json.loads(capsys.readouterr().out)
    assert data['p2'] is None and data['chi2'] is None and math.isclose(data['p1'], 6.3,
                                                                        rel_tol=0.01)
    assert data['sampling'][0][0] in {'solar day', 'sidereal day'}
    assert isinstance(data['alternatives'], list) and data['alternatives']


def test_the_command_prints_the_warnings_on_stderr(tmp_path, capsys):
    from tumble_ros.analysis.cli import command
    t = np.arange(0.0, 144.0, 0.25)
    y = 5 * np.log10(flyby(t)) + 0.1 * np.cos(4 * np.pi * t / 7.0)
    path = tmp_path / 'flyby.csv'
    path.write_text('hours,mag\n' + ''.join(f'{a:.3f},{b:.4f}\n' for a, b in zip(t, y)))
    assert command(['--photometry', str(path), '--period-range', '2', '40', '--quiet']) == 0
    captured = capsys.readouterr()
    assert 'WARNING: period search: the magnitudes span 6.8 mag (2-98 %), more than a ' \
        'rotation makes' in captured.err
    assert 'WARNING: the magnitudes span 6.8 mag' in captured.out

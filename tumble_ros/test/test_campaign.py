"""
A photometric campaign: the lightcurve observed night by night (lightcurve.night_*, issue 47).

The shipped config/photometric_campaign.yaml runs (shortened to five nights here), its
lightcurve topic is NaN exactly between the nights, and ``analyze --lightcurve`` finds its period
in what the nights kept.
"""
from pathlib import Path

import numpy as np
import pytest

from tumble_ros.core import load_scenario, parse_scenario, ScenarioError
from tumble_ros.core.photometry import LightcurveSettings
from tumble_ros.core.units import HOURS_PER_YEAR

CAMPAIGN = Path(__file__).resolve().parents[1] / 'config' / 'photometric_campaign.yaml'
HOURS = ('sim:\n  ros__parameters:\n    time_unit: h\n    inertia: [0.61, 0.965, 1.0]\n'
         '    orbit_rate: 0.0\n    duration: 48.0\n    output_interval: 0.1\n'
         '    lightcurve:\n{nights}')


def test_nights_are_read_in_the_scenarios_unit():
    sc = parse_scenario(HOURS.format(nights='      night_length: 8.0\n      night_every: 24.0\n'
                                            '      night_start: 2.0\n'))
    assert sc.lightcurve.night_length * HOURS_PER_YEAR == pytest.approx(8.0, rel=1e-14)
    hours = np.array([1.9, 2.1, 9.9, 10.1, 25.9, 26.1, 33.9, 34.1])
    assert sc.lightcurve.observed(hours / HOURS_PER_YEAR).tolist() == [
        False, True, True, False, False, True, True, False]
    assert parse_scenario(HOURS.format(nights='      law: lambert\n')).lightcurve.observed(
        [0.0, 1.0]).all()                                                   # no nights: all
    default = parse_scenario(HOURS.format(nights='      night_length: 8.0\n'))
    assert default.lightcurve.night_every == 1.0 / 365.25                  # default: a day


@pytest.mark.parametrize('values, phrase', [
    ({'night_length': 2.0, 'night_every': 1.0}, 'lightcurve.night_length: must be in [0, '
                                                'night_every]'),
    ({'night_length': -1e-3}, 'lightcurve.night_length: must be in [0, night_every]'),
    ({'night_every': 0.0}, 'lightcurve.night_every: must be > 0'),
    ({'night_start': float('nan')}, 'lightcurve.night_start: must be a finite time'),
    ({'night_length': '8h'}, "lightcurve.night_length: must be a finite time, got '8h'"),
])
def test_impossible_nights_are_refused_naming_the_field(values, phrase):
    with pytest.raises(ScenarioError, match=phrase.replace('[', r'\[').replace(']', r'\]')):
        LightcurveSettings(**values)


@pytest.fixture(scope='module')
def five_nights(tmp_path_factory):
    """Record the shipped campaign, shortened to five nights (120 h)."""
    from tumble_ros.runs.offline import record_offline

    shipped = load_scenario(CAMPAIGN)
    assert shipped.duration * HOURS_PER_YEAR == pytest.approx(240.0)     # the file: ten nights
    path = tmp_path_factory.mktemp('campaign') / 'campaign.mcap'
    record_offline(shipped.replace(duration=120.0 / HOURS_PER_YEAR), path, markers=False)
    return path


def test_the_campaigns_lightcurve_is_seen_only_at_night(five_nights):
    from tumble_ros.analysis import load_recording

    rec = load_recording(five_nights)
    hours = rec.lightcurve_t * HOURS_PER_YEAR
    seen = np.isfinite(rec.lightcurve[:, 1])
    assert hours.size == 1201                                 # one message a sample
    # nights [0.05, 8.05) h + k 24 h (off the 0.1-h grid): samples 1 to 80 of every 240
    index = np.round(hours * 10.0).astype(int)
    in_night = (np.mod(index, 240) >= 1) & (np.mod(index, 240) <= 80)
    assert np.array_equal(seen, in_night), hours[seen != in_night]
    assert seen.sum() == 5 * 80
    assert np.all(np.isnan(rec.lightcurve[~seen, 0]))         # the brightness too


def test_analyze_finds_the_period_in_the_campaigns_nights(five_nights, capsys):
    """
    The lightcurve period 3.65 h: half the rotation's 7.3 h (two maxima a turn).

    Searched in 2 to 12 h (the default range's two-period grid takes minutes, and a
    noise-free curve lets it fit harmonics as a second period: docs/analysis.md, "Limits").
    """
    from tumble_ros.analysis.cli import command

    assert command([str(five_nights), '--lightcurve', '--quiet', '--period-range', '2',
                    '12']) == 0
    out = capsys.readouterr().out
    assert 'lightcurve: 400 points over' in out, out
    line = next(s for s in out.splitlines() if s.strip().startswith('one period: P = '))
    period = float(line.split('P = ')[1].split()[0])
    assert period == pytest.approx(7.3 / 2.0, rel=1e-4), line
    assert 'periodicities of the sampling: window peak' in out    # the nights' 24 h, named

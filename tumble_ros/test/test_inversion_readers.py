"""
Photometry as observers have it, read into a Campaign (issue 49): each format, each refusal.

The numbers are checked against hand-computed ones: a relative flux of 0.5 is +0.7526 mag
(2.5 log10 2); UTC -> TDB in 2020 is 37 s of leap seconds + 32.184 s (TT - TAI) + < 1.7 ms
(TDB - TT); one au of light is 499.005 s. The geometry comes from Horizons tables of an
asteroid and an observer moving uniformly about the Sun, so that the light-time equation
|E(t_r) - A(t_e)| = c (t_r - t_e) is a quadratic solved here in closed form, independently of
the reader's iteration. Bad input (a missing column, a bad number on line k, NaN, unsorted
times, a time outside the ephemeris, a FIFO, too many rows) is one CampaignError line naming
the file and the line.
"""
import math
import os

import numpy as np
import pytest

from tumble_ros.core.units import KM_PER_AU
from tumble_ros.inversion.campaign import CampaignError
from tumble_ros.inversion.readers import common, read_campaign, to_tdb
from tumble_ros.inversion.readers.common import LIGHT_DAYS_PER_AU

C_AU_PER_DAY = 299792.458 * 86400.0 / KM_PER_AU
T0 = 2459000.5                                   # 2020-05-31.0
#: the asteroid's and the observer's heliocentric motion: x(t) = x0 + v (t - T0) [au, au/d]
A0, V = np.array([1.5, 0.2, 0.05]), np.array([-0.002, 0.01, 0.0003])
E0, W = np.array([0.1, 0.99, 0.0]), np.array([-0.017, 0.0017, 0.0])
#: TDB - UTC in 2020 [s]: 37 leap seconds + 32.184 s; TDB - TT is below 1.7 ms
TDB_MINUS_UTC = 37.0 + 32.184


def asteroid(t):
    return A0 + V * (np.asarray(t)[..., None] - T0)


def earth(t):
    return E0 + W * (np.asarray(t)[..., None] - T0)


def horizons(path, target, center, vectors, velocity, *, frame='Ecliptic of J2000.0',
             start=T0 - 2.0, end=T0 + 8.0):
    """Write a Horizons vector table (CSV, AU-D) of ``vectors(t)`` [au], ``velocity`` [au/d]."""
    times = np.arange(start, end + 1e-9, 0.5)
    rows = [f'{t:.9f}, A.D. 2020-May-31 00:00:00.0000, '
            + ', '.join(f'{c:.16E}' for c in (*vectors(t), *velocity)) + ','
            for t in times]
    header = ['*' * 40, f'Target body name: {target}   {{source: JPL#1}}',
              f'Center body name: {center}   {{source: DE441}}', 'Output units    : AU-D',
              f'Reference frame : {frame}', 'JDTDB, Calendar Date (TDB), X, Y, Z, VX, VY, VZ,',
              '$$SOE']
    path.write_text('\n'.join(header + rows + ['$$EOE', '']))
    return path


@pytest.fixture
def tables(tmp_path):
    """Write the asteroid about the Sun and about the observer (as Horizons gives them)."""
    sun = horizons(tmp_path / 'sun.txt', '99942 Apophis (2004 MN4)', 'Sun (10)', asteroid, V)
    observer = horizons(tmp_path / 'geo.txt', '99942 Apophis (2004 MN4)', 'Earth (399)',
                        lambda t: asteroid(t) - earth(t), V - W)
    return sun, observer


def light_time(t_received):
    """Return tau [d] with |E(t_r) - A(t_r - tau)| = c tau, the quadratic's positive root."""
    d0 = earth(t_received) - asteroid(t_received)
    a = V @ V - C_AU_PER_DAY ** 2
    b = 2.0 * d0 @ V
    c = d0 @ d0
    return (-b - math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


# --- time scales and light time ------------------------------------------------------------

def test_utc_tt_and_tdb_become_tdb_by_the_known_offsets(monkeypatch):
    import astropy.utils.data

    def no_download(*args, **kwargs):
        raise AssertionError('a download was attempted')
    monkeypatch.setattr(astropy.utils.data, 'download_file', no_download)
    jd = np.array([2458849.5, 2459000.5])                        # 2020-01-01, 2020-05-31
    tdb, notes = to_tdb(jd, 'utc', 'f')
    assert np.all(np.abs((tdb - jd) * 86400.0 - TDB_MINUS_UTC) < 1.7e-3) and notes == ()
    tdb, _ = to_tdb(jd, 'TT', 'f')
    assert np.all(np.abs((tdb - jd) * 86400.0) < 1.7e-3)
    assert np.array_equal(to_tdb(jd, 'tdb', 'f')[0], jd)
    # a date beyond the bundled leap seconds: the last offset, said in a note
    tdb, notes = to_tdb(np.array([2470000.5]), 'utc', 'f')
    assert abs((tdb[0] - 2470000.5) * 86400.0 - TDB_MINUS_UTC) < 1.7e-3
    assert len(notes) == 1 and 'leap-second' in notes[0]
    with pytest.raises(CampaignError, match="f: time scale 'tai' not read"):
        to_tdb(jd, 'tai', 'f')


def test_one_au_of_light_is_499_seconds():
    assert LIGHT_DAYS_PER_AU * 86400.0 == pytest.approx(499.00478, abs=1e-5)


# --- DAMIT ---------------------------------------------------------------------------------

def damit_text(*curves):
    out = [f'{len(curves)}']
    for flag, rows in curves:
        out.append(f'{len(rows)} {flag}')
        out += [' '.join(str(v) for v in row) for row in rows]
    return '\n'.join(out) + '\n'


def damit_rows(start, count, flux=1.0):
    return [(start + k * 0.01, flux, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0) for k in range(count)]


def test_a_damit_file_is_read(tmp_path):
    path = tmp_path / 'lc.txt'
    path.write_text(damit_text((0, damit_rows(T0, 3, 0.5)),
                               (1, [(T0 + 1.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.5, 0.0)])))
    c = read_campaign(path)
    assert len(c) == 4 and c.light_time_corrected and c.free_offset == (True, False)
    np.testing.assert_allclose(c.magnitude[:3], 2.5 * math.log10(2.0), atol=5e-14)  # 0.7526
    assert c.magnitude[0] == pytest.approx(0.75257499, abs=1e-8)
    # the calibrated point: -2.5 log10 2 + 5 log10(2 au * 0.5 au) = -0.7526 mag
    assert c.magnitude[3] == pytest.approx(-0.75257499, abs=1e-8)
    assert c.reduced_magnitude()[3] == pytest.approx(-0.75257499, abs=1e-8)
    np.testing.assert_allclose((c.jd_tdb[:3] - (T0 + np.arange(3) * 0.01)) * 86400.0,
                               TDB_MINUS_UTC, atol=2e-3)
    np.testing.assert_allclose(c.phase_angle(), math.pi / 2)
    assert c.block.tolist() == [0, 0, 0, 1] and np.all(c.sigma == common.DEFAULT_SIGMA)
    # reception times: each point later by its observer distance's light time
    r = read_campaign(path, light_time=False, time_scale='tdb')
    np.testing.assert_allclose((r.jd_tdb - c.jd_tdb) * 86400.0 + TDB_MINUS_UTC,
                               [499.00478] * 3 + [0.5 * 499.00478], atol=2e-3)


@pytest.mark.parametrize('bad, line, match', [
    ('2459000.52 1.0 1 0 0 0 1', 5, r'7 numbers, a DAMIT point has 8'),
    ('2459000.52 abc 1 0 0 0 1 0', 5, r"intensity = 'abc' is not a number"),
    ('2459000.52 nan 1 0 0 0 1 0', 5, r'intensity = nan must be a finite number'),
    ('2459000.50 1.0 1 0 0 0 1 0', 5, r'is before the previous point.s \(line 4'),
    ('2459000.52 0.0 1 0 0 0 1 0', 5, r'intensity = 0 must be a relative flux > 0'),
    ('2459000.52 1.0 0 0 0 0 1 0', 5, r'the sun vector \[0.0, 0.0, 0.0\] is not a distance'),
    ('59000.52 1.0 1 0 0 0 1 0', 5, r'not a Julian date of the years 1800 to 2200'),
])
def test_a_bad_damit_line_is_refused_with_its_number(tmp_path, bad, line, match):
    path = tmp_path / 'lc.txt'
    good = [' '.join(str(v) for v in row) for row in damit_rows(T0, 2)]
    path.write_text('\n'.join(['1', '4 0', good[0], good[1], bad, good[1].replace('.51', '.6')]))
    with pytest.raises(CampaignError, match=rf'^{path} line {line}: .*{match}'):
        read_campaign(path, format='damit')


@pytest.mark.parametrize('text, match', [
    ('2\n1 0\n2459000.5 1 1 0 0 0 1 0\n', r': ends after 1 of the 2 lightcurves'),
    ('1\n3 0\n2459000.5 1 1 0 0 0 1 0\n', r': ends inside lightcurve 1 \(line 2 announces 3'),
    ('1\n1 0\n2459000.5 1 1 0 0 0 1 0\n7\n', r' line 4: more lines after the 1 lightcurves'),
    ('1\n1 2\n2459000.5 1 1 0 0 0 1 0\n', r' line 2: lightcurve 1: expected "points flag"'),
])
def test_a_damit_file_that_does_not_add_up_is_refused(tmp_path, text, match):
    path = tmp_path / 'lc.txt'
    path.write_text(text)
    with pytest.raises(CampaignError, match=f'^{path}{match}'):
        read_campaign(path, format='damit')


def test_a_fifo_is_refused_by_its_kind_at_once(tmp_path, alarm):
    fifo = tmp_path / 'lc.txt'
    os.mkfifo(fifo)
    for fmt in ('damit', 'alcdef', 'csv', None):
        with pytest.raises(CampaignError, match=r'lc.txt: is a FIFO \(named pipe\), not a'):
            read_campaign(fifo, format=fmt)


def test_too_many_points_are_refused_at_the_first_beyond_the_limit(tmp_path, monkeypatch):
    path = tmp_path / 'lc.txt'
    path.write_text(damit_text((0, damit_rows(T0, 12))))
    monkeypatch.setattr(common, 'MAX_CAMPAIGN_ROWS', 10)
    with pytest.raises(CampaignError, match=rf'^{path} line 13: more than 10 points'):
        read_campaign(path)


def test_a_byte_order_mark_is_skipped_and_utf16_refused(tmp_path):
    path = tmp_path / 'lc.txt'
    path.write_bytes(damit_text((0, damit_rows(T0, 3))).encode('utf-8-sig'))
    assert len(read_campaign(path, format='damit')) == 3
    path.write_bytes(damit_text((0, damit_rows(T0, 3))).encode('utf-16'))
    with pytest.raises(CampaignError, match='it holds UTF-16 text, not UTF-8'):
        read_campaign(path, format='damit')


# --- ALCDEF --------------------------------------------------------------------------------

def alcdef_block(rows, **meta):
    keys = {'OBJECTNUMBER': '99942', 'OBJECTNAME': 'Apophis', 'SESSIONDATE': '2020-05-31',
            'LTCAPP': 'NONE', 'REDUCEDMAGS': 'NONE', 'DIFFMAGS': 'TRUE',
            'STANDARD': 'INTERNAL', 'DELIMITER': 'PIPE', **meta}
    return '\n'.join(['STARTMETADATA', 'COMMENT=a test block'] + [f'{k}={v}' for k, v in
                                                                  keys.items()]
                     + ['ENDMETADATA'] + [f'DATA={row}' for row in rows] + ['ENDDATA'])


def test_an_alcdef_file_is_read_with_its_geometry_from_the_ephemeris(tmp_path, tables):
    path = tmp_path / 'apophis.alcdef'
    received = T0 + np.array([0.5, 0.51, 0.52])
    path.write_text(alcdef_block([f'{t:.6f}|15.100|0.010' for t in received]) + '\n'
                    + alcdef_block(['2459002.500000|14.000|0.020'], STANDARD='TRANSFORMED',
                                   DIFFMAGS='FALSE', LTCAPP='POINT', REDUCEDMAGS='AVERAGE',
                                   UCORMAG='-1.25', SESSIONDATE='2020-06-02') + '\n')
    c = read_campaign(path, ephemeris=tables, time_scale='tdb')
    assert c.light_time_corrected and c.free_offset == (True, False) and len(c) == 4
    # the first block: reception times -> emission times, by the quadratic's light time
    tau = np.array([light_time(t) for t in received])
    assert np.all(np.abs(tau * 86400.0 - 499.0 * np.linalg.norm(
        earth(received) - asteroid(received), axis=1)) < 2.0)        # ~ Delta / c
    np.testing.assert_allclose((c.jd_tdb[:3] - (received - tau)) * 86400.0, 0.0, atol=1e-4)
    np.testing.assert_allclose(c.sun[:3], -asteroid(received - tau), rtol=1e-10)
    np.testing.assert_allclose(c.observer[:3], earth(received) - asteroid(received - tau),
                               rtol=1e-10)
    np.testing.assert_allclose(c.sigma, [0.01] * 3 + [0.02])
    # the second: already corrected (LTCAPP=POINT), its reduction (UCORMAG) undone
    assert c.jd_tdb[3] == 2459002.5
    assert c.magnitude[3] == pytest.approx(14.0 + 1.25, abs=1e-12)
    # read in UTC (the default): every time 69.184 s later in TDB, then corrected
    u = read_campaign(path, ephemeris=tables)
    shifted = received + TDB_MINUS_UTC / 86400.0
    emitted = shifted - np.array([light_time(t) for t in shifted])
    np.testing.assert_allclose((u.jd_tdb[:3] - emitted) * 86400.0, 0.0, atol=2e-3)
    assert (u.jd_tdb[3] - c.jd_tdb[3]) * 86400.0 == pytest.approx(TDB_MINUS_UTC, abs=2e-3)
    # reception times asked for: the first block's times as in the file
    r = read_campaign(path, ephemeris=tables, time_scale='tdb', light_time=False)
    np.testing.assert_allclose(r.jd_tdb[:3], received, rtol=0, atol=1e-9)
    assert not r.light_time_corrected


def test_the_ephemeris_tables_may_point_either_way(tmp_path, tables):
    sun = horizons(tmp_path / 's2.txt', 'Sun (10)', '99942 Apophis (2004 MN4)',
                   lambda t: -asteroid(t), -V)
    observer = horizons(tmp_path / 'g2.txt', 'Earth (399)', '99942 Apophis (2004 MN4)',
                        lambda t: earth(t) - asteroid(t), W - V)
    path = tmp_path / 'a.alcdef'
    path.write_text(alcdef_block(['2459000.6|15|0.01', '2459000.7|15|0.01']))
    one = read_campaign(path, ephemeris=tables)
    other = read_campaign(path, ephemeris=(sun, observer))
    np.testing.assert_allclose(other.sun, one.sun, rtol=1e-12)
    np.testing.assert_allclose(other.observer, one.observer, rtol=1e-12)


@pytest.mark.parametrize('rows, line, match', [
    (['2459000.6|15.1|0.01', '2459000.7|15.1'], None, None),        # no MAGERR: sigma given
    (['2459000.6|15.1|0.01', '2459000.7|abc|0.01'], 13, r"MAG = 'abc' is not a number"),
    (['2459000.6|15.1|0.01', '2459000.7|nan|0.01'], 13, r'MAG = nan must be a finite'),
    (['2459000.6|15.1|0.01', '2459000.5|15.1|0.01'], 13, r'is before the previous point'),
    (['2459000.6|15.1|0.01', '2459010.7|15.1|0.01'], 13,
     r'the time JD 2459010.70\d+ \(TDB\) is outside the ephemeris \(2458998.5\d+ to 2459008.5'),
    (['2459000.6|15.1|0.01', '2459000.7|15.1|0'], 13, r'MAGERR = 0 must be in'),
])
def test_a_bad_alcdef_line_is_refused_with_its_number(tmp_path, tables, rows, line, match):
    path = tmp_path / 'a.alcdef'
    path.write_text(alcdef_block(rows))
    if match is None:
        c = read_campaign(path, ephemeris=tables)
        assert c.sigma.tolist() == [0.01, common.DEFAULT_SIGMA]
        return
    with pytest.raises(CampaignError, match=rf'^{path} line {line}: .*{match}'):
        read_campaign(path, ephemeris=tables, time_scale='tdb')


def test_alcdef_reads_tabs_and_refuses_a_data_line_without_its_magnitude(tmp_path, tables):
    path = tmp_path / 'a.alcdef'
    path.write_text(alcdef_block(['2459000.6\t15.5\t0.02\t1.3'], DELIMITER='TAB'))
    c = read_campaign(path, ephemeris=tables)
    assert c.magnitude.tolist() == [15.5] and c.sigma.tolist() == [0.02]
    path.write_text(alcdef_block(['2459000.6']))
    with pytest.raises(CampaignError, match=rf'^{path} line 12: 1 field: a DATA line gives '
                                            r'JD\|MAG\|MAGERR'):
        read_campaign(path, ephemeris=tables)


def test_a_time_whose_emission_falls_before_the_ephemeris_is_refused(tmp_path, tables):
    path = tmp_path / 'a.alcdef'
    path.write_text(alcdef_block(['2458998.5001|15|0.01']))          # tau ~ 0.008 d
    with pytest.raises(CampaignError, match=rf'^{path} line 12: the emission time '):
        read_campaign(path, ephemeris=tables, time_scale='tdb')


@pytest.mark.parametrize('text, match', [
    ('STARTMETADATA\nOBJECTNUMBER=1\nENDMETADATA\nDATA=2459000.6|15|0.01\n',
     r' line 4: the block of line 1 has no ENDDATA'),
    ('DATA=2459000.6|15|0.01\n', r" line 1: 'DATA=2459000.6\|15\|0.01' outside a block"),
    ('STARTMETADATA\nLTCAPP=SOMETIMES\nENDMETADATA\nDATA=2459000.6|15|0.01\nENDDATA\n',
     r' line 1: LTCAPP=SOMETIMES not read'),
    ('STARTMETADATA\nOBJECTNUMBER=433\nENDMETADATA\nDATA=2459000.6|15|0.01\nENDDATA\n',
     r' line 1: OBJECTNUMBER=433 but the ephemeris is of 99942 Apophis'),
    ('STARTMETADATA\nREDUCEDMAGS=AVERAGE\nENDMETADATA\nDATA=2459000.6|15|0.01\nENDDATA\n',
     r' line 1: REDUCEDMAGS=AVERAGE without UCORMAG'),
])
def test_an_alcdef_file_out_of_shape_is_refused(tmp_path, tables, text, match):
    path = tmp_path / 'a.alcdef'
    path.write_text(text)
    with pytest.raises(CampaignError, match=f'^{path}{match}'):
        read_campaign(path, ephemeris=tables)


def test_alcdef_without_or_with_wrong_tables_is_refused(tmp_path, tables):
    path = tmp_path / 'a.alcdef'
    path.write_text(alcdef_block(['2459000.6|15|0.01']))
    with pytest.raises(CampaignError, match=rf'^{path}: ALCDEF gives no geometry'):
        read_campaign(path)
    equatorial = horizons(tmp_path / 'eq.txt', '99942 Apophis', 'Sun (10)', asteroid, V,
                          frame='ICRF')
    with pytest.raises(CampaignError, match=r'eq.txt: the table is not ecliptic'):
        read_campaign(path, ephemeris=(equatorial, tables[1]))
    broken = tables[0].read_text().splitlines()
    broken[9] = broken[9].replace(broken[9].split(',')[2], ' NaN', 1)
    (tmp_path / 'nan.txt').write_text('\n'.join(broken))
    with pytest.raises(CampaignError, match=r'nan.txt line 10: .NaN. is not a finite number'):
        read_campaign(path, ephemeris=(tmp_path / 'nan.txt', tables[1]))
    with pytest.raises(CampaignError, match=r'geo.txt: neither the target .* is the Sun'):
        read_campaign(path, ephemeris=(tables[1], tables[1]))
    with pytest.raises(CampaignError, match=r"sun.txt: the Sun is in the observer's table"):
        read_campaign(path, ephemeris=(tables[0], tables[0]))


# --- the project's CSV ---------------------------------------------------------------------

def csv_rows(times, geometry=True):
    out = []
    for k, t in enumerate(times):
        a, e = asteroid(t), earth(t)
        vectors = f',{-a[0]},{-a[1]},{-a[2]},{e[0] - a[0]},{e[1] - a[1]},{e[2] - a[2]}' \
            if geometry else ''
        out.append(f'{t:.6f},{15 + 0.1 * math.sin(k):.4f},0.01{vectors}\n')
    return ''.join(out)


#: two nights of 12 points, as the CSV writes them (6 decimals)
NIGHTS = np.round(np.concatenate([T0 + 0.5 + np.arange(12) / 96, T0 + 1.5 + np.arange(12) / 96]),
                  6)


def test_a_csv_with_vectors_is_read_by_nights(tmp_path):
    path = tmp_path / 'obs.csv'
    path.write_text('jd_tdb,mag,err,sun_x,sun_y,sun_z,obs_x,obs_y,obs_z\n' + csv_rows(NIGHTS))
    c = read_campaign(path, times_corrected=True)
    assert len(c) == 24 and c.block_names == ('obs.csv night 1', 'obs.csv night 2')
    assert c.free_offset == (True, True) and c.block.tolist() == [0] * 12 + [1] * 12
    np.testing.assert_allclose(c.jd_tdb, NIGHTS, rtol=0, atol=1e-9)
    np.testing.assert_allclose(c.sun, -asteroid(NIGHTS), rtol=1e-12)
    # reception times (the default) corrected once, by the file's own distances
    r = read_campaign(path)
    delta = np.linalg.norm(earth(NIGHTS) - asteroid(NIGHTS), axis=1)
    np.testing.assert_allclose((NIGHTS - r.jd_tdb) * 86400.0, 499.00478 * delta, rtol=0,
                               atol=1e-4)                  # a float64 JD holds ~40 us
    assert read_campaign(path, calibrated=True).free_offset == (False, False)


def test_a_csv_without_vectors_takes_the_ephemeris(tmp_path, tables):
    path = tmp_path / 'obs.csv'
    path.write_text('mjd_tdb,mag,err\n' + csv_rows(NIGHTS - 2400000.5, geometry=False)
                    .replace('\n', '\n', 1))
    c = read_campaign(path, ephemeris=tables)
    tau = np.array([light_time(t) for t in NIGHTS])
    np.testing.assert_allclose((c.jd_tdb - (NIGHTS - tau)) * 86400.0, 0.0, atol=2e-4)
    with pytest.raises(CampaignError, match=rf'^{path}: no geometry: give the vectors'):
        read_campaign(path)


@pytest.mark.parametrize('header, match', [
    ('hjd,mag,err', r"the time column 'hjd' is not read for the inversion"),
    ('time_h,mag,err', r"the time column 'time_h' is not read"),
])
def test_a_csv_with_times_the_inversion_cannot_use_is_refused(tmp_path, header, match):
    path = tmp_path / 'obs.csv'
    path.write_text(header + '\n' + csv_rows(NIGHTS, geometry=False))
    with pytest.raises(CampaignError, match=f'^{path}: {match}'):
        read_campaign(path)


def test_a_bad_csv_line_is_refused_with_its_number(tmp_path):
    path = tmp_path / 'obs.csv'
    text = csv_rows(NIGHTS).splitlines(keepends=True)
    text[4] = text[4].replace(',0.01,', ',nan,')
    path.write_text('jd,mag,err,sun_x,sun_y,sun_z,obs_x,obs_y,obs_z\n' + ''.join(text))
    with pytest.raises(CampaignError, match=rf'^{path} line 6: err = nan must be finite'):
        read_campaign(path)
    path.write_text('jd,mag,err,sun_x,sun_y,sun_z,obs_x,obs_y\n' + csv_rows(NIGHTS))
    with pytest.raises(CampaignError, match=r'without \[.obs_z.\]: give all of'):
        read_campaign(path)


def test_analyze_searches_reduced_magnitudes_when_the_csv_has_geometry(tmp_path, capsys):
    from tumble_ros.analysis.cli import command
    from tumble_ros.analysis.photometry_file import read_photometry, reduced_photometry
    t = np.arange(60) / 24.0
    r, delta = 1.1 + 0.2 * t, 0.2 + 0.3 * t
    mag = 15.0 + 0.3 * np.sin(2 * np.pi * t * 24.0 / 5.0) + 5 * np.log10(r * delta)
    path = tmp_path / 'obs.csv'
    path.write_text('jd,mag,r,delta\n' + ''.join(
        f'{T0 + a:.6f},{m:.6f},{b:.6f},{c:.6f}\n' for a, m, b, c in zip(t, mag, r, delta)))
    data = read_photometry(path)
    reduced, note = reduced_photometry(data)
    np.testing.assert_allclose(reduced, mag - 5 * np.log10(r * delta), atol=2e-6)
    assert note.startswith('reduced magnitudes: m - 5 log10(r delta)')
    assert command(['--photometry', str(path), '--period-range', '1', '20']) == 0
    out = capsys.readouterr().out
    assert 'searched: reduced magnitudes: m - 5 log10(r delta)' in out, out


# --- recordings, the registry, merging -----------------------------------------------------

def test_a_recordings_lightcurve_is_read_in_its_frame(tmp_path):
    from tumble_ros.core import Scenario
    from tumble_ros.runs.offline import record_offline
    params = {'duration': 0.02, 'output_interval': 0.001, 'lightcurve.law': 'lambert',
              'lightcurve.observer': [0.0, 0.6, 0.8]}
    path = tmp_path / 'run.mcap'
    record_offline(Scenario.from_parameters(params), path, markers=False)
    with pytest.raises(CampaignError, match=r"run.mcap: the run's frame is its orbital frame"):
        read_campaign(path)
    c = read_campaign(path, orbital_frame_is_ecliptic=True, epoch_jd=T0)
    from tumble_ros.analysis.recording import load_recording
    rec = load_recording(path)
    lit = np.isfinite(rec.lightcurve[:, 1]) & (rec.lightcurve[:, 0] > 0)
    assert len(c) == lit.sum() > 10
    np.testing.assert_allclose(c.magnitude, rec.lightcurve[lit, 1])
    np.testing.assert_allclose(c.phase_angle(), rec.lightcurve[lit, 2], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(c.observer, axis=1) * 499.00478,
                               rec.lightcurve[lit, 7], rtol=1e-6)
    np.testing.assert_allclose(c.jd_tdb, T0 + 365.25 * rec.lightcurve_t[lit], rtol=0,
                               atol=1e-9)


def test_the_format_is_recognised_and_files_merged(tmp_path):
    damit = tmp_path / 'lc.txt'
    damit.write_text(damit_text((0, damit_rows(T0, 3))))
    csv = tmp_path / 'obs.csv'
    csv.write_text('jd,mag,err,sun_x,sun_y,sun_z,obs_x,obs_y,obs_z\n' + csv_rows(NIGHTS))
    both = read_campaign([damit, csv], times_corrected=True)
    assert len(both) == 27 and len(both.block_names) == 3
    assert both.block_names[0].startswith('lc.txt') and both.source.count(' + ') == 1
    other = tmp_path / 'x.dat'
    other.write_text('hello world\n')
    with pytest.raises(CampaignError, match=r'x.dat: cannot tell its format: name it'):
        read_campaign(other)
    with pytest.raises(CampaignError, match=r"format 'fits' not read"):
        read_campaign(damit, format='fits')

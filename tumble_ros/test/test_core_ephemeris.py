"""
Tabulated ephemerides (core/torques/ephemeris.py): reading, interpolation order, a flyby.

The interpolant is checked against the exact Kepler hyperbola it samples (positions, and
positions with velocities): its error converges at the order of a quintic (h^6); the reader
against tables written here in the JPL Horizons vector-table layouts (text, labelled or not,
and CSV) and as a plain t, x, y, z table; the torque through the compiled evaluation against the
same perturber on its Kepler orbit; and the Apophis flyby simulated through a Horizons table
against the Kepler-orbit run of config/apophis_2029.yaml.
"""
from pathlib import Path

import numpy as np
import pytest

from tumble_ros.core import load_scenario, parse_scenario, ScenarioError, simulate
from tumble_ros.core.model.units import HOURS_PER_YEAR, KM_PER_AU
from tumble_ros.core.torques.ephemeris import Ephemeris, read_ephemeris
from tumble_ros.core.torques.perturbers import Perturber

CONFIG = Path(__file__).resolve().parents[1] / 'config'
APOPHIS = load_scenario(CONFIG / 'apophis_2029.yaml')
ORBIT = APOPHIS.orbit
#: The Julian date (TDB) of the Apophis scenario's t = 0: 72 h before the perigee of
#: 2029-04-13 21:46 TDB (JD 2462240.4069).
EPOCH_JD = 2462240.406944 - 3.0
#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 28


def sampled(spacing_h: float, velocities: bool, start_h: float = 0.0,
            end_h: float = 144.0) -> Ephemeris:
    """Return the Apophis flyby's hyperbola sampled every ``spacing_h`` hours."""
    t = np.arange(start_h / spacing_h, end_h / spacing_h + 0.5) * spacing_h / HOURS_PER_YEAR
    v = ORBIT.velocity(t) if velocities else np.empty((0, 3))
    return Ephemeris(tuple(t), tuple(map(tuple, ORBIT.position(t))), tuple(map(tuple, v)))


@pytest.mark.parametrize('velocities', [False, True])
def test_the_interpolant_converges_to_the_orbit_at_the_sixth_order(velocities):
    """Max relative position error over the flyby, knots every 1, 1/2, 1/4, 1/8 h."""
    t = np.linspace(0.0, 144.0 / HOURS_PER_YEAR, 3001)
    exact = ORBIT.position(t)
    distance = np.linalg.norm(exact, axis=1)
    errors = []
    for spacing in (1.0, 0.5, 0.25, 0.125):
        error = np.linalg.norm(sampled(spacing, velocities).position(t) - exact, axis=1)
        errors.append(float(np.max(error / distance)))
    order = np.log2(errors[0] / errors[-1]) / 3.0
    # measured 2026-12-04: 6.85 (positions), 6.47 (with velocities); errors 2.9e-4 -> 1.9e-10
    # and 3.5e-5 -> 5.1e-11 (a quintic: h^6)
    assert 5.5 < order < 7.5, errors
    assert errors[-1] < 3e-10
    # and at the knots themselves the table is reproduced to rounding
    table = sampled(0.25, velocities)
    np.testing.assert_allclose(table.position(table.times), table.positions, rtol=1e-13)


def test_the_compiled_torque_of_an_ephemeris_is_the_kepler_orbits():
    rng = np.random.default_rng(SEED)
    inertia = (0.64, 0.97, 1.0)
    kepler = Perturber('earth', ORBIT).torque_component(inertia)
    table = Perturber('earth', sampled(5.0 / 60.0, True), gm=ORBIT.gm).torque_component(inertia)
    for t in rng.uniform(0.0, 144.0 / HOURS_PER_YEAR, 20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        expected = kepler.torque(t, q)
        np.testing.assert_allclose(table.torque(t, q), expected, rtol=0,
                                   atol=1e-10 * np.linalg.norm(expected))


def horizons_text(ephemeris: Ephemeris, *, csv: bool, labels: bool, units: str = 'KM-S') -> str:
    """Return the table in the layout of a Horizons vector table (VEC_TABLE 3, with LT RG RR)."""
    km, seconds = {'KM-S': (1.0, 1.0), 'AU-D': (KM_PER_AU, 86400.0)}[units]
    header = ['*' * 79, 'Ephemeris / WWW_USER Fri Dec  4 12:00:00 2026 Pasadena, USA / Horizons',
              'Target body name: Earth (399)                     {source: DE441}',
              'Center body name: 99942 Apophis (2004 MN4)        {source: JPL#220}',
              f'Output units    : {units}', 'Output type     : GEOMETRIC cartesian states',
              'Reference frame : Ecliptic of J2000.0', '*' * 79,
              'JDTDB, Calendar Date (TDB), X, Y, Z, VX, VY, VZ, LT, RG, RR,' if csv else
              '            JDTDB,            Calendar Date (TDB)', '*' * 79, '$$SOE']
    rows = []
    for t, x, v in zip(ephemeris.times, ephemeris.positions, ephemeris.velocities):
        jd = EPOCH_JD + t * 365.25
        x = np.asarray(x) / km
        v = np.asarray(v) / (km / seconds)
        extra = (0.1, float(np.linalg.norm(x)), 0.0)
        if csv:
            numbers = ', '.join(f'{c:.16E}' for c in (*x, *v, *extra))
            rows.append(f'{jd:.9f}, A.D. 2029-Apr-11 00:00:00.0000, {numbers},')
        elif labels:
            rows += [f'{jd:.9f} = A.D. 2029-Apr-11 00:00:00.0000 TDB',
                     ' X ={:.16E} Y ={:.16E} Z ={:.16E}'.format(*x),
                     ' VX={:.16E} VY={:.16E} VZ={:.16E}'.format(*v),
                     ' LT={:.16E} RG={:.16E} RR={:.16E}'.format(*extra)]
        else:
            rows += [f'{jd:.9f} = A.D. 2029-Apr-11 00:00:00.0000 TDB',
                     ' '.join(f'{c:.16E}' for c in x), ' '.join(f'{c:.16E}' for c in v),
                     ' '.join(f'{c:.16E}' for c in extra)]
    return '\n'.join(header + rows + ['$$EOE', '*' * 79, 'Coordinate system description:', ''])


@pytest.mark.parametrize('csv, labels, units', [(True, False, 'KM-S'), (False, True, 'KM-S'),
                                                (False, False, 'AU-D')])
def test_a_horizons_vector_table_is_read(tmp_path, csv, labels, units):
    table = sampled(1.0, True, end_h=12.0)
    path = tmp_path / 'earth.txt'
    path.write_text(horizons_text(table, csv=csv, labels=labels, units=units))
    read = read_ephemeris(path, epoch_jd=EPOCH_JD)
    # the times pass through a Julian date of 9 decimals (86 us): 1e-9 d / 365.25 ~ 3e-12 yr
    np.testing.assert_allclose(read.times, table.times, rtol=0, atol=5e-12)
    np.testing.assert_allclose(read.positions, table.positions, rtol=1e-14)
    np.testing.assert_allclose(read.velocities, table.velocities, rtol=1e-14)
    assert read.source == str(path) and read.epoch_jd == EPOCH_JD


def test_a_plain_table_is_read_in_the_scenarios_time_unit(tmp_path):
    table = sampled(1.0, False, end_h=12.0)
    hours = np.asarray(table.times) * HOURS_PER_YEAR
    rows = zip(hours.tolist(), table.positions)
    lines = ['t, x, y, z   # hours, km'] + [f'{h!r}, {x!r}, {y!r}, {z!r}' for h, (x, y, z) in rows]
    path = tmp_path / 'earth.csv'
    path.write_text('\n'.join(lines) + '\n')
    read = read_ephemeris(path, time_unit='h')
    np.testing.assert_allclose(read.times, table.times, rtol=1e-15)
    assert read.positions == table.positions and read.velocities == ()


@pytest.mark.parametrize('text, match', [
    ('$$SOE\n2462240.5 = A.D.\n1 2 3\n', r'one \$\$SOE and one \$\$EOE'),
    ('t,x,y,z\n0,1,2,3\n1,1,2,3\n', r'times: must have 6 to'),
    ('0,1,2,3\n1,1,2\n2,1,2,3\n', r'bad\.csv:2: the row has 3 numbers, the first row \(line 1\) 4'),
    ('\n'.join(f'{t},1,2,3' for t in (0, 1, 2, 2, 3, 4)), r'strictly increasing, got 2\.0'),
    ('\n'.join(f'{t},0,0,0' for t in range(6)), r'distance 0'),
    ('0,1,2,3\n1,1,2,3\nabc\n', r"bad\.csv:3: 'abc' is not a finite number"),
])
def test_a_bad_table_is_refused_naming_the_file_and_what_is_wrong(tmp_path, text, match):
    path = tmp_path / 'bad.csv'
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_ephemeris(path, epoch_jd=EPOCH_JD)


def test_a_horizons_table_needs_its_epoch(tmp_path):
    path = tmp_path / 'earth.txt'
    path.write_text(horizons_text(sampled(1.0, True, end_h=12.0), csv=True, labels=False))
    with pytest.raises(ValueError, match=r'epoch_jd: a Horizons table needs the Julian date'):
        read_ephemeris(path)


def apophis_through(path: Path, time_unit: str = '') -> str:
    """Return config/apophis_2029.yaml with its orbit replaced by the Earth of ``path``."""
    text = (CONFIG / 'apophis_2029.yaml').read_text()
    orbit = text.index('    orbit:')
    epoch = f'epoch_jd: {EPOCH_JD!r}' if not time_unit else f'ephemeris_time_unit: {time_unit}'
    return text[:orbit] + f"""    perturbers:
      names: [earth]
      earth:
        kind: ephemeris
        gm: {ORBIT.gm!r}
        ephemeris_file: {path}
        {epoch}
"""


def plain_text(ephemeris: Ephemeris) -> str:
    """Return the table as plain ``t, x, y, z, vx, vy, vz`` rows, t in hours."""
    hours = (np.asarray(ephemeris.times) * HOURS_PER_YEAR).tolist()
    return '\n'.join(['t, x, y, z, vx, vy, vz'] + [
        ', '.join(repr(float(c)) for c in (h, *x, *v))
        for h, x, v in zip(hours, ephemeris.positions, ephemeris.velocities)]) + '\n'


@pytest.mark.parametrize('layout, bound', [('horizons', 5e-9), ('plain', 2e-11)])
def test_the_apophis_flyby_through_a_table_is_the_kepler_orbits(tmp_path, layout, bound):
    """
    The same flyby, the Earth from a 5-minute table instead of the hyperbola.

    Measured 2026-12-04, max |omega - omega_kepler| / |omega| over the run: plain table (full
    precision) 2.4e-12 at 5 min, 6.5e-11 at 10 min, 3.2e-9 at 20 min; a Horizons table 2.4e-9
    at 5 min, limited by its Julian dates printed to 1e-9 d (86 us: the Earth moves 0.3 m
    meanwhile). The flyby itself changes omega by 59 %.
    """
    table = sampled(5.0 / 60.0, True, start_h=-1.0, end_h=145.0)
    text = (horizons_text(table, csv=True, labels=False) if layout == 'horizons'
            else plain_text(table))
    (tmp_path / 'earth.txt').write_text(text)
    scenario_file = tmp_path / 'apophis_table.yaml'
    scenario_file.write_text(apophis_through(Path('earth.txt'),
                                             '' if layout == 'horizons' else 'h'))
    through = load_scenario(scenario_file)     # the table found beside the params file
    assert through.orbit is None and isinstance(through.perturbers[0].source, Ephemeris)
    kepler, table_run = simulate(APOPHIS), simulate(through)
    norm = np.linalg.norm(kepler.omega, axis=1)
    assert np.max(np.linalg.norm(table_run.omega - kepler.omega, axis=1) / norm) < bound
    free = simulate(APOPHIS.replace(orbit=None))
    assert np.max(np.linalg.norm(free.omega - kepler.omega, axis=1) / norm) > 0.1


def test_a_table_that_does_not_cover_the_run_is_refused(tmp_path):
    table = sampled(1.0, True, end_h=100.0)
    (tmp_path / 'earth.txt').write_text(horizons_text(table, csv=True, labels=False))
    with pytest.raises(ScenarioError, match=r'^perturbers\.earth\.ephemeris_file: the table must '
                                            r'cover the run, \[0, 0\.0164'):
        parse_scenario(apophis_through(tmp_path / 'earth.txt'))
    with pytest.raises(ScenarioError, match=r'^perturbers\.earth\.ephemeris_file: no such file'):
        parse_scenario(apophis_through(Path('nowhere.txt')))

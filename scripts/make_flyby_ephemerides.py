#!/usr/bin/env python3
"""
Write the Moon's and the Sun's ephemerides relative to Apophis for its 2029 flyby (a model).

    scripts/env.sh python scripts/make_flyby_ephemerides.py [--out-dir DIR]

writes ``apophis_2029_moon.txt`` and ``apophis_2029_sun.txt`` (to ``tumble_ros/config/ephemerides``
by default): the Moon and the Sun seen from
(99942) Apophis, ecliptic J2000 [km, km/s], every 15 minutes from 1 h before the run of
``config/apophis_2029.yaml`` starts (2029-04-10 21:46 TDB, JD 2462237.406944444) to 1 h after it
ends (144 h later), in the JPL Horizons vector-table format that ``core/torques/ephemeris.py``
reads. They are the perturbers of ``config/apophis_2029_moon_sun.yaml``.

**A model, not JPL's ephemeris.** No network here, so no Horizons: each position is

    (body relative to Apophis) = (body relative to the Earth) + (the Earth relative to Apophis)

with (1) the body relative to the Earth from astropy's ``'builtin'`` solar-system ephemeris,
which needs no download: ERFA's ``epv00`` for the Earth about the Sun (Sun: heliocentric Earth
negated; ERFA states errors of a few km against DE405 over 1900-2100) and ``moon98`` for the
Moon (Meeus' series; ERFA states RMS errors of 6.1 km, worst 31.7 km, in position against
ELP/MPP02 over 1950-2100), both geometric, in the GCRS (the J2000 mean equator to 23 mas),
turned to ecliptic J2000 by the obliquity 84381.448 arcsec (Horizons' ``ECLIPTIC``/``J2000``
frame, the frame of the scenario); and (2) the Earth relative to Apophis from the scenario's
own hyperbola (``orbit.*`` of apophis_2029.yaml: ``KeplerOrbit.position``/``velocity``), so
that the three bodies move consistently with the Earth the simulator uses. Against JPL's
Apophis-centred vectors the tables then differ by the hyperbola's own error (a two-body
geocentric orbit; the published perigee differs by ~300 km between solutions) plus the series'
few to 30 km: ~1e-3 of the Moon's distance (~3e-3 of its tidal torque), ~1e-6 of the Sun's.
The script is deterministic: ``test_scenarios.py`` writes the tables again and compares them
with the shipped ones.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path
import sys

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'tumble_ros'))

from tumble_ros.core import load_scenario  # noqa: E402
from tumble_ros.core.units import HOURS_PER_YEAR  # noqa: E402

#: The run's t = 0: 2029-04-10 21:46 TDB (72 h before the perigee of 2029-04-13 21:46 TDB).
EPOCH_JD = 2462237.406944444
#: The scenario whose hyperbola places the Earth.
SCENARIO = ROOT / 'tumble_ros' / 'config' / 'apophis_2029.yaml'
#: Knot spacing [h] and the span [h] covered around the run (0 to 144 h).
STEP_HOURS = 0.25
SPAN_HOURS = (-1.0, 145.0)
#: Obliquity of the ecliptic J2000 [arcsec] (Horizons' ecliptic frame; IAU 1976).
OBLIQUITY_ARCSEC = 84381.448
BODIES = {'moon': 'the Moon', 'sun': 'the Sun'}


def geocentric(body: str, jd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (position [km], velocity [km/s]) of ``body`` from the Earth, GCRS axes (ERFA)."""
    from astropy.coordinates import get_body_barycentric_posvel, solar_system_ephemeris
    from astropy.time import Time

    times = Time(jd, format='jd', scale='tdb')
    with solar_system_ephemeris.set('builtin'):
        body_p, body_v = get_body_barycentric_posvel(body, times)
        earth_p, earth_v = get_body_barycentric_posvel('earth', times)
    position = (body_p - earth_p).xyz.to_value('km').T
    velocity = (body_v - earth_v).xyz.to_value('km/s').T
    return position, velocity


def to_ecliptic(vectors: np.ndarray) -> np.ndarray:
    """Return (n, 3) equatorial vectors turned to ecliptic J2000 (about X by the obliquity)."""
    eps = math.radians(OBLIQUITY_ARCSEC / 3600.0)
    c, s = math.cos(eps), math.sin(eps)
    x, y, z = vectors[:, 0], vectors[:, 1], vectors[:, 2]
    return np.column_stack([x, c * y + s * z, -s * y + c * z])


def relative_to_apophis(body: str, hours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (position [km], velocity [km/s]) of ``body`` from Apophis, ecliptic J2000."""
    orbit = load_scenario(SCENARIO).orbit
    assert orbit is not None
    years = hours / HOURS_PER_YEAR
    position, velocity = geocentric(body, EPOCH_JD + hours / 24.0)
    return (to_ecliptic(position) + orbit.position(years),
            to_ecliptic(velocity) + orbit.velocity(years))


def table_text(body: str) -> str:
    """Return the Horizons-format table of ``body`` relative to Apophis (module docstring)."""
    count = int(round((SPAN_HOURS[1] - SPAN_HOURS[0]) / STEP_HOURS)) + 1
    hours = SPAN_HOURS[0] + STEP_HOURS * np.arange(count)
    position, velocity = relative_to_apophis(body, hours)
    distance = np.linalg.norm(position, axis=1)
    lines = [
        '*' * 79,
        f"A MODEL in the JPL Horizons vector-table format, NOT JPL's ephemeris: {BODIES[body]}",
        'relative to (99942) Apophis, written by scripts/make_flyby_ephemerides.py (its docstring',
        "states the model and its accuracy): the body from the Earth by astropy's 'builtin'",
        'ephemeris (ERFA epv00 / moon98), plus the Earth from Apophis on the hyperbola of',
        'config/apophis_2029.yaml. Accuracy against JPL: ~1e-3 of the distance (Moon), ~1e-6',
        '(Sun).',
        f'Center body name: (99942) Apophis, as modelled; target: {BODIES[body]}',
        'Reference frame : Ecliptic of J2000.0 (obliquity 84381.448 arcsec)',
        f'Step-size       : {STEP_HOURS * 60:g} minutes; closest {distance.min():.6e} km',
        'Output units    : KM-S',
        '*' * 79,
        '$$SOE',
    ]
    for k, h in enumerate(hours):
        jd = EPOCH_JD + h / 24.0
        x, y, z = position[k]
        vx, vy, vz = velocity[k]
        lines.append(f"{jd:.9f} = TDB (t = {h:+.2f} h from the run's start)")
        lines.append(f' X ={x: .15E} Y ={y: .15E} Z ={z: .15E}')
        lines.append(f' VX={vx: .15E} VY={vy: .15E} VZ={vz: .15E}')
    lines.append('$$EOE')
    return '\n'.join(lines) + '\n'


def main(argv: list[str] | None = None) -> int:
    """Write the tables to ``--out-dir``."""
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n', 1)[0])
    parser.add_argument('--out-dir', type=Path,
                        default=ROOT / 'tumble_ros' / 'config' / 'ephemerides')
    args = parser.parse_args(argv)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    for body in BODIES:
        path = args.out_dir / f'apophis_2029_{body}.txt'
        path.write_text(table_text(body), encoding='utf-8')
        print(f'{path}: written')
    return 0


if __name__ == '__main__':
    sys.exit(main())

"""
The Sun's and the observer's vectors from JPL Horizons tables, with the light-time correction.

A user gives two Horizons vector tables (``TABLE_TYPE = VECTORS``, ``REF_PLANE = ECLIPTIC``,
``REF_SYSTEM = J2000``, geometric states ``VEC_CORR = NONE``, text or CSV, any of the
``OUT_UNITS`` the project reads), covering the observations:

* the asteroid about the Sun: ``COMMAND`` the asteroid, ``CENTER = '@10'`` (or the Sun about
  the asteroid, ``COMMAND = '10'``, ``CENTER = '@2099942'``);
* the asteroid about the observer: ``COMMAND`` the asteroid, ``CENTER`` the observatory
  (``'500@399'`` the geocentre, an observatory code for the topocentre), or the observer about
  the asteroid.

Each is read by the project's one Horizons reader (``core.torques.ephemeris``: its parser, its
bounds :data:`~tumble_ros.core.torques.ephemeris.MAX_KNOTS` and
:data:`~tumble_ros.core.torques.ephemeris.MAX_EPHEMERIS_BYTES`, its refusal of a table too
sparse to interpolate) and interpolated by its quintic. Which way a table points is read from
its header (``Target body name``, ``Center body name``); a table without them is taken as the
asteroid about the Sun / the observer. A header whose frame lines (``Reference frame``,
``Reference plane``, ``Coordinate systm``) do not say ecliptic is refused: the Campaign is
ecliptic J2000.

Light time (:meth:`HorizonsGeometry.at`): with S(t) the asteroid -> Sun and B(t) the asteroid
-> observer vectors at one instant t, the light the observer receives at t_r left the asteroid
at t_e = t_r - |D| / c, D = B(t_r) - S(t_r) + S(t_e) (the observer at t_r seen from the
asteroid at t_e), solved by iteration (each step gains a factor v / c ~ 1e-4). The campaign's
vectors are then S(t_e) and D. A time already light-time corrected (DAMIT, ALCDEF's LTCAPP) is
t_e: t_r is solved the same way, never corrected twice.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import re

import numpy as np

from tumble_ros.core.torques.ephemeris import (DAYS_PER_YEAR, Ephemeris, MAX_EPHEMERIS_BYTES,
                                               parse_ephemeris)
from tumble_ros.core.units import KM_PER_AU

from .common import fail, LIGHT_DAYS_PER_AU, read_text

__all__ = ['HorizonsGeometry', 'EPOCH_JD', 'LIGHT_TIME_ITERATIONS']

#: the Julian date (TDB) the tables' times are counted from (J2000.0) [d]
EPOCH_JD = 2451545.0
#: iterations of the light-time equation: the first is good to v/c ~ 1e-4 of tau, each next
#: gains 1e-4: three leave < 1e-9 s
LIGHT_TIME_ITERATIONS = 3
_FRAME_LINE = re.compile(r'^\s*(Reference frame|Reference plane|Coordinate systm)\s*:(.*)$',
                         re.IGNORECASE | re.MULTILINE)


def _body(header: str, which: str) -> str:
    """Return the header's ``<which> body name`` ('Target', 'Center'), its source note dropped."""
    found = re.search(rf'^\s*{which} body name\s*:\s*(.*)$', header, re.MULTILINE)
    return found.group(1).split('{')[0].strip() if found else ''


def _is_sun(name: str) -> bool:
    return bool(re.match(r'Sun\b', name))


@dataclass(frozen=True)
class _Table:
    """One Horizons table: the Ephemeris (km, yr since EPOCH_JD), its sign, its bodies."""

    path: str
    ephemeris: Ephemeris
    target: str
    center: str
    coefficients: np.ndarray = field(repr=False, compare=False)

    @classmethod
    def read(cls, path: str) -> '_Table':
        name = str(Path(path).resolve())
        text = read_text(Path(name), 'Horizons vector table', MAX_EPHEMERIS_BYTES,
                         'MAX_EPHEMERIS_BYTES')
        if '$$SOE' not in text:
            fail(name, None, 'not a JPL Horizons vector table (no $$SOE line): ask Horizons '
                 'for TABLE_TYPE = VECTORS')
        header = text[:text.index('$$SOE')]
        frames = _FRAME_LINE.findall(header)
        if frames and not any('ecliptic' in value.lower() for _, value in frames):
            said = '; '.join(f'{key}:{value.rstrip()}' for key, value in frames)
            fail(name, None, f'the table is not ecliptic ({said}): '
                 "ask Horizons for REF_PLANE = 'ECLIPTIC' (the campaign's frame is ecliptic "
                 'J2000)')
        try:
            ephemeris = parse_ephemeris(text, name, epoch_jd=EPOCH_JD)
        except ValueError as err:                  # 'NAME:LINE: why' or 'NAME: why' or 'why'
            said = str(err)
            line = re.match(rf'{re.escape(name)}:(\d+): (.*)$', said, re.DOTALL)
            if line:
                fail(name, int(line.group(1)), line.group(2))
            fail(name, None, said[len(name) + 2:] if said.startswith(f'{name}: ') else said)
        return cls(name, ephemeris, _body(header, 'Target'), _body(header, 'Center'),
                   ephemeris.coefficients())

    def span_jd(self) -> tuple[float, float]:
        """Return the first and last times of the table [JD TDB]."""
        return (EPOCH_JD + self.ephemeris.start * DAYS_PER_YEAR,
                EPOCH_JD + self.ephemeris.end * DAYS_PER_YEAR)

    def position_au(self, jd: np.ndarray) -> np.ndarray:
        """Return the vector [au] at ``jd`` [JD TDB] (n, 3): the Ephemeris's own quintic."""
        knots = np.asarray(self.ephemeris.times)
        t = (np.asarray(jd, dtype=float) - EPOCH_JD) / DAYS_PER_YEAR
        k = np.clip(np.searchsorted(knots, t, side='right') - 1, 0, knots.size - 2)
        s = (t - 0.5 * (knots[k] + knots[k + 1]))[:, None]
        c = self.coefficients[k]                                     # (n, 3, 6)
        out = c[:, :, -1]
        for p in range(c.shape[2] - 2, -1, -1):
            out = out * s + c[:, :, p]
        return out / KM_PER_AU


@dataclass(frozen=True)
class HorizonsGeometry:
    """
    The asteroid -> Sun and asteroid -> observer vectors from two Horizons tables (module doc).

    ``sun``, ``observer`` the tables; ``sun_sign``, ``observer_sign`` +1 when the table gives
    the vector from the asteroid, -1 when it gives the asteroid about the Sun / the observer;
    ``asteroid`` its name in the headers ('' when they name none).
    """

    sun: _Table
    observer: _Table
    sun_sign: float
    observer_sign: float
    asteroid: str

    @classmethod
    def read(cls, sun_path: str, observer_path: str) -> 'HorizonsGeometry':
        """Read the two tables (asteroid about the Sun, about the observer); refuse a mix-up."""
        sun, observer = _Table.read(sun_path), _Table.read(observer_path)
        if _is_sun(sun.target):
            sun_sign, asteroid = 1.0, sun.center
        elif _is_sun(sun.center) or not (sun.target or sun.center):
            sun_sign, asteroid = -1.0, sun.target
        else:
            fail(sun.path, None, f'neither the target ({sun.target}) nor the centre '
                 f'({sun.center}) is the Sun: the first table is the asteroid about the Sun '
                 "(CENTER = '@10')")
        if _is_sun(observer.center) or _is_sun(observer.target):
            fail(observer.path, None, "the Sun is in the observer's table: the second table is "
                 "the asteroid about the observer (CENTER = '500@399' or an observatory code)")
        if asteroid and observer.center == asteroid:
            observer_sign = 1.0
        elif not asteroid or observer.target == asteroid or not observer.target:
            observer_sign = -1.0
        else:
            fail(observer.path, None, f'the table is of {observer.target} about '
                 f"{observer.center}, the Sun's table of {asteroid}: give both of one asteroid")
        return cls(sun, observer, sun_sign, observer_sign, asteroid)

    @property
    def sources(self) -> str:
        """Return the two tables' paths."""
        return f'{self.sun.path} + {self.observer.path}'

    def span_jd(self) -> tuple[float, float]:
        """Return the times both tables cover [JD TDB]."""
        a, b = self.sun.span_jd(), self.observer.span_jd()
        return max(a[0], b[0]), min(a[1], b[1])

    def _check(self, jd: np.ndarray, path: Path, lines: np.ndarray, what: str) -> None:
        start, end = self.span_jd()
        outside = (jd < start) | (jd > end)
        if np.any(outside):
            k = int(np.argmax(outside))
            fail(path, int(lines[k]), f'{what} JD {jd[k]:.6f} (TDB) is outside the ephemeris '
                 f'({start:.6f} to {end:.6f}, {self.sources}): give tables that cover the '
                 'observations')

    def at(self, jd: np.ndarray, corrected: np.ndarray, light_time: bool, path: Path,
           lines: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Return (times [JD TDB], asteroid -> Sun, asteroid -> observer [au]) at the points.

        ``jd`` [JD TDB] the points' times, emission times where ``corrected`` (bool, per
        point), reception times elsewhere; the times returned are the emission times with
        ``light_time``, else the reception times. ``lines`` the points' lines in ``path``: a
        time outside the tables (or whose light-time partner is) is refused with its line.
        """
        jd = np.asarray(jd, dtype=float)
        corrected = np.asarray(corrected, dtype=bool)
        self._check(jd, path, lines, 'the time')
        sun = lambda t: self.sun_sign * self.sun.position_au(t)                 # noqa: E731
        seen = lambda t: self.observer_sign * self.observer.position_au(t)      # noqa: E731
        emission, reception = jd.copy(), jd.copy()
        start, end = self.span_jd()
        for _ in range(LIGHT_TIME_ITERATIONS):
            d = seen(np.clip(reception, start, end)) - sun(np.clip(reception, start, end)) \
                + sun(np.clip(emission, start, end))
            tau = np.linalg.norm(d, axis=1) * LIGHT_DAYS_PER_AU
            emission = np.where(corrected, jd, jd - tau)
            reception = np.where(corrected, jd + tau, jd)
        self._check(emission, path, lines, 'the emission time (light-time corrected)')
        self._check(reception, path, lines, 'the reception time')
        vector_sun = sun(emission)
        vector_observer = seen(reception) - sun(reception) + vector_sun
        return (emission if light_time else reception), vector_sun, vector_observer

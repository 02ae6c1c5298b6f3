"""
Tabulated ephemerides of a perturber: read, validated, interpolated in the integrators' loops.

An :class:`Ephemeris` is the perturber's position relative to the asteroid, in the scenario's
orbital (inertial) frame [km], at knots t_k [yr of the scenario's time base, t = 0 its start],
optionally with the velocities [km/s]. Between the knots it is a piecewise quintic, precomputed
once in numpy and evaluated by compiled code (:func:`ephemeris_position`: a binary search on
the knots, then Horner's rule):

* positions only: the quintic interpolating spline (scipy ``make_interp_spline``, k = 5, C4);
* positions and velocities: the quintic Hermite interpolant of positions, velocities and the
  accelerations of the quintic spline through the velocities (C2).

Both converge as h^6 in the knot spacing h (measured: tests/test_core_ephemeris.py, a Kepler
flyby sampled at spacing h); a table at the spacing a user exports (minutes for a flyby) is
then exact to the integrators' tolerances (docs/physics.md, "Ephemerides").

Files (:func:`read_ephemeris`):

* a JPL Horizons vector table (``TABLE_TYPE = VECTORS``), text or ``CSV_FORMAT = YES``: a
  header, ``$$SOE``, records of the Julian date (TDB) then X Y Z [VX VY VZ ...], ``$$EOE``
  (labelled ``X = ...`` or not); units from the header's ``Output units`` (KM-S, KM-D, AU-D;
  KM-S when absent). The time mapping: t [yr] = (JD_TDB - epoch_jd) / 365.25, ``epoch_jd`` the
  Julian date (TDB) of the scenario's t = 0;
* a plain CSV/text table ``t, x, y, z [, vx, vy, vz]`` (comma or blank separated, lines with
  ``#`` comments and a non-numeric header line skipped): t in the scenario's ``time_unit``
  (converted to years by ``years_per_unit``), positions [km], velocities [km/s].

The positions must be the perturber's relative to the asteroid (Horizons: the asteroid as the
centre, ``CENTER = '@2099942'`` for Apophis, or the negated geocentric vectors of the asteroid)
in the frame the attitude is given in.

Refused, each in one line naming the file (and the line): a field that is not a finite number
(``NaN``), a row with fewer or more numbers than the first, more than :data:`MAX_KNOTS` rows, a
file over :data:`MAX_EPHEMERIS_BYTES`; and, for a table from a file or from Python alike, knots
whose interpolation error may exceed :data:`MAX_INTERPOLATION_ERROR` of the distance
(:func:`interpolation_error`: a gap across a perigee).
"""
from __future__ import annotations

from dataclasses import dataclass
from decimal import Decimal
import math
from pathlib import Path
import re
from typing import Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit_inline, python_source
from tumble_ros.core.units import KM_PER_AU, SECONDS_PER_YEAR, TIME_UNITS

__all__ = ['Ephemeris', 'read_ephemeris', 'ephemeris_position', 'interpolation_error',
           'DEGREE', 'MIN_KNOTS', 'MAX_KNOTS', 'MAX_EPHEMERIS_BYTES', 'MAX_INTERPOLATION_ERROR',
           'DAYS_PER_YEAR']

#: Degree of the interpolating polynomials (quintic: 6 coefficients per interval and axis).
DEGREE = 5
_WIDTH = DEGREE + 1
#: Fewest knots a table must have (a quintic spline needs six).
MIN_KNOTS = 6
#: Most knots (rows) accepted: the interpolant rides in a torque component's parameters (13
#: floats a knot: 1e5 knots are 10 MB). Real use: ten days at one minute is 14,400 rows, a year
#: at 10 minutes 52,600. The reader stops at the row beyond it.
MAX_KNOTS = 100_000
#: Why, in the refusal's words.
MAX_KNOTS_REASON = ('the interpolant of 1e5 knots is 10 MB of torque parameters; ten days at '
                    'one minute is 14,400 rows')
#: Largest ephemeris file [bytes] read: a Horizons record of X..VZ, LT, RG, RR takes ~250 bytes
#: (CSV) to ~330 (text), so MAX_KNOTS records and a header fit in 40 MB; a bigger file is
#: refused before it is read.
MAX_EPHEMERIS_BYTES = 40_000_000
#: Largest estimated interpolation error between two knots (:func:`interpolation_error`),
#: relative to the perturber's distance there: 0.2 %. On the Apophis flyby the true error of
#: the positions-only quintic was at most 4.7 times the estimate (knots every 4 h: estimate
#: 5.7e-3, true 2.7e-2), so this keeps it below ~1 % of the distance (3 % of the tidal torque,
#: ~ R^-3). Knots every 2 h (estimate 1.8e-3) and finer pass; every 4 h, or every hour with a
#: 24-h gap around the perigee (estimate 0.18, true 0.32: the Earth 17,000 km off) are refused.
MAX_INTERPOLATION_ERROR = 0.002
#: Days per year of the scenario's time base (the Julian year, ``units.SECONDS_PER_YEAR``).
DAYS_PER_YEAR = 365.25
#: Horizons' ``Output units`` -> (km per length unit, seconds per time unit).
_HORIZONS_UNITS = {'KM-S': (1.0, 1.0), 'KM-D': (1.0, 86400.0), 'AU-D': (KM_PER_AU, 86400.0)}


def _fail(field: str, why: str, value: object) -> None:
    raise ValueError(f'{field}: {why}, got {value!r}')


def interpolation_error(times: npt.ArrayLike, positions: npt.ArrayLike,
                        ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """
    Return (the estimated interpolation error [km], the distance [km]) on each interval.

    Both (n - 1,): on [t_k, t_k+1], the largest difference between the quintic and the cubic
    interpolating splines through the knots, and the smallest distance |x| of the quintic, at 8
    points of the interval. The difference is about the cubic's error (h^4 x^(4)), so it bounds
    the quintic's (h^6 x^(6)) where the knots resolve the motion; over a gap across which the
    motion turns (a perigee) the two differ by a good part of what both miss. Measured on the
    Apophis flyby (docs/physics.md, "Ephemerides"): the true error of the positions-only
    quintic was 0.14 to 4.7 times this estimate (knots every 0.5 to 4 h, or every hour with a
    24-h gap at the perigee; with velocities, the Hermite's, at most 2 times).
    ``times`` [yr], ``positions`` (n, 3) [km], n >= 6.
    """
    from scipy.interpolate import make_interp_spline

    t = np.asarray(times, dtype=float)
    x = np.asarray(positions, dtype=float)
    s = t[:-1, None] + (np.arange(8) + 0.5) / 8.0 * np.diff(t)[:, None]      # (n - 1, 8)
    quintic = make_interp_spline(t, x, k=DEGREE)(s.ravel())
    cubic = make_interp_spline(t, x, k=3)(s.ravel())
    error = np.linalg.norm(quintic - cubic, axis=1).reshape(s.shape)
    distance = np.linalg.norm(quintic, axis=1).reshape(s.shape)
    return np.max(error, axis=1), np.min(distance, axis=1)


@dataclass(frozen=True)
class Ephemeris:
    """
    A perturber's tabulated position relative to the asteroid, interpolated.

    Attributes
    ----------
    times : tuple of float
        The knots [yr], strictly increasing, at least :data:`MIN_KNOTS`.
    positions : tuple of (x, y, z)
        The perturber's position relative to the asteroid [km], orbital (inertial) frame.
    velocities : tuple of (vx, vy, vz), or ()
        Its velocity [km/s] at the knots, when the table gives it (then a Hermite interpolant).
    source : str
        The file it was read from (:func:`read_ephemeris`: its absolute path), '' for a table
        given in Python; with ``epoch_jd`` and ``time_unit`` what the scenario's parameters
        write back (``perturbers.<name>.ephemeris_file``...).
    epoch_jd : float
        The Julian date (TDB) of t = 0 the times were mapped with (a Horizons table), else 0.
    time_unit : str
        The unit of a plain table's time column (a key of ``units.TIME_UNITS``), else ''.

    """

    times: tuple[float, ...]
    positions: tuple[tuple[float, float, float], ...]
    velocities: tuple[tuple[float, float, float], ...] = ()
    source: str = ''
    epoch_jd: float = 0.0
    time_unit: str = ''

    def __post_init__(self) -> None:
        name = f'ephemeris {Path(self.source).name}' if self.source else 'ephemeris'
        t = np.asarray(self.times, dtype=float).reshape(-1)
        if not MIN_KNOTS <= t.size <= MAX_KNOTS:
            _fail(f'{name}.times', f'must have {MIN_KNOTS} to {MAX_KNOTS} knots', t.size)
        if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0.0):
            k = int(np.argmax(~(np.diff(t) > 0.0))) + 1 if np.all(np.isfinite(t)) else 0
            _fail(f'{name}.times', 'must be finite and strictly increasing', float(t[k]))
        x = np.asarray(self.positions, dtype=float)
        if x.shape != (t.size, 3) or not np.all(np.isfinite(x)):
            _fail(f'{name}.positions', f'must be {t.size} finite (x, y, z) rows [km]', x.shape)
        distance = np.linalg.norm(x, axis=1)
        if not np.all(distance > 0.0):
            _fail(f'{name}.positions', 'the perturber may not be at the asteroid (distance 0)',
                  int(np.argmin(distance)))
        v = np.asarray(self.velocities, dtype=float)
        if v.size and (v.shape != (t.size, 3) or not np.all(np.isfinite(v))):
            _fail(f'{name}.velocities', f'must be empty or {t.size} finite rows [km/s]', v.shape)
        self._check_interpolation(name, t, x)
        object.__setattr__(self, 'times', tuple(float(a) for a in t))
        object.__setattr__(self, 'positions', tuple((float(a), float(b), float(c))
                                                    for a, b, c in x))
        object.__setattr__(self, 'velocities', tuple((float(a), float(b), float(c))
                                                     for a, b, c in v.reshape(-1, 3)))

    def _check_interpolation(self, name: str, t: npt.NDArray[np.float64],
                             x: npt.NDArray[np.float64]) -> None:
        """Refuse knots whose interpolation error may exceed MAX_INTERPOLATION_ERROR."""
        error, distance = interpolation_error(t, x)
        limit = MAX_INTERPOLATION_ERROR * distance
        if np.all(error <= limit):
            return
        k = int(np.argmax(error / limit))
        gap = (t[k + 1] - t[k]) * DAYS_PER_YEAR * 24.0
        where = f't = {t[k]:.6g} to {t[k + 1]:.6g} yr'
        if self.epoch_jd:
            where += (f' (JD {self.epoch_jd + t[k] * DAYS_PER_YEAR:.6f} to '
                      f'{self.epoch_jd + t[k + 1] * DAYS_PER_YEAR:.6f})')
        raise ValueError(
            f'{name}.times: the knots {where}, {gap:.4g} h apart, allow interpolation errors up '
            f'to ~{error[k]:.3g} km, above the limit {limit[k]:.3g} km '
            f'({MAX_INTERPOLATION_ERROR:.1%} of the distance there; the estimate: the quintic '
            'spline through the knots minus the cubic): sample the table more densely there '
            '(Horizons: a smaller step)')

    @property
    def start(self) -> float:
        """Return the first knot [yr]."""
        return self.times[0]

    @property
    def end(self) -> float:
        """Return the last knot [yr]."""
        return self.times[-1]

    def coefficients(self) -> npt.NDArray[np.float64]:
        """
        Return the interpolant: (n - 1, 3, 6) Taylor coefficients about each interval's middle.

        Row k, axis a: c_p with x_a(t) = sum_p c_p (t - m_k)^p on [t_k, t_k+1], m_k = (t_k +
        t_k+1) / 2 [km/yr^p].
        """
        from scipy.interpolate import BPoly, make_interp_spline

        t = np.asarray(self.times)
        x = np.asarray(self.positions)
        middle = 0.5 * (t[:-1] + t[1:])
        out = np.empty((t.size - 1, 3, _WIDTH))
        if not self.velocities:
            spline = make_interp_spline(t, x, k=DEGREE)
            for p in range(_WIDTH):
                out[:, :, p] = spline.derivative(p)(middle) / math.factorial(p) if p else \
                    spline(middle)
            return out
        v = np.asarray(self.velocities) * SECONDS_PER_YEAR          # km/yr
        a = make_interp_spline(t, v, k=DEGREE).derivative()(t)       # km/yr^2
        for axis in range(3):
            hermite = BPoly.from_derivatives(t, np.stack([x[:, axis], v[:, axis], a[:, axis]],
                                                         axis=1))
            for p in range(_WIDTH):
                out[:, axis, p] = hermite.derivative(p)(middle) / math.factorial(p) if p else \
                    hermite(middle)
        return out

    def parameters(self) -> tuple[float, ...]:
        """
        Return the block :func:`ephemeris_position` reads: (n, t_0..t_n, coefficients).

        n the number of intervals, then the n + 1 knots [yr], then the (n, 3, 6) coefficients of
        :meth:`coefficients`, row-major.
        """
        cached: tuple[float, ...] | None = self.__dict__.get('_parameters')
        if cached is None:        # computed once (~0.1 s for 2,000 knots), kept with the table
            t = np.asarray(self.times)
            block = np.concatenate([[t.size - 1.0], t, self.coefficients().reshape(-1)])
            cached = tuple(float(v) for v in block)
            object.__setattr__(self, '_parameters', cached)
        return cached

    def closest_approach(self) -> tuple[float, float]:
        """
        Return (the smallest distance [km], its time [yr]) of the interpolant over the table.

        The interpolant's own polynomials (:meth:`parameters`) at 17 points of each interval,
        then, on the intervals next to the smallest, the exact minimum of |x(s)|^2 (a root of
        its derivative, a polynomial): the perigee between two knots, not the nearest knot.
        """
        from numpy.polynomial import polynomial

        par = np.asarray(self.parameters())
        n = int(par[0])
        t = par[1:n + 2]
        coefficients = par[n + 2:].reshape(n, 3, _WIDTH)
        half = 0.5 * np.diff(t)
        s = np.linspace(-1.0, 1.0, 17)[None, :] * half[:, None]                 # (n, 17)
        powers = s[:, :, None] ** np.arange(_WIDTH)                              # (n, 17, 6)
        x = np.einsum('kap,ksp->ksa', coefficients, powers)                      # (n, 17, 3)
        distance = np.linalg.norm(x, axis=2)
        k, j = (int(v) for v in np.unravel_index(int(np.argmin(distance)), distance.shape))
        best = (float(distance[k, j]), float(0.5 * (t[k] + t[k + 1]) + s[k, j]))
        for m in range(max(k - 1, 0), min(k + 2, n)):
            squared = sum(polynomial.polymul(c, c) for c in coefficients[m])
            for root in polynomial.polyroots(polynomial.polyder(squared)):
                if abs(root.imag) <= 1e-6 * half[m] and abs(root.real) <= half[m]:
                    value = float(polynomial.polyval(root.real, squared))
                    if value >= 0.0 and math.sqrt(value) < best[0]:
                        best = (math.sqrt(value), float(0.5 * (t[m] + t[m + 1]) + root.real))
        return best

    def position(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return the interpolated positions [km], orbital frame, (n, 3), at times ``t`` [yr]."""
        times = np.atleast_1d(np.asarray(t, dtype=float))
        par = np.asarray(self.parameters())
        evaluate = python_source(ephemeris_position)
        out = np.array([evaluate(par, 0, float(x)) for x in times], dtype=float)
        return out.reshape(-1, 3)


@jit_inline
def _horner(par: npt.NDArray[np.float64], c: int, s: float) -> float:
    """Return sum_p par[c + p] s^p for p = 0..5."""
    value: float = par[c] + s * (par[c + 1] + s * (par[c + 2] + s * (par[c + 3] + s * (
        par[c + 4] + s * par[c + 5]))))
    return value


@jit_inline
def ephemeris_position(par: npt.NDArray[np.float64], o: int,
                       t: float) -> tuple[float, float, float]:
    """
    Return the perturber's interpolated position [km] at time ``t`` [yr], orbital frame.

    ``par[o:]`` is :meth:`Ephemeris.parameters`. The interval is found by bisection on the
    knots; before the first knot or after the last one the end polynomial is extrapolated (a
    scenario's run lies inside the table: checked by the Scenario).
    """
    n = int(par[o])
    knots = o + 1
    lo = 0
    hi = n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t >= par[knots + mid]:
            lo = mid
        else:
            hi = mid
    s = t - 0.5 * (par[knots + lo] + par[knots + lo + 1])
    c = knots + n + 1 + lo * 3 * _WIDTH
    return _horner(par, c, s), _horner(par, c + _WIDTH, s), _horner(par, c + 2 * _WIDTH, s)


_NUMBER = r'[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?'
_LABEL = re.compile(r'\b([A-Z]+)\s*=\s*(\S*)')
_COLUMNS = ('X', 'Y', 'Z', 'VX', 'VY', 'VZ')


def _number(text: str, where: str, line: str) -> float:
    """Return the finite number ``text`` (Fortran's D exponent read as E); else ValueError."""
    if re.fullmatch(_NUMBER, text):
        value = float(text.replace('D', 'E').replace('d', 'e'))
        if math.isfinite(value):
            return value
    raise ValueError(f'{where}: {text!r} is not a finite number, in {line.strip()!r} (every '
                     'column of every row must parse: a row with a column left out would '
                     'shift the others)')


def _days_since(jd: str, epoch_jd: float) -> float:
    """Return JD - epoch_jd [d] from the printed JD, exactly (a JD in float64 is ~40 us)."""
    return float(Decimal(jd) - Decimal(repr(epoch_jd)))


class _Rows:
    """The rows of numbers of a table, each with its line number, at most MAX_KNOTS of them."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.rows: list[list[float]] = []
        self.lines: list[int] = []

    def start(self, values: list[float], line: int) -> None:
        """Append a row read from ``line``; ValueError if it is one more than MAX_KNOTS."""
        if len(self.rows) == MAX_KNOTS:
            raise ValueError(f'{self.name}:{line}: more than {MAX_KNOTS:,} rows (MAX_KNOTS: '
                             f'{MAX_KNOTS_REASON}); split the run or sample the table more '
                             'coarsely')
        self.rows.append(values)
        self.lines.append(line)


def _horizons_records(lines: Sequence[str], name: str, epoch_jd: float,
                      first: int) -> _Rows:
    """
    Return [days since epoch_jd, x, y, z (, vx, vy, vz ...)] per record ($$SOE to $$EOE).

    ``first``: the line number of ``lines[0]`` in the file. Every number of a record must
    parse (a ``NaN``, a ``n.a.`` is refused with its line), and a labelled record must give
    X, Y, Z (and VX, VY, VZ, or none of them).
    """
    table = _Rows(name)
    labelled: dict[str, float] = {}

    def close() -> None:
        if labelled and table.rows:
            keys = [k for k in _COLUMNS if k in labelled]
            if keys not in (list(_COLUMNS[:3]), list(_COLUMNS)):
                raise ValueError(f'{name}:{table.lines[-1]}: the record gives {keys}, not X, Y, '
                                 'Z (and VX, VY, VZ)')
            table.rows[-1] = table.rows[-1][:1] + [labelled[k] for k in keys]
        labelled.clear()

    for k, line in enumerate(lines, first):
        if not line.strip():
            continue
        where = f'{name}:{k}'
        if ',' in line:                               # CSV_FORMAT = YES: one line a record
            fields = [f.strip() for f in line.split(',')]
            fields = fields[:-1] if not fields[-1] else fields
            # the calendar date (the second field) is the one column that is not a number
            values = [_number(f, where, line) for j, f in enumerate(fields[1:], 1)
                      if not (j == 1 and re.match(r'\s*(A\.D\.|B\.C\.)', f))]
            _number(fields[0], where, line)
            table.start([_days_since(fields[0], epoch_jd)] + values, k)
            continue
        head = line.split('=')[0]
        if '=' in line and re.fullmatch(r'\s*' + _NUMBER + r'\s*', head):
            close()                                   # "2462240.5 = A.D. 2029-Apr-13 ..."
            table.start([_days_since(head.strip(), epoch_jd)], k)
            continue
        if not table.rows:
            raise ValueError(f'{where}: a line between $$SOE and $$EOE before any date: '
                             f'{line!r}')
        if '=' in line:                               # " X = 1.0E+05 Y =-2.0E+04 Z = ..."
            labelled.update({key: _number(value, where, line)
                             for key, value in _LABEL.findall(line) if key in _COLUMNS})
            continue
        table.rows[-1].extend(_number(f, where, line) for f in line.split())
    close()
    return table


def read_ephemeris(path: str | Path, *, epoch_jd: float = 0.0, time_unit: str = 'yr',
                   ) -> Ephemeris:
    """
    Read a JPL Horizons vector table or a plain ``t, x, y, z`` table (module docstring).

    ``epoch_jd``: the Julian date (TDB) of the scenario's t = 0, required for a Horizons table;
    ``time_unit``: the unit of a plain table's t (a key of ``units.TIME_UNITS``; the scenario's).
    ValueError naming the file, the line or field, and what was expected.
    """
    path = Path(path).resolve()
    name = str(path)
    if time_unit not in TIME_UNITS:
        _fail(f'{name}: time_unit', f'must be one of {sorted(TIME_UNITS)}', time_unit)
    try:
        size = path.stat().st_size
        if size > MAX_EPHEMERIS_BYTES:
            raise ValueError(f'{name}: {size:,} bytes, above {MAX_EPHEMERIS_BYTES:,} '
                             f'(MAX_EPHEMERIS_BYTES: {MAX_KNOTS:,} Horizons records of ~330 bytes '
                             'and a header fit in it); split the run or sample the table more '
                             'coarsely')
        text = path.read_text(encoding='utf-8')
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f'{name}: cannot read the ephemeris ({err})') from None
    lines = text.splitlines()
    marks = [k for k, line in enumerate(lines) if line.strip() in ('$$SOE', '$$EOE')]
    if marks:
        if len(marks) != 2 or lines[marks[0]].strip() != '$$SOE':
            raise ValueError(f'{name}: a Horizons table needs one $$SOE and one $$EOE line')
        if not (math.isfinite(epoch_jd) and epoch_jd > 0.0):
            _fail(f'{name}: epoch_jd', 'a Horizons table needs the Julian date (TDB) of the '
                  "scenario's t = 0 (> 0)", epoch_jd)
        header = '\n'.join(lines[:marks[0]])
        unit = re.search(r'Output units\s*:\s*([A-Z]+-[A-Z]+)', header)
        units = unit.group(1) if unit else 'KM-S'
        if units not in _HORIZONS_UNITS:
            raise ValueError(f'{name}: Output units {units!r} not read (one of '
                             f'{sorted(_HORIZONS_UNITS)})')
        km, seconds = _HORIZONS_UNITS[units]
        table = _table(_horizons_records(lines[marks[0] + 1:marks[1]], name, epoch_jd,
                                         marks[0] + 2))
        times = table[:, 0] / DAYS_PER_YEAR
        scale = (km, km / seconds)
        epoch, table_unit = float(epoch_jd), ''
    else:
        table = _table(_plain_rows(lines, name))
        times = table[:, 0] * TIME_UNITS[time_unit]
        scale = (1.0, 1.0)
        epoch, table_unit = 0.0, time_unit
    positions = table[:, 1:4] * scale[0]
    velocities = table[:, 4:7] * scale[1] if table.shape[1] >= 7 else np.empty((0, 3))
    return Ephemeris(tuple(times), tuple(map(tuple, positions)),
                     tuple(map(tuple, velocities)), source=name, epoch_jd=epoch,
                     time_unit=table_unit)


def _plain_rows(lines: Sequence[str], name: str) -> _Rows:
    """Return the rows of a plain table; lines before the first row of numbers are a header."""
    rows = _Rows(name)
    for k, line in enumerate(lines, 1):
        body = line.split('#')[0].strip()
        if not body:
            continue
        fields = [f for f in re.split(r'[,\s]+', body) if f]
        if not rows.rows and not re.fullmatch(_NUMBER, fields[0]):
            continue                                  # a header line ("t, x, y, z")
        rows.start([_number(f, f'{name}:{k}', line) for f in fields], k)
    return rows


def _table(rows: _Rows) -> npt.NDArray[np.float64]:
    """
    Return the rows as an (n, 4) or (n, 7) array: t, x, y, z (, vx, vy, vz).

    Every row must hold as many numbers as the first (ValueError with the line of the first
    that does not): a row with a column missing is refused, not read shifted or cut short.
    """
    name = rows.name
    if not rows.rows:
        raise ValueError(f'{name}: no rows of numbers (t, x, y, z) in the ephemeris')
    width = len(rows.rows[0])
    for row, line in zip(rows.rows, rows.lines):
        if len(row) != width:
            raise ValueError(f'{name}:{line}: the row has {len(row)} numbers, the first row '
                             f'(line {rows.lines[0]}) {width}: every row must give the same '
                             'columns')
    if width < 4 or width in (5, 6):
        raise ValueError(f'{name}:{rows.lines[0]}: the row has {width} numbers, needs t, x, y, '
                         'z or t, x, y, z, vx, vy, vz')
    width = 7 if width >= 7 else 4
    return np.array([r[:width] for r in rows.rows], dtype=float)

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

from tumble_ros.core.jit import jit_inline, python_source
from tumble_ros.core.model.units import KM_PER_AU, SECONDS_PER_YEAR, TIME_UNITS

__all__ = ['Ephemeris', 'read_ephemeris', 'ephemeris_position', 'DEGREE', 'MIN_KNOTS',
           'MAX_KNOTS', 'DAYS_PER_YEAR']

#: Degree of the interpolating polynomials (quintic: 6 coefficients per interval and axis).
DEGREE = 5
_WIDTH = DEGREE + 1
#: Fewest knots a table must have (a quintic spline needs six).
MIN_KNOTS = 6
#: Most knots accepted: the interpolant rides in a torque component's parameters (13 floats a
#: knot: 1e5 knots are 10 MB), ten days at one minute is 14,400.
MAX_KNOTS = 100_000
#: Days per year of the scenario's time base (the Julian year, ``units.SECONDS_PER_YEAR``).
DAYS_PER_YEAR = 365.25
#: Horizons' ``Output units`` -> (km per length unit, seconds per time unit).
_HORIZONS_UNITS = {'KM-S': (1.0, 1.0), 'KM-D': (1.0, 86400.0), 'AU-D': (KM_PER_AU, 86400.0)}


def _fail(field: str, why: str, value: object) -> None:
    raise ValueError(f'{field}: {why}, got {value!r}')


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
        object.__setattr__(self, 'times', tuple(float(a) for a in t))
        object.__setattr__(self, 'positions', tuple((float(a), float(b), float(c))
                                                    for a, b, c in x))
        object.__setattr__(self, 'velocities', tuple((float(a), float(b), float(c))
                                                     for a, b, c in v.reshape(-1, 3)))

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
_LABELLED = re.compile(r'\b(X|Y|Z|VX|VY|VZ)\s*=\s*(' + _NUMBER + ')')


def _numbers(text: str) -> list[float]:
    """Return the numbers of a line (Fortran's D exponent read as E)."""
    return [float(v.replace('D', 'E').replace('d', 'e')) for v in re.findall(_NUMBER, text)]


def _days_since(jd: str, epoch_jd: float) -> float:
    """Return JD - epoch_jd [d] from the printed JD, exactly (a JD in float64 is ~40 us)."""
    return float(Decimal(jd) - Decimal(repr(epoch_jd)))


def _horizons_records(lines: Sequence[str], name: str, epoch_jd: float) -> list[list[float]]:
    """Return [days since epoch_jd, x, y, z (, vx, vy, vz)] per record ($$SOE to $$EOE)."""
    records: list[list[float]] = []
    labelled: dict[str, float] = {}

    def close() -> None:
        if labelled and records:
            keys = [k for k in ('X', 'Y', 'Z', 'VX', 'VY', 'VZ') if k in labelled]
            records[-1] = records[-1][:1] + [labelled[k] for k in keys]
        labelled.clear()

    for line in lines:
        if not line.strip():
            continue
        if ',' in line:                               # CSV_FORMAT = YES: one line a record
            fields = [f.strip() for f in line.split(',') if f.strip()]
            values = [float(f) for f in fields[1:] if re.fullmatch(_NUMBER, f)]
            records.append([_days_since(fields[0], epoch_jd)] + values)
            continue
        found = _LABELLED.findall(line)
        if found:
            labelled.update({k: float(v) for k, v in found})
            continue
        head = line.split('=')[0]
        if '=' in line and re.fullmatch(r'\s*' + _NUMBER + r'\s*', head):
            close()                                   # "2462240.5 = A.D. 2029-Apr-13 ..."
            records.append([_days_since(head.strip(), epoch_jd)])
            continue
        if records:
            records[-1].extend(_numbers(line))        # unlabelled X Y Z [VX VY VZ ...]
        else:
            raise ValueError(f'{name}: a line between $$SOE and $$EOE before any date: {line!r}')
    close()
    return records


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
        rows = _horizons_records(lines[marks[0] + 1:marks[1]], name, epoch_jd)
        table = _table(rows, name)
        times = table[:, 0] / DAYS_PER_YEAR
        scale = (km, km / seconds)
        epoch, table_unit = float(epoch_jd), ''
    else:
        rows = []
        for k, line in enumerate(lines, 1):
            body = line.split('#')[0].strip()
            if not body:
                continue
            fields = [f for f in re.split(r'[,\s]+', body) if f]
            try:
                rows.append([float(f) for f in fields])
            except ValueError:
                if rows:
                    raise ValueError(f'{name}:{k}: not a row of numbers: {line!r}') from None
        table = _table(rows, name)
        times = table[:, 0] * TIME_UNITS[time_unit]
        scale = (1.0, 1.0)
        epoch, table_unit = 0.0, time_unit
    positions = table[:, 1:4] * scale[0]
    velocities = table[:, 4:7] * scale[1] if table.shape[1] >= 7 else np.empty((0, 3))
    return Ephemeris(tuple(times), tuple(map(tuple, positions)),
                     tuple(map(tuple, velocities)), source=name, epoch_jd=epoch,
                     time_unit=table_unit)


def _table(rows: list[list[float]], name: str) -> npt.NDArray[np.float64]:
    """Return the rows as an (n, 4) or (n, 7) array; ValueError when ragged or too narrow."""
    if not rows:
        raise ValueError(f'{name}: no rows of numbers (t, x, y, z) in the ephemeris')
    width = min(len(r) for r in rows)
    if width < 4:
        k = min(range(len(rows)), key=lambda j: len(rows[j]))
        raise ValueError(f'{name}: row {k + 1} has {width} numbers, needs t, x, y, z')
    width = 7 if width >= 7 else 4
    return np.array([r[:width] for r in rows], dtype=float)

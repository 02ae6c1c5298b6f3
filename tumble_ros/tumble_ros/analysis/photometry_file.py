"""
A user's photometry: a CSV file of time and magnitude, optional errors and geometry (ROS-free).

The first line that is not empty and not a ``#`` comment names the columns, comma-separated,
case-insensitive (a UTF-8 byte-order mark before it, as spreadsheets write, is skipped):

* the time: ``jd``, ``hjd``, ``bjd`` or ``mjd`` [days] or ``time_d`` [days], or ``time_h`` or
  ``hours`` [h] (:data:`TIME_COLUMNS`); read into hours. ``jd`` and ``mjd`` may name their time
  scale: ``jd_utc``, ``jd_tt``, ``jd_tdb``, ``mjd_utc``... (:data:`TIME_SCALES`; the
  inversion's reader converts them to TDB, the period search needs no scale);
* the magnitude: ``mag`` or ``magnitude`` [mag], |mag| <= :data:`~.periods.MAX_MAGNITUDE`;
* optionally the error: ``err``, ``error``, ``mag_err`` or ``sigma`` [mag] in
  [:data:`~.periods.MIN_SIGMA`, :data:`~.periods.MAX_SIGMA`] (the weights 1/err^2 of the
  period search);
* optionally the geometry, either the vectors ``sun_x, sun_y, sun_z`` (asteroid -> Sun) and
  ``obs_x, obs_y, obs_z`` (asteroid -> observer) [au], ecliptic J2000 (:data:`VECTOR_COLUMNS`),
  or the distances ``r`` (Sun - asteroid) and ``delta`` (observer - asteroid) [au] with
  optionally the phase angle ``phase`` [deg] (:data:`DISTANCE_COLUMNS`). With it the period
  search runs on reduced magnitudes (:func:`reduced_photometry`);
* optionally ``block`` or ``night``: a label per row; rows of one label are one lightcurve
  block (its own magnitude offset in the inversion).

Other columns are ignored; every data line has the header's number of fields. Bounded work: only
a regular file is read (``core.model.user_files.read_user_bytes``: a FIFO, a device, a directory is
refused by its kind before any read, a FIFO without a writer cannot block), at most
:data:`MAX_PHOTOMETRY_BYTES` of it and at most :data:`MAX_PHOTOMETRY_ROWS` data lines. Every
failure is one AnalysisError line naming the file, the line and the column. docs/analysis.md,
"Periods from a lightcurve".
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import math
from pathlib import Path
from typing import Iterator

import numpy as np

from tumble_ros.core.model.user_files import decode_user_text, read_user_bytes
from tumble_ros.errors import AnalysisError

from .periods import MAX_MAGNITUDE, MAX_SIGMA, MIN_SIGMA

__all__ = ['Photometry', 'read_photometry', 'reduced_photometry', 'BLOCK_COLUMNS',
           'DISTANCE_COLUMNS', 'ERROR_COLUMNS', 'MAGNITUDE_COLUMNS', 'MAX_PHOTOMETRY_BYTES',
           'MAX_PHOTOMETRY_ROWS', 'TIME_COLUMNS', 'TIME_SCALES', 'VECTOR_COLUMNS']

#: the time scales a ``jd`` or ``mjd`` column may name (``jd_utc``, ``mjd_tdb``...)
TIME_SCALES = ('utc', 'tt', 'tdb')
#: time column name -> hours per unit
TIME_COLUMNS = {'jd': 24.0, 'hjd': 24.0, 'bjd': 24.0, 'mjd': 24.0, 'time_d': 24.0,
                'time_h': 1.0, 'hours': 1.0,
                **{f'{kind}_{scale}': 24.0 for kind in ('jd', 'mjd') for scale in TIME_SCALES}}
MAGNITUDE_COLUMNS = ('mag', 'magnitude')
ERROR_COLUMNS = ('err', 'error', 'mag_err', 'sigma')
#: asteroid -> Sun, asteroid -> observer [au], ecliptic J2000: all six or none
VECTOR_COLUMNS = ('sun_x', 'sun_y', 'sun_z', 'obs_x', 'obs_y', 'obs_z')
#: the Sun's and the observer's distances [au] (both or neither), the phase angle [deg]
DISTANCE_COLUMNS = ('r', 'delta', 'phase')
BLOCK_COLUMNS = ('block', 'night')
#: fewer points cannot hold a period search
MIN_POINTS = 20
#: the most data lines read: a campaign holds ~10^4 points (a month of nights at one point
#: every few minutes); ten times that is still searched in seconds
MAX_PHOTOMETRY_ROWS = 100_000
#: the largest file read [bytes]: MAX_PHOTOMETRY_ROWS lines of ~300 characters (comments and
#: columns that are not read included)
MAX_PHOTOMETRY_BYTES = 32 * 1024 * 1024
#: no observer or Sun is nearer the asteroid than this [au] (~1.5 km): a zero vector is missing
_MIN_DISTANCE_AU = 1e-8


@dataclass(frozen=True)
class Photometry:
    """
    A photometry CSV as read, in time order (rows sorted together).

    ``t`` times [h] (as in the file, times the unit); ``magnitude`` [mag]; ``sigma`` [mag] or
    None; ``time_column`` the time column's name; ``time`` the times in the file's unit (days
    or hours); ``lines`` each row's line in the file; ``sun``, ``observer`` (n, 3) asteroid ->
    Sun and asteroid -> observer [au], ecliptic J2000, or None; ``r``, ``delta`` [au] and
    ``phase`` [rad] (from the vectors, or the columns) or None; ``block`` one label per row or
    None; ``path`` the file.
    """

    t: np.ndarray
    magnitude: np.ndarray
    sigma: np.ndarray | None
    time_column: str
    time: np.ndarray | None = None
    lines: np.ndarray | None = None
    sun: np.ndarray | None = None
    observer: np.ndarray | None = None
    r: np.ndarray | None = None
    delta: np.ndarray | None = None
    phase: np.ndarray | None = None
    block: tuple[str, ...] | None = None
    path: str = ''


def _one(path: Path, header: list[str], names, what: str, required: bool) -> int | None:
    found = [i for i, name in enumerate(header) if name in names]
    if len(found) > 1:
        raise AnalysisError(f'{path}: several {what} columns {[header[i] for i in found]}: '
                            f'keep one')
    if not found and required:
        raise AnalysisError(f'{path}: no {what} column in the header {header}: name one of '
                            f'{", ".join(names)}')
    return found[0] if found else None


def _text(path: Path) -> str:
    """Return the file's text: a regular file, at most MAX_PHOTOMETRY_BYTES, UTF-8 (no BOM)."""
    what = f'{path}'
    data = read_user_bytes(path, what, MAX_PHOTOMETRY_BYTES, 'MAX_PHOTOMETRY_BYTES',
                           'photometry file', AnalysisError)
    return decode_user_text(data, what, AnalysisError)


def _rows(path: Path, text: str) -> Iterator[tuple[int, list[str]]]:
    """Yield (line number, fields) of the lines that are neither empty nor comments."""
    reader = csv.reader(text.splitlines())
    try:
        for row in reader:
            if row and ''.join(row).strip() and not row[0].lstrip().startswith('#'):
                yield reader.line_num, row
    except csv.Error as err:
        raise AnalysisError(f'{path} line {reader.line_num}: not CSV: {err}') from None


@dataclass(frozen=True)
class _Columns:
    """Where each quantity is in the header (indices), the numbers read first."""

    numbers: tuple[int, ...]        # time, magnitude, (error), (vectors), (r, delta, (phase))
    error: bool
    vectors: bool
    distances: bool
    phase: bool
    block: int | None


def _columns(path: Path, header: list[str]) -> _Columns:
    i_t = _one(path, header, tuple(TIME_COLUMNS), 'time', True)
    i_m = _one(path, header, MAGNITUDE_COLUMNS, 'magnitude', True)
    i_e = _one(path, header, ERROR_COLUMNS, 'error', False)
    numbers = [i for i in (i_t, i_m, i_e) if i is not None]
    vectors = [name for name in VECTOR_COLUMNS if name in header]
    if vectors and len(vectors) != len(VECTOR_COLUMNS):
        missing = [name for name in VECTOR_COLUMNS if name not in header]
        raise AnalysisError(f'{path}: the geometry columns {vectors} without {missing}: give '
                            f'all of {", ".join(VECTOR_COLUMNS)} [au] or none')
    distances = [name for name in DISTANCE_COLUMNS[:2] if name in header]
    if len(distances) == 1:
        raise AnalysisError(f'{path}: the column {distances[0]} without '
                            f'{"delta" if distances[0] == "r" else "r"}: give both distances '
                            '[au] or neither')
    phase = 'phase' in header
    if phase and not distances:
        raise AnalysisError(f'{path}: a phase column without r and delta: give the distances '
                            '[au] too')
    if vectors and distances:
        raise AnalysisError(f'{path}: both the vectors ({", ".join(VECTOR_COLUMNS)}) and r, '
                            'delta: give one geometry (the vectors hold the distances)')
    for name in vectors + distances + (['phase'] if phase else []):
        numbers.append(header.index(name))
    return _Columns(tuple(numbers), i_e is not None, bool(vectors), bool(distances), phase,
                    _one(path, header, BLOCK_COLUMNS, 'block', False))


def _numbers(path: Path, line: int, row: list[str], header: list[str],
             columns: _Columns) -> list[float]:
    """Return the row's numbers (``columns.numbers``); AnalysisError naming line and column."""
    if len(row) != len(header):
        raise AnalysisError(f'{path} line {line}: {len(row)} fields, the header has '
                            f'{len(header)}')
    numbers = []
    for i in columns.numbers:
        try:
            x = float(row[i])
        except ValueError:
            raise AnalysisError(f'{path} line {line}: {header[i]} = {row[i].strip()[:40]!r} '
                                f'is not a number') from None
        if not math.isfinite(x):
            raise AnalysisError(f'{path} line {line}: {header[i]} = {x} must be finite')
        numbers.append(x)
    name = header[columns.numbers[1]]
    if abs(numbers[1]) > MAX_MAGNITUDE:
        raise AnalysisError(f'{path} line {line}: {name} = {numbers[1]:g} is not '
                            f'a magnitude (|mag| <= {MAX_MAGNITUDE:g})')
    if columns.error and not MIN_SIGMA <= numbers[2] <= MAX_SIGMA:
        raise AnalysisError(f'{path} line {line}: {header[columns.numbers[2]]} = {numbers[2]:g} '
                            f'must be in [{MIN_SIGMA:g}, {MAX_SIGMA:g}] mag (> 0: a weight '
                            f'1/err^2; no photometry is better than 1e-4 mag)')
    _check_geometry(path, line, numbers[2 + columns.error:], columns)
    return numbers


def _check_geometry(path: Path, line: int, values: list[float], columns: _Columns) -> None:
    """Refuse a zero vector, a distance <= 0, a phase angle outside [0, 180] deg."""
    if columns.vectors:
        for name, vector in (('sun', values[:3]), ('obs', values[3:6])):
            if math.hypot(*vector) < _MIN_DISTANCE_AU:
                raise AnalysisError(f'{path} line {line}: the {name}_x, {name}_y, {name}_z '
                                    f'vector {vector} is not a distance from the asteroid (au)')
    elif columns.distances:
        for name, value in zip(('r', 'delta'), values[:2]):
            if value < _MIN_DISTANCE_AU:
                raise AnalysisError(f'{path} line {line}: {name} = {value:g} must be a '
                                    'distance > 0 [au]')
        if columns.phase and not 0.0 <= values[2] <= 180.0:
            raise AnalysisError(f'{path} line {line}: phase = {values[2]:g} must be in '
                                '[0, 180] deg')


def read_photometry(path: str | Path) -> Photometry:
    """Read a photometry CSV (module docstring); AnalysisError for a bad file."""
    path = Path(path)
    rows = _rows(path, _text(path))
    first = next(rows, None)
    if first is None:
        raise AnalysisError(f'{path}: empty: need a header line naming the columns and '
                            f'data')
    header = [c.strip().lower() for c in first[1]]
    columns = _columns(path, header)
    values: list[list[float]] = []
    lines: list[int] = []
    labels: list[str] = []
    for line, row in rows:
        if len(values) == MAX_PHOTOMETRY_ROWS:
            raise AnalysisError(f'{path} line {line}: more than {MAX_PHOTOMETRY_ROWS:,} '
                                f'data lines (MAX_PHOTOMETRY_ROWS; a campaign holds ~10^4 '
                                f'points): bin or split the file')
        values.append(_numbers(path, line, row, header, columns))
        lines.append(line)
        if columns.block is not None:
            labels.append(row[columns.block].strip())
    if len(values) < MIN_POINTS:
        raise AnalysisError(f'{path}: {len(values)} data lines, need at least {MIN_POINTS}')
    order = np.argsort(np.array(values)[:, 0], kind='stable')
    return _photometry(path, header, columns, np.array(values)[order],
                       np.array(lines)[order], tuple(labels[k] for k in order) if labels
                       else None)


def _photometry(path: Path, header: list[str], columns: _Columns, data: np.ndarray,
                lines: np.ndarray, labels: tuple[str, ...] | None) -> Photometry:
    name = header[columns.numbers[0]]
    k = 2 + columns.error
    sun = observer = r = delta = phase = None
    if columns.vectors:
        sun, observer = data[:, k:k + 3], data[:, k + 3:k + 6]
        r, delta = np.linalg.norm(sun, axis=1), np.linalg.norm(observer, axis=1)
        cosine = np.sum(sun * observer, axis=1) / (r * delta)
        phase = np.arccos(np.clip(cosine, -1.0, 1.0))
    elif columns.distances:
        r, delta = data[:, k], data[:, k + 1]
        phase = np.radians(data[:, k + 2]) if columns.phase else None
    return Photometry(data[:, 0] * TIME_COLUMNS[name], data[:, 1],
                      data[:, 2] if columns.error else None, name, time=data[:, 0],
                      lines=lines, sun=sun, observer=observer, r=r, delta=delta, phase=phase,
                      block=labels, path=str(path))


def reduced_photometry(data: Photometry) -> tuple[np.ndarray, str | None]:
    """
    Return (the magnitudes the period search takes [mag], what was removed, or None).

    With the geometry (:class:`Photometry` ``r`` and ``delta``): the reduced magnitudes
    m - 5 log10(r delta), then, with the phase angle varying by more than
    ``lightcurve.PHASE_SPAN``, a quadratic phase function removed as for a recording
    (``lightcurve.remove_phase_function``). Without it: the magnitudes as given, None.
    """
    if data.r is None or data.delta is None:
        return data.magnitude, None
    from .lightcurve import remove_phase_function

    modulus = 5.0 * np.log10(data.r * data.delta)
    reduced = data.magnitude - modulus
    note = (f"reduced magnitudes: m - 5 log10(r delta) from the file's geometry (the distance "
            f'term spans {np.ptp(modulus):.3g} mag)')
    if data.phase is None:
        return reduced, note + ', no phase angle given (its phase function is left in)'
    reduced, phase_note = remove_phase_function(reduced, data.phase)
    return reduced, f'{note}, {phase_note}'

"""
A user's photometry: a CSV file of time and magnitude, with optional errors (ROS-free).

The first line that is not empty and not a ``#`` comment names the columns, comma-separated,
case-insensitive (a UTF-8 byte-order mark before it, as spreadsheets write, is skipped):

* the time: ``jd``, ``hjd``, ``bjd`` or ``mjd`` [days] or ``time_d`` [days], or ``time_h`` or
  ``hours`` [h] (:data:`TIME_COLUMNS`); read into hours;
* the magnitude: ``mag`` or ``magnitude`` [mag], |mag| <= :data:`~.periods.MAX_MAGNITUDE`;
* optionally the error: ``err``, ``error``, ``mag_err`` or ``sigma`` [mag] in
  [:data:`~.periods.MIN_SIGMA`, :data:`~.periods.MAX_SIGMA`] (the weights 1/err^2 of the
  period search).

Other columns are ignored; every data line has the header's number of fields. Bounded work: only
a regular file is read (a FIFO, a device, a directory is refused by its kind before any read, a
FIFO without a writer cannot block), at most :data:`MAX_PHOTOMETRY_BYTES` of it and at most
:data:`MAX_PHOTOMETRY_ROWS` data lines. Every failure is one AnalysisError line naming the file,
the line and the column. docs/analysis.md, "Periods from a lightcurve".
"""
from __future__ import annotations

import codecs
import csv
from dataclasses import dataclass
import io
import math
import os
from pathlib import Path
import stat

import numpy as np

from tumble_ros.errors import AnalysisError
from tumble_ros.file_kinds import file_kind

from .periods import MAX_MAGNITUDE, MAX_SIGMA, MIN_SIGMA

__all__ = ['Photometry', 'read_photometry', 'ERROR_COLUMNS', 'MAGNITUDE_COLUMNS',
           'MAX_PHOTOMETRY_BYTES', 'MAX_PHOTOMETRY_ROWS', 'TIME_COLUMNS']

#: time column name -> hours per unit
TIME_COLUMNS = {'jd': 24.0, 'hjd': 24.0, 'bjd': 24.0, 'mjd': 24.0, 'time_d': 24.0,
                'time_h': 1.0, 'hours': 1.0}
MAGNITUDE_COLUMNS = ('mag', 'magnitude')
ERROR_COLUMNS = ('err', 'error', 'mag_err', 'sigma')
#: fewer points cannot hold a period search
MIN_POINTS = 20
#: the most data lines read: a campaign holds ~10^4 points (a month of nights at one point
#: every few minutes); ten times that is still searched in seconds
MAX_PHOTOMETRY_ROWS = 100_000
#: the largest file read [bytes]: MAX_PHOTOMETRY_ROWS lines of ~300 characters (comments and
#: columns that are not read included)
MAX_PHOTOMETRY_BYTES = 32 * 1024 * 1024


@dataclass(frozen=True)
class Photometry:
    """Times [h] (as in the file, times the unit), magnitudes [mag], errors [mag] or None."""

    t: np.ndarray
    magnitude: np.ndarray
    sigma: np.ndarray | None
    time_column: str


def _one(path: Path, header: list[str], names, what: str, required: bool) -> int | None:
    found = [i for i, name in enumerate(header) if name in names]
    if len(found) > 1:
        raise AnalysisError(f'{path}: several {what} columns {[header[i] for i in found]}: '
                            f'keep one')
    if not found and required:
        raise AnalysisError(f'{path}: no {what} column in the header {header}: name one of '
                            f'{", ".join(names)}')
    return found[0] if found else None


def _open(path: Path) -> io.BufferedReader:
    """
    Open the regular file ``path`` for reading, never blocking on it.

    O_NONBLOCK makes the open of a FIFO return at once; the opened file (not the name) must be
    regular and at most MAX_PHOTOMETRY_BYTES long.
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        try:
            mode = os.stat(path).st_mode            # a socket or a directory fails to open
        except OSError:
            mode = stat.S_IFREG
        why = (f'{file_kind(mode)}: only a regular file is read' if not stat.S_ISREG(mode)
               else ' '.join(str(err.strerror or err).split()))
        raise AnalysisError(f'cannot read photometry {path}: {why}') from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise AnalysisError(f'cannot read photometry {path}: {file_kind(info.st_mode)}: '
                                'only a regular file is read')
        if info.st_size > MAX_PHOTOMETRY_BYTES:
            raise AnalysisError(f'{path}: {info.st_size:,} bytes, above the limit of '
                                f'{MAX_PHOTOMETRY_BYTES:,} (MAX_PHOTOMETRY_BYTES; a campaign '
                                f'of 10^4 points is ~0.5 MB)')
        os.set_blocking(fd, True)
        return os.fdopen(fd, 'rb')
    except BaseException:
        os.close(fd)
        raise


def _text_lines(path: Path, stream: io.BufferedReader):
    """Yield the lines as text (a UTF-8 BOM skipped); AnalysisError naming one not UTF-8."""
    for number, raw in enumerate(stream, start=1):
        if number == 1 and raw.startswith(codecs.BOM_UTF8):
            raw = raw[len(codecs.BOM_UTF8):]
        try:
            yield raw.decode('utf-8')
        except UnicodeDecodeError as err:
            raise AnalysisError(f'{path} line {number}: not UTF-8 text ({err.reason})') \
                from None


def _rows(path: Path, stream: io.BufferedReader):
    """Yield (line number, fields) of the lines that are neither empty nor comments."""
    reader = csv.reader(_text_lines(path, stream))
    try:
        for row in reader:
            if row and ''.join(row).strip() and not row[0].lstrip().startswith('#'):
                yield reader.line_num, row
    except csv.Error as err:
        raise AnalysisError(f'{path} line {reader.line_num}: not CSV: {err}') from None


def _numbers(path: Path, line: int, row: list[str], header: list[str],
             columns: list[int]) -> list[float]:
    """Return the row's time, magnitude (and error); AnalysisError naming line and column."""
    if len(row) != len(header):
        raise AnalysisError(f'{path} line {line}: {len(row)} fields, the header has '
                            f'{len(header)}')
    numbers = []
    for i in columns:
        try:
            x = float(row[i])
        except ValueError:
            raise AnalysisError(f'{path} line {line}: {header[i]} = {row[i].strip()[:40]!r} '
                                f'is not a number') from None
        if not math.isfinite(x):
            raise AnalysisError(f'{path} line {line}: {header[i]} = {x} must be finite')
        numbers.append(x)
    if abs(numbers[1]) > MAX_MAGNITUDE:
        raise AnalysisError(f'{path} line {line}: {header[columns[1]]} = {numbers[1]:g} is not '
                            f'a magnitude (|mag| <= {MAX_MAGNITUDE:g})')
    if len(numbers) == 3 and not MIN_SIGMA <= numbers[2] <= MAX_SIGMA:
        raise AnalysisError(f'{path} line {line}: {header[columns[2]]} = {numbers[2]:g} must '
                            f'be in [{MIN_SIGMA:g}, {MAX_SIGMA:g}] mag (> 0: a weight '
                            f'1/err^2; no photometry is better than 1e-4 mag)')
    return numbers


def read_photometry(path: str | Path) -> Photometry:
    """Read a photometry CSV (module docstring); AnalysisError for a bad file."""
    path = Path(path)
    with _open(path) as stream:
        rows = _rows(path, stream)
        first = next(rows, None)
        if first is None:
            raise AnalysisError(f'{path}: empty: need a header line naming the columns and '
                                f'data')
        header = [c.strip().lower() for c in first[1]]
        i_t = _one(path, header, tuple(TIME_COLUMNS), 'time', True)
        i_m = _one(path, header, MAGNITUDE_COLUMNS, 'magnitude', True)
        i_e = _one(path, header, ERROR_COLUMNS, 'error', False)
        columns = [i for i in (i_t, i_m, i_e) if i is not None]
        values: list[list[float]] = []
        for line, row in rows:
            if len(values) == MAX_PHOTOMETRY_ROWS:
                raise AnalysisError(f'{path} line {line}: more than {MAX_PHOTOMETRY_ROWS:,} '
                                    f'data lines (MAX_PHOTOMETRY_ROWS; a campaign holds ~10^4 '
                                    f'points): bin or split the file')
            values.append(_numbers(path, line, row, header, columns))
    if len(values) < MIN_POINTS:
        raise AnalysisError(f'{path}: {len(values)} data lines, need at least {MIN_POINTS}')
    data = np.array(values)
    data = data[np.argsort(data[:, 0], kind='stable')]
    name = header[columns[0]]
    return Photometry(data[:, 0] * TIME_COLUMNS[name], data[:, 1],
                      data[:, 2] if i_e is not None else None, name)

"""
A user's photometry: a CSV file of time and magnitude, with optional errors (ROS-free).

The first line that is not empty and not a ``#`` comment names the columns, comma-separated,
case-insensitive:

* the time: ``jd``, ``hjd``, ``bjd`` or ``mjd`` [days] or ``time_d`` [days], or ``time_h`` or
  ``hours`` [h] (:data:`TIME_COLUMNS`); read into hours;
* the magnitude: ``mag`` or ``magnitude`` [mag];
* optionally the error: ``err``, ``error``, ``mag_err`` or ``sigma`` [mag, > 0] (the weights
  1/err^2 of the period search).

Other columns are ignored. Every failure is an AnalysisError naming the file, the line and the
column. docs/analysis.md, "Periods from a lightcurve".
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import math
from pathlib import Path

import numpy as np

from tumble_ros.errors import AnalysisError

__all__ = ['Photometry', 'read_photometry', 'ERROR_COLUMNS', 'MAGNITUDE_COLUMNS',
           'TIME_COLUMNS']

#: time column name -> hours per unit
TIME_COLUMNS = {'jd': 24.0, 'hjd': 24.0, 'bjd': 24.0, 'mjd': 24.0, 'time_d': 24.0,
                'time_h': 1.0, 'hours': 1.0}
MAGNITUDE_COLUMNS = ('mag', 'magnitude')
ERROR_COLUMNS = ('err', 'error', 'mag_err', 'sigma')
#: fewer points cannot hold a period search
MIN_POINTS = 20


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


def read_photometry(path: str | Path) -> Photometry:
    """Read a photometry CSV (module docstring); AnalysisError for a bad file."""
    path = Path(path)
    try:
        text = path.read_text(encoding='utf-8')
    except (OSError, UnicodeDecodeError) as err:
        raise AnalysisError(f'cannot read photometry {path}: {err}') from None
    rows = [(n, row) for n, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and ''.join(row).strip() and not row[0].lstrip().startswith('#')]
    if not rows:
        raise AnalysisError(f'{path}: empty: need a header line naming the columns and data')
    header = [c.strip().lower() for c in rows[0][1]]
    i_t = _one(path, header, tuple(TIME_COLUMNS), 'time', True)
    i_m = _one(path, header, MAGNITUDE_COLUMNS, 'magnitude', True)
    i_e = _one(path, header, ERROR_COLUMNS, 'error', False)
    assert i_t is not None   # (required: _one raised otherwise)
    columns = [i for i in (i_t, i_m, i_e) if i is not None]
    values = []
    for line, row in rows[1:]:
        if len(row) < len(header):
            raise AnalysisError(f'{path} line {line}: {len(row)} fields, the header has '
                                f'{len(header)}')
        try:
            numbers = [float(row[i]) for i in columns]
        except ValueError:
            bad = next(i for i in columns if not _is_float(row[i]))
            raise AnalysisError(f'{path} line {line}: {header[bad]} = {row[bad].strip()!r} is '
                                f'not a number') from None
        for i, x in zip(columns, numbers):
            if not math.isfinite(x):
                raise AnalysisError(f'{path} line {line}: {header[i]} = {x} must be finite')
        if i_e is not None and numbers[2] <= 0.0:
            raise AnalysisError(f'{path} line {line}: {header[i_e]} = {numbers[2]} must be '
                                f'> 0 [mag]')
        values.append(numbers)
    if len(values) < MIN_POINTS:
        raise AnalysisError(f'{path}: {len(values)} data lines, need at least {MIN_POINTS}')
    data = np.array(values)
    order = np.argsort(data[:, 0], kind='stable')
    data = data[order]
    name = header[i_t]
    return Photometry(data[:, 0] * TIME_COLUMNS[name], data[:, 1],
                      data[:, 2] if i_e is not None else None, name)


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True

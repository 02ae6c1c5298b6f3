"""
The DAMIT lightcurve format (``lc.txt``, the input of Kaasalainen's convexinv): its own geometry.

The file, blank-separated numbers (docs/inversion.md, "Your photometry")::

    2                                  <- the number of lightcurves
    3 0                                <- the points of this lightcurve, 0 relative / 1 calibrated
    2440000.50000 1.012 -0.81 2.50 0.12 -0.30 1.80 0.08
    ...                                <- JD, intensity, asteroid -> Sun xyz, asteroid -> Earth xyz

The times are light-time corrected Julian dates (emission times; scale UTC unless
``time_scale`` says); the intensities relative fluxes reduced to unit distances (convexinv's
model has no distances); the vectors ecliptic J2000 [au]. Each lightcurve is a block: flag 0
its own magnitude offset, flag 1 the calibrated scale shared by all. Read as magnitudes m =
-2.5 log10(I) + 5 log10(r Delta) (so that ``Campaign.reduced_magnitude`` is -2.5 log10 I: a flux
of 0.5 is +0.7526 mag); the file has no errors: each point gets ``sigma``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .common import (campaign, fail, LIGHT_DAYS_PER_AU, number, Points, read_text,
                     ReadOptions)
from .timescales import to_tdb
from ..campaign import Campaign, MIN_DISTANCE_AU

__all__ = ['read_damit', 'looks_like_damit']

_FIELDS = ('JD', 'intensity', 'sun_x', 'sun_y', 'sun_z', 'earth_x', 'earth_y', 'earth_z')


def _lines(text: str):
    """Yield (line number, fields) of the lines that are not blank."""
    for k, line in enumerate(text.splitlines(), 1):
        fields = line.split()
        if fields:
            yield k, fields


def looks_like_damit(text: str) -> bool:
    """Whether ``text`` opens as a DAMIT file: a count, then 'n flag'."""
    head = [fields for (_, fields), _ in zip(_lines(text), range(2))]
    return (len(head) == 2 and len(head[0]) == 1 and head[0][0].isdigit()
            and len(head[1]) == 2 and all(f.isdigit() for f in head[1]))


def _integer(path: Path, line: int, name: str, text: str) -> int:
    if not text.isdigit():
        fail(path, line, f'{name} = {text!r} is not a whole number')
    return int(text)


def _point(path: Path, line: int, fields: list[str]) -> tuple[list[float], float]:
    """Return the point's 8 numbers; refuse a missing one, a flux <= 0, a zero vector."""
    if len(fields) != len(_FIELDS):
        fail(path, line, f'{len(fields)} numbers, a DAMIT point has {len(_FIELDS)}: '
             f'{", ".join(_FIELDS)}')
    values = [number(path, line, name, text) for name, text in zip(_FIELDS, fields)]
    if values[1] <= 0.0:
        fail(path, line, f'intensity = {values[1]:g} must be a relative flux > 0')
    for name, vector in (('sun', values[2:5]), ('earth', values[5:8])):
        if math.hypot(*vector) < MIN_DISTANCE_AU:
            fail(path, line, f'the {name} vector {vector} is not a distance from the asteroid '
                 '[au]')
    return values, -2.5 * math.log10(values[1])


def read_damit(path: Path, options: ReadOptions) -> Campaign:
    """Read a DAMIT lightcurve file (module docstring) into a Campaign; one-line refusals."""
    lines = _lines(read_text(path, 'DAMIT lightcurve file'))
    first = next(lines, None)
    if first is None:
        fail(path, None, 'empty: a DAMIT file starts with the number of lightcurves')
    line, fields = first
    if len(fields) != 1:
        fail(path, line, 'the first line holds the number of lightcurves alone')
    count = _integer(path, line, 'the number of lightcurves', fields[0])
    points = Points(path)
    for curve in range(count):
        head = next(lines, None)
        if head is None:
            fail(path, None, f'ends after {curve} of the {count} lightcurves the first line '
                 'announces')
        line, fields = head
        if len(fields) != 2 or fields[1] not in ('0', '1'):
            fail(path, line, f'lightcurve {curve + 1}: expected "points flag" (flag 0 relative, '
                 f'1 calibrated), got {" ".join(fields)[:60]!r}')
        n = _integer(path, line, 'the number of points', fields[0])
        if n == 0:
            fail(path, line, f'lightcurve {curve + 1} has no points')
        calibrated = fields[1] == '1' if options.calibrated is None else options.calibrated
        points.new_block(f'{path.name} lightcurve {curve + 1} (line {line})', not calibrated)
        for _ in range(n):
            row = next(lines, None)
            if row is None:
                fail(path, None, f'ends inside lightcurve {curve + 1} (line {line} announces {n} '
                     'points)')
            values, magnitude = _point(path, *row)
            sun, earth = tuple(values[2:5]), tuple(values[5:8])
            r, delta = math.hypot(*sun), math.hypot(*earth)
            points.add(row[0], values[0], magnitude + 5.0 * math.log10(r * delta),
                       options.sigma, True, sun, earth)       # type: ignore[arg-type]
    extra = next(lines, None)
    if extra is not None:
        fail(path, extra[0], f'more lines after the {count} lightcurves the first line announces')
    return _campaign(path, points, options)


def _campaign(path: Path, points: Points, options: ReadOptions) -> Campaign:
    jd, notes = to_tdb(np.asarray(points.jd), options.time_scale or 'utc', str(path))
    sun, observer = np.asarray(points.sun), np.asarray(points.observer)
    if not options.light_time:                      # back to the reception times
        jd = jd + np.linalg.norm(observer, axis=1) * LIGHT_DAYS_PER_AU
    notes += (f'{path}: no errors in a DAMIT file: each point given sigma = '
              f'{options.sigma:g} mag',)
    return campaign(path, jd, points, sun, observer, options.light_time, notes)

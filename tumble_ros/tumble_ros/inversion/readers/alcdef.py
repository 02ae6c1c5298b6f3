"""
ALCDEF, the Minor Planet Center's lightcurve exchange format, with the geometry from Horizons.

A file holds lightcurve blocks, each a metadata block then its data::

    STARTMETADATA
    OBJECTNUMBER=99942
    OBJECTNAME=Apophis
    SESSIONDATE=2021-03-10
    LTCAPP=NONE                 <- NONE, or AVERAGE / POINT: the times are light-time corrected
    REDUCEDMAGS=NONE            <- NONE, or AVERAGE (UCORMAG added) / POINT: reduced magnitudes
    DIFFMAGS=TRUE               <- differential magnitudes
    STANDARD=INTERNAL           <- or TRANSFORMED: on a standard system
    DELIMITER=PIPE              <- or TAB
    ENDMETADATA
    DATA=2459284.612345|15.213|0.012
    ...
    ENDDATA

DATA lines give JD (UTC unless ``time_scale`` says), the magnitude and its error (MAGERR; a
line without it gets ``sigma``); other fields are ignored; other keywords are read but not used
except as said here (COMMENT lines are free). The geometry comes from two Horizons tables
(``geometry``). The magnitudes become apparent ones: a block of reduced magnitudes has its
reduction undone (AVERAGE: m - UCORMAG, UCORMAG being the -5 log10(r Delta) the observer added;
POINT: m + 5 log10(r Delta) from the ephemeris). A block has its own free offset unless its
magnitudes are on a standard system (STANDARD=TRANSFORMED and DIFFMAGS=FALSE), or ``calibrated``
says otherwise. OBJECTNUMBER must name the ephemeris' asteroid when both say which it is.
"""
from __future__ import annotations

from pathlib import Path
import re

import numpy as np

from .common import campaign, fail, number, Points, read_text, ReadOptions
from .geometry import HorizonsGeometry
from .timescales import to_tdb
from ..campaign import Campaign

__all__ = ['read_alcdef', 'looks_like_alcdef', 'LTCAPP', 'REDUCEDMAGS']

#: LTCAPP -> whether the block's times are light-time corrected
LTCAPP = {'NONE': False, 'AVERAGE': True, 'POINT': True}
REDUCEDMAGS = ('NONE', 'AVERAGE', 'POINT')
_DELIMITERS = {'PIPE': '|', 'TAB': '\t'}
_FIELDS = ('JD', 'MAG', 'MAGERR')


def looks_like_alcdef(text: str) -> bool:
    """Whether ``text`` holds an ALCDEF metadata block."""
    return re.search(r'^\s*STARTMETADATA\s*$', text[:65536], re.MULTILINE) is not None


class _Block:
    """One ALCDEF block as read: its metadata, its first line, its points' rows."""

    def __init__(self, line: int) -> None:
        self.line = line
        self.meta: dict[str, str] = {}
        self.rows: list[tuple[int, float, float, float | None]] = []

    def key(self, name: str, default: str = '') -> str:
        return self.meta.get(name, default).strip().upper()


def _blocks(path: Path, text: str) -> list[_Block]:
    """Return the blocks; refuse a line out of place (data outside a block, a missing END)."""
    blocks: list[_Block] = []
    state = 'outside'          # then 'metadata', 'data' inside blocks[-1]
    line = 0
    for line, raw in enumerate(text.splitlines(), 1):
        body = raw.strip()
        if not body:
            continue
        word = body.upper()
        if word == 'STARTMETADATA':
            if state != 'outside':
                fail(path, line, f'STARTMETADATA inside the block of line {blocks[-1].line} '
                     '(ENDMETADATA or ENDDATA missing)')
            blocks.append(_Block(line))
            state = 'metadata'
        elif word == 'ENDMETADATA':
            if state != 'metadata':
                fail(path, line, 'ENDMETADATA without STARTMETADATA')
            state = 'data'
        elif word == 'ENDDATA':
            if state != 'data':
                fail(path, line, 'ENDDATA outside a data block')
            state = 'outside'
        elif state == 'metadata':
            _metadata(path, line, body, blocks[-1])
        elif state == 'data':
            _data(path, line, body, blocks[-1])
        else:
            fail(path, line, f'{body[:40]!r} outside a block (STARTMETADATA ... ENDDATA)')
    if state != 'outside':
        fail(path, line, f'the block of line {blocks[-1].line} has no '
             f'{"ENDMETADATA" if state == "metadata" else "ENDDATA"}')
    if not blocks:
        fail(path, None, 'no ALCDEF block (STARTMETADATA ... ENDDATA)')
    return blocks


def _metadata(path: Path, line: int, body: str, block: _Block) -> None:
    if '=' not in body:
        fail(path, line, f'a metadata line is KEYWORD=VALUE, got {body[:60]!r}')
    key, value = body.split('=', 1)
    if key.strip().upper() != 'COMMENT':
        block.meta[key.strip().upper()] = value.strip()


def _data(path: Path, line: int, body: str, block: _Block) -> None:
    if not body.upper().startswith('DATA='):
        fail(path, line, f'a data line starts with DATA=, got {body[:40]!r}')
    delimiter = block.key('DELIMITER', 'PIPE')
    if delimiter not in _DELIMITERS:
        fail(path, line, f'DELIMITER={delimiter} not read (PIPE or TAB)')
    fields = body[5:].split(_DELIMITERS[delimiter])
    if len(fields) < 2:
        fail(path, line, f'{len(fields)} field: a DATA line gives JD{_DELIMITERS[delimiter]}MAG'
             f'{_DELIMITERS[delimiter]}MAGERR')
    values = [number(path, line, name, text) for name, text in zip(_FIELDS, fields)]
    if abs(values[1]) > 100.0:
        fail(path, line, f'MAG = {values[1]:g} is not a magnitude (|mag| <= 100)')
    if len(values) == 3 and not 1e-6 <= values[2] <= 100.0:
        fail(path, line, f'MAGERR = {values[2]:g} must be in [1e-06, 100] mag')
    block.rows.append((line, values[0], values[1], values[2] if len(values) == 3 else None))


def _check_object(path: Path, block: _Block, geometry: HorizonsGeometry) -> None:
    number_ = block.meta.get('OBJECTNUMBER', '').strip()
    if number_ and number_ != '0' and geometry.asteroid and \
            not re.search(rf'(^|\D){re.escape(number_)}(\D|$)', geometry.asteroid):
        fail(path, block.line, f'OBJECTNUMBER={number_} but the ephemeris is of '
             f'{geometry.asteroid}: give the tables of this asteroid')


def _points(path: Path, blocks: list[_Block], options: ReadOptions) -> Points:
    points = Points(path)
    for block in blocks:
        if not block.rows:
            fail(path, block.line, 'the block has no DATA lines')
        ltcapp = block.key('LTCAPP', 'NONE')
        if ltcapp not in LTCAPP:
            fail(path, block.line, f'LTCAPP={ltcapp} not read (one of {", ".join(LTCAPP)})')
        reduced = block.key('REDUCEDMAGS', 'NONE')
        if reduced not in REDUCEDMAGS:
            fail(path, block.line, f'REDUCEDMAGS={reduced} not read (one of '
                 f'{", ".join(REDUCEDMAGS)})')
        if reduced == 'AVERAGE' and 'UCORMAG' not in block.meta:
            fail(path, block.line, 'REDUCEDMAGS=AVERAGE without UCORMAG: the reduction cannot be '
                 'undone')
        standard = block.key('STANDARD') == 'TRANSFORMED' and block.key('DIFFMAGS') == 'FALSE'
        calibrated = standard if options.calibrated is None else options.calibrated
        name = ' '.join(filter(None, (path.name, block.meta.get('OBJECTNAME', '').strip(),
                                      block.meta.get('SESSIONDATE', '').strip(),
                                      f'(line {block.line})')))
        points.new_block(name, not calibrated)
        for line, jd, mag, err in block.rows:
            points.add(line, jd, mag, options.sigma if err is None else err, LTCAPP[ltcapp])
    return points


def read_alcdef(path: Path, options: ReadOptions) -> Campaign:
    """Read an ALCDEF file (module docstring) with ``options.ephemeris``; one-line refusals."""
    blocks = _blocks(path, read_text(path, 'ALCDEF file'))
    if options.ephemeris is None:
        fail(path, None, 'ALCDEF gives no geometry: give ephemeris=(the asteroid about the Sun, '
             'the asteroid about the observer), two Horizons vector tables')
    geometry = HorizonsGeometry.read(*options.ephemeris)
    for block in blocks:
        _check_object(path, block, geometry)
    points = _points(path, blocks, options)
    jd, notes = to_tdb(np.asarray(points.jd), options.time_scale or 'utc', str(path))
    times, sun, observer = geometry.at(jd, np.asarray(points.corrected), options.light_time,
                                       path, np.asarray(points.line))
    magnitude = np.asarray(points.magnitude)
    block_of = np.asarray(points.block)
    distance = 5.0 * np.log10(np.linalg.norm(sun, axis=1) * np.linalg.norm(observer, axis=1))
    for k, block in enumerate(blocks):
        mine = block_of == k
        reduced = block.key('REDUCEDMAGS', 'NONE')
        if reduced == 'AVERAGE':
            ucormag = number(path, block.line, 'UCORMAG', block.meta['UCORMAG'])
            magnitude[mine] -= ucormag
        elif reduced == 'POINT':
            magnitude[mine] += distance[mine]
    points.magnitude = list(magnitude)
    if any(err is None for block in blocks for *_, err in block.rows):
        notes += (f'{path}: DATA lines without MAGERR given sigma = {options.sigma:g} mag',)
    return campaign(path, times, points, sun, observer, options.light_time,
                    notes + (f'geometry from {geometry.sources}',))

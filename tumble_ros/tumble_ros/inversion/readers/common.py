"""
What every photometry reader shares: the options, the bounded read, the one-line refusals.

A reader reads a user's file through ``core.model.user_files`` (a regular file, at most
:data:`MAX_CAMPAIGN_BYTES`, UTF-8: a FIFO, a device, a directory are refused by their kind
before any read), at most :data:`MAX_CAMPAIGN_ROWS` points, and refuses bad input with one
:class:`~tumble_ros.inversion.campaign.CampaignError` line naming the file, the line and why
(:func:`fail`). docs/inversion.md, "Your photometry".
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path
from typing import NoReturn

import numpy as np

from tumble_ros.core.model.user_files import decode_user_text, read_user_bytes
from tumble_ros.core.torques.orbits import SPEED_OF_LIGHT
from tumble_ros.core.units import KM_PER_AU

from ..campaign import Campaign, CampaignError

__all__ = ['ReadOptions', 'Points', 'fail', 'number', 'read_text', 'LIGHT_DAYS_PER_AU',
           'MAX_CAMPAIGN_BYTES', 'MAX_CAMPAIGN_ROWS', 'DEFAULT_SIGMA', 'JD_RANGE']

#: the largest photometry file read [bytes]: 10^5 points of ~300 characters
MAX_CAMPAIGN_BYTES = 32 * 1024 * 1024
#: the most points a file may hold: a campaign is ~10^4 points (a month of nights at one point
#: every few minutes); ten times that is still read in a second
MAX_CAMPAIGN_ROWS = 100_000
#: the error given to points whose file states none (DAMIT, a CSV without errors, a
#: recording) [mag]: the 0.01-0.02 mag of good ground photometry; ``sigma=`` changes it
DEFAULT_SIGMA = 0.01
#: the light time of one au [d] (499.005 s)
LIGHT_DAYS_PER_AU = KM_PER_AU / SPEED_OF_LIGHT / 86400.0
#: the Julian dates read (the years 1800 to 2200): a time outside is another unit (an MJD
#: read as a JD, a time in hours), refused with its line
JD_RANGE = (2378496.5, 2524593.5)


@dataclass(frozen=True)
class ReadOptions:
    """
    How to read a file (``read_campaign``'s keywords; docs/inversion.md, "Your photometry").

    ``ephemeris`` (asteroid about the Sun, asteroid about the observer): two Horizons vector
    tables, for the formats without geometry (ALCDEF, a CSV without vectors); ``time_scale``
    the scale of the file's times (``utc``, ``tt``, ``tdb``; None: the format's default, UTC
    for observers' files); ``light_time`` whether the campaign's times are the emission times
    (the inversion's convention) or the reception times; ``sigma`` [mag] the error of points
    given without one; ``calibrated`` None (the format says), True (every block shares the
    model's offset) or False (each block its own offset); ``times_corrected`` whether a CSV's
    times are already light-time corrected; ``epoch_jd`` the Julian date (TDB) of a
    recording's t = 0; ``orbital_frame_is_ecliptic`` read a recording whose frame is not
    ecliptic J2000 as if it were.
    """

    ephemeris: tuple[str, str] | None = None
    time_scale: str | None = None
    light_time: bool = True
    sigma: float = DEFAULT_SIGMA
    calibrated: bool | None = None
    times_corrected: bool = False
    epoch_jd: float | None = None
    orbital_frame_is_ecliptic: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.sigma) and 1e-6 <= self.sigma <= 10.0):
            raise CampaignError(f'sigma = {self.sigma!r}: the error of points given without '
                                'one must be in [1e-6, 10] mag')
        if self.ephemeris is not None and len(self.ephemeris) != 2:
            raise CampaignError('ephemeris: give two Horizons vector tables, (the asteroid '
                                'about the Sun, the asteroid about the observer), not '
                                f'{self.ephemeris!r}')


def fail(path: Path | str, line: int | None, why: str) -> NoReturn:
    """Raise the one-line CampaignError ``FILE line N: why`` (``FILE: why`` without a line)."""
    where = f'{path} line {line}' if line is not None else f'{path}'
    raise CampaignError(f'{where}: {" ".join(why.split())}')


def number(path: Path, line: int, name: str, text: str) -> float:
    """Return the finite number ``text`` of the field ``name`` on ``line``; else refuse it."""
    try:
        value = float(text)
    except ValueError:
        fail(path, line, f'{name} = {text.strip()[:40]!r} is not a number')
    if not math.isfinite(value):
        fail(path, line, f'{name} = {text.strip()} must be a finite number')
    return value


def read_text(path: Path, kind: str, limit: int = MAX_CAMPAIGN_BYTES,
              limit_name: str = 'MAX_CAMPAIGN_BYTES') -> str:
    """Return the text of the user's file ``path`` (a ``kind``, e.g. 'ALCDEF file'), bounded."""
    what = f'{path}'
    data = read_user_bytes(path, what, limit, limit_name, kind, CampaignError)
    return decode_user_text(data, what, CampaignError)


@dataclass
class Points:
    """
    The points of a file as they are read, block by block, before the campaign is made.

    Per point: ``jd`` [d] the Julian date in the file's time scale (converted to TDB at once
    for all, :func:`~.timescales.to_tdb`), ``magnitude`` [mag], ``sigma`` [mag], ``line`` in
    the file,
    ``block`` its block's index, ``corrected`` whether its time is light-time corrected, and
    (when the file gives them) ``sun``, ``observer`` [au]; per block ``names`` and
    ``free_offset``. :meth:`add` refuses the point beyond MAX_CAMPAIGN_ROWS.
    """

    path: Path
    jd: list[float] = field(default_factory=list)
    magnitude: list[float] = field(default_factory=list)
    sigma: list[float] = field(default_factory=list)
    line: list[int] = field(default_factory=list)
    block: list[int] = field(default_factory=list)
    corrected: list[bool] = field(default_factory=list)
    sun: list[tuple[float, float, float]] = field(default_factory=list)
    observer: list[tuple[float, float, float]] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    free_offset: list[bool] = field(default_factory=list)

    def new_block(self, name: str, free_offset: bool) -> int:
        """Open a block; return its index."""
        self.names.append(name)
        self.free_offset.append(free_offset)
        return len(self.names) - 1

    def add(self, line: int, jd: float, magnitude: float, sigma: float, corrected: bool,
            sun: tuple[float, float, float] | None = None,
            observer: tuple[float, float, float] | None = None,
            block: int | None = None) -> None:
        """Add a point of ``block`` (default the last opened); refuse one too many."""
        block = len(self.names) - 1 if block is None else block
        if len(self.jd) == MAX_CAMPAIGN_ROWS:
            fail(self.path, line, f'more than {MAX_CAMPAIGN_ROWS:,} points (MAX_CAMPAIGN_ROWS; a '
                 'campaign holds ~10^4): bin or split the file')
        if not JD_RANGE[0] <= jd <= JD_RANGE[1]:
            fail(self.path, line, f'the time {jd:.6f} is not a Julian date of the years 1800 to '
                 '2200 (an MJD, or a time in other units?)')
        if self.block and self.block[-1] == block and jd < self.jd[-1]:
            fail(self.path, line, f"the time {jd:.6f} is before the previous point's (line "
                 f"{self.line[-1]}, {self.jd[-1]:.6f}): a lightcurve's points must be in time "
                 'order')
        self.jd.append(jd)
        self.magnitude.append(magnitude)
        self.sigma.append(sigma)
        self.line.append(line)
        self.block.append(block)
        self.corrected.append(corrected)
        if sun is not None and observer is not None:
            self.sun.append(sun)
            self.observer.append(observer)


def campaign(path: Path, jd: np.ndarray, points: Points, sun: np.ndarray, observer: np.ndarray,
             light_time: bool, notes: tuple[str, ...] = ()) -> Campaign:
    """Return the Campaign of ``points`` with times ``jd`` and geometry, sorted in time."""
    if not points.jd:
        fail(path, None, 'no points')
    order = np.argsort(jd, kind='stable')
    return Campaign(jd[order], np.asarray(points.magnitude)[order],
                    np.asarray(points.sigma)[order], sun[order], observer[order],
                    np.asarray(points.block, dtype=np.int64)[order], tuple(points.names),
                    tuple(points.free_offset), str(path), light_time, notes)

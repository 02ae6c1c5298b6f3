"""
Photometry as observers have it, read into a :class:`~tumble_ros.inversion.campaign.Campaign`.

One entry, :func:`read_campaign`, and a registry of formats (:data:`FORMATS`), each a reader
``(path, ReadOptions) -> Campaign``:

* ``damit``: the DAMIT lightcurve format (``lc.txt``), geometry in the file (:mod:`.damit`);
* ``alcdef``: the MPC's ALCDEF, geometry from Horizons tables (:mod:`.alcdef`);
* ``csv``: the project's photometry CSV, geometry in its columns or from Horizons tables
  (:mod:`.csv_file`);
* ``recording``: a tumble_ros MCAP recording's ``lightcurve`` topic (:mod:`.recording`).

A format is named, or recognised: ``.mcap`` or the MCAP magic is a recording, a
``STARTMETADATA`` line ALCDEF, a first line holding one whole number then "n flag" DAMIT, a
``.csv`` (or a first line with commas) a CSV. Several files are read alike and merged
(``Campaign.merged``: their blocks kept apart). docs/inversion.md, "Your photometry".
"""
from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Callable, Sequence

from .alcdef import looks_like_alcdef, read_alcdef
from .common import DEFAULT_SIGMA, MAX_CAMPAIGN_BYTES, read_text, ReadOptions
from .csv_file import read_csv
from .damit import looks_like_damit, read_damit
from .recording import MCAP_MAGIC, read_recording
from .timescales import TIME_SCALES, to_tdb
from ..campaign import Campaign, CampaignError

__all__ = ['read_campaign', 'CampaignFormat', 'FORMATS', 'ReadOptions', 'DEFAULT_SIGMA',
           'MAX_CAMPAIGN_BYTES', 'TIME_SCALES', 'to_tdb', 'sniff_format']


@dataclass(frozen=True)
class CampaignFormat:
    """A format: its name, its reader, its file extensions, whether a text is of it."""

    name: str
    read: Callable[[Path, ReadOptions], Campaign]
    extensions: tuple[str, ...]
    looks_like: Callable[[str], bool] | None
    what: str


def _looks_like_csv(text: str) -> bool:
    first = next((line for line in text.splitlines()
                  if line.strip() and not line.lstrip().startswith('#')), '')
    return ',' in first and any(c.isalpha() for c in first)


#: the formats read, by name (the order of recognition: the most specific first)
FORMATS: dict[str, CampaignFormat] = {f.name: f for f in (
    CampaignFormat('recording', read_recording, ('.mcap',), None,
                   'a tumble_ros recording (lightcurve topic)'),
    CampaignFormat('alcdef', read_alcdef, ('.alcdef',), looks_like_alcdef,
                   "ALCDEF (the MPC's lightcurve exchange format)"),
    CampaignFormat('damit', read_damit, (), looks_like_damit, 'the DAMIT lightcurve format'),
    CampaignFormat('csv', read_csv, ('.csv',), _looks_like_csv, "the project's photometry CSV"),
)}


def sniff_format(path: Path) -> CampaignFormat:
    """Return the format of ``path``: by its extension, else by its content; refuse unknown."""
    for fmt in FORMATS.values():
        if path.suffix.lower() in fmt.extensions:
            return fmt
    with_magic = _starts_with_mcap(path)
    if with_magic:
        return FORMATS['recording']
    text = read_text(path, 'photometry file')
    for fmt in FORMATS.values():
        if fmt.looks_like is not None and fmt.looks_like(text):
            return fmt
    raise CampaignError(f'{path}: cannot tell its format: name it (format= one of '
                        f'{", ".join(FORMATS)})')


def _starts_with_mcap(path: Path) -> bool:
    """Whether a regular file ``path`` starts with the MCAP magic (a non-regular one: no)."""
    import stat
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return False                 # refused with its reason by the text reader
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return False
        return os.read(fd, len(MCAP_MAGIC)) == MCAP_MAGIC
    finally:
        os.close(fd)


def read_campaign(paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
                  format: str | None = None, *,         # noqa: A002 (the brief's name)
                  ephemeris: tuple[str | os.PathLike[str], str | os.PathLike[str]] | None = None,
                  time_scale: str | None = None, light_time: bool = True,
                  sigma: float = DEFAULT_SIGMA, calibrated: bool | None = None,
                  times_corrected: bool = False, epoch_jd: float | None = None,
                  orbital_frame_is_ecliptic: bool = False) -> Campaign:
    """
    Read one photometry file, or several merged, into one Campaign.

    ``format``: a name of :data:`FORMATS`, or None to recognise each file. ``ephemeris``: two
    Horizons vector tables, the asteroid about the Sun and about the observer (ALCDEF, a CSV
    without vectors). ``time_scale``: ``utc``, ``tt`` or ``tdb`` of the files' times (None: the
    format's default, UTC). ``light_time``: the campaign's times are emission times (True, the
    inversion's) or reception times. The rest: :class:`ReadOptions`. CampaignError, one line
    naming the file (and the line) and why.
    """
    if format is not None and format not in FORMATS:
        raise CampaignError(f'format {format!r} not read: one of {", ".join(FORMATS)}')
    if time_scale is not None and time_scale.lower() not in TIME_SCALES:
        raise CampaignError(f'time_scale {time_scale!r} not read: one of '
                            f'{", ".join(TIME_SCALES)}')
    options = ReadOptions(None if ephemeris is None else (os.fspath(ephemeris[0]),
                                                          os.fspath(ephemeris[1])),
                          time_scale, light_time, sigma, calibrated, times_corrected,
                          epoch_jd, orbital_frame_is_ecliptic)
    files = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    if not files:
        raise CampaignError('read_campaign: no file given')
    result: Campaign | None = None
    for name in files:
        path = Path(os.fspath(name))
        fmt = FORMATS[format] if format is not None else sniff_format(path)
        one = fmt.read(path, options)
        result = one if result is None else result.merged(one)
    assert result is not None
    return result

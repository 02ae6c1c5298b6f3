"""
Observation times to Julian dates in TDB, with astropy's ``Time`` (the field's standard).

A Julian date in UTC, TT or TDB (:data:`TIME_SCALES`) becomes JD TDB by
``astropy.time.Time(jd, format='jd', scale=...).tdb``: UTC -> TAI by the leap seconds, TAI ->
TT by 32.184 s, TT -> TDB by the periodic terms (< 1.7 ms) at the geocentre. In 2020, TDB -
UTC = 37 + 32.184 s (+ 0.9 ms).

Nothing is downloaded: the conversion runs with ``astropy.utils.iers.conf.auto_download``
False, so the leap seconds are those bundled with astropy (the astropy-iers-data package and
erfa's table). The bundled table is valid to its expiry date (:func:`leap_second_expiry`;
2027-06-28 for astropy-iers-data 0.2026.11.16): a UTC date after it is converted with the last
known offset, UTC - TAI = -37 s, wrong by one second per leap second announced later (none is
expected: leap seconds are to stop by 2035), and the campaign's notes say so. No UT1 (IERS
Earth rotation) is needed: TT -> TDB at the geocentre uses none.
"""
from __future__ import annotations

import datetime
import warnings

import numpy as np

from ..campaign import CampaignError

__all__ = ['TIME_SCALES', 'MJD_ZERO', 'to_tdb', 'leap_second_expiry']

#: the time scales read
TIME_SCALES = ('utc', 'tt', 'tdb')
#: JD of MJD 0 [d]
MJD_ZERO = 2400000.5


def leap_second_expiry() -> datetime.datetime:
    """Return the date until which the bundled leap-second table is known to hold (UTC)."""
    from astropy.utils import iers

    with iers.conf.set_temp('auto_download', False):
        table = iers.LeapSeconds.auto_open()          # what astropy's UTC conversions load
    expires: datetime.datetime = table.expires.to_datetime()
    return expires


def to_tdb(jd: np.ndarray, scale: str, what: str) -> tuple[np.ndarray, tuple[str, ...]]:
    """
    Return (the Julian dates ``jd`` [d] of ``scale`` as JD TDB [d], notes).

    ``what`` names the file in a refusal (an unknown scale). The two-part Julian date keeps
    ~20 us (float64 at JD 2.46e6 holds ~40 us). ``notes``: one line when a UTC date lies
    beyond the leap-second table (module docstring).
    """
    from astropy.time import Time
    from astropy.utils import iers

    scale = scale.lower()
    if scale not in TIME_SCALES:
        raise CampaignError(f'{what}: time scale {scale!r} not read: one of '
                            f'{", ".join(TIME_SCALES)}')
    jd = np.asarray(jd, dtype=float)
    if scale == 'tdb' or jd.size == 0:
        return jd.copy(), ()
    whole = np.floor(jd)
    with iers.conf.set_temp('auto_download', False), warnings.catch_warnings():
        warnings.simplefilter('ignore')   # erfa's 'dubious year': beyond the table, noted below
        tdb = Time(whole, jd - whole, format='jd', scale=scale).tdb
    out = (tdb.jd1 - whole) + tdb.jd2 + whole
    notes: tuple[str, ...] = ()
    if scale == 'utc':
        expiry = leap_second_expiry()
        if float(jd.max()) > Time(expiry, scale='utc').jd:
            notes = (f'{what}: UTC dates after {expiry:%Y-%m-%d} (the bundled leap-second '
                     "table's expiry) taken with UTC - TAI = -37 s: one second off per leap "
                     'second announced later',)
    return out, notes

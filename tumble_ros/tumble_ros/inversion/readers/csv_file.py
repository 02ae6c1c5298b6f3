"""
The project's photometry CSV (``analysis/photometry_file.py``) as a campaign.

The CSV ``analyze --photometry`` reads (its columns, bounds and refusals: that module), with
for the inversion:

* times: ``jd`` or ``mjd`` [d], their scale UTC unless the column says (``jd_tdb``, ``mjd_tt``
  ...) or ``time_scale`` does; reception times unless ``times_corrected``. ``hjd`` and ``bjd``
  (corrected to the Sun or the barycentre, not to the asteroid) and times in hours are refused;
* geometry: the vectors ``sun_x..obs_z`` [au] of the file, else the Horizons tables of
  ``ephemeris`` (the distances ``r``, ``delta`` alone do not say where the Sun and the observer
  are: refused without tables);
* blocks: the ``block`` (or ``night``) column's labels, else a new block after each gap of
  more than :data:`BLOCK_GAP_DAYS`; each has its own offset unless ``calibrated``;
* errors: the error column, else ``sigma`` for every point.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from tumble_ros.analysis.photometry_file import Photometry, read_photometry, TIME_SCALES
from tumble_ros.errors import AnalysisError

from .common import campaign, fail, LIGHT_DAYS_PER_AU, Points, ReadOptions
from .geometry import HorizonsGeometry
from .timescales import MJD_ZERO, to_tdb
from ..campaign import Campaign, CampaignError

__all__ = ['read_csv', 'BLOCK_GAP_DAYS']

#: a gap longer than this between two points starts a new block (a new night) [d]
BLOCK_GAP_DAYS = 0.25


def _scale(path: Path, column: str, options: ReadOptions) -> tuple[str, str]:
    """Return (jd or mjd, the time scale) of the time column; refuse one not read."""
    kind, _, said = column.partition('_')
    if kind not in ('jd', 'mjd') or (said and said not in TIME_SCALES):
        fail(path, None, f'the time column {column!r} is not read for the inversion: give jd or '
             'mjd (with its scale: jd_utc, jd_tt, jd_tdb) of reception, not heliocentric or '
             'barycentric times nor hours')
    if said and options.time_scale and said != options.time_scale.lower():
        fail(path, None, f'the time column {column!r} says {said}, time_scale says '
             f'{options.time_scale}')
    return kind, said or options.time_scale or 'utc'


def _labels(data: Photometry, jd: np.ndarray) -> list[str]:
    """Each point's block label: the file's, else the night (split at gaps)."""
    if data.block is not None:
        return list(data.block)
    night = np.concatenate([[0], np.cumsum(np.diff(jd) > BLOCK_GAP_DAYS)])
    return [f'night {k + 1}' for k in night]


def read_csv(path: Path, options: ReadOptions) -> Campaign:
    """Read a photometry CSV (module docstring) into a Campaign; one-line refusals."""
    try:
        data = read_photometry(path)
    except AnalysisError as err:
        raise CampaignError(str(err)) from None
    assert data.time is not None and data.lines is not None
    kind, scale = _scale(path, data.time_column, options)
    raw = data.time + (MJD_ZERO if kind == 'mjd' else 0.0)
    labels = _labels(data, raw)
    points = Points(path)
    blocks: dict[str, int] = {}
    free = not bool(options.calibrated)
    order = np.argsort(np.array([blocks.setdefault(label, len(blocks)) for label in labels]),
                       kind='stable')                       # block by block, each in time order
    for name in blocks:
        points.new_block(f'{path.name} {name}', free)
    for k in order:
        points.add(int(data.lines[k]), float(raw[k]), float(data.magnitude[k]),
                   options.sigma if data.sigma is None else float(data.sigma[k]),
                   options.times_corrected, block=blocks[labels[k]])
    jd, notes = to_tdb(np.asarray(points.jd), scale, str(path))
    index = np.asarray(order)
    if data.sun is not None and data.observer is not None:
        sun, observer = data.sun[index], data.observer[index]
        tau = np.linalg.norm(observer, axis=1) * LIGHT_DAYS_PER_AU
        if options.light_time != options.times_corrected:
            jd = jd - tau if options.light_time else jd + tau
    else:
        if options.ephemeris is None:
            fail(path, None, 'no geometry: give the vectors sun_x, sun_y, sun_z, obs_x, obs_y, '
                 'obs_z [au] (r and delta alone do not say where the Sun and the observer '
                 'are), or ephemeris=(the asteroid about the Sun, about the observer)')
        geometry = HorizonsGeometry.read(*options.ephemeris)
        jd, sun, observer = geometry.at(jd, np.full(jd.size, options.times_corrected),
                                        options.light_time, path, np.asarray(points.line))
        notes += (f'geometry from {geometry.sources}',)
    if data.sigma is None:
        notes += (f'{path}: no error column: each point given sigma = {options.sigma:g} mag',)
    return campaign(path, jd, points, sun, observer, options.light_time, notes)

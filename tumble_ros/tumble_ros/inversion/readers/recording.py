"""
The project's own recordings: the ``lightcurve`` topic of a tumble_ros MCAP file as a campaign.

Each lit sample (finite magnitude, brightness > 0) of the run's ``lightcurve`` topic is a point:
its recorded magnitude (apparent: -2.5 log10(B / B_ref) + 5 log10(r Delta)), the error
``sigma`` (a synthetic lightcurve has none), one block with the shared offset (its magnitudes
are on one scale) unless ``calibrated=False``.

Geometry: the record gives the Sun and the observer in body axes; the campaign wants them in
the inertial frame, so they are recomputed where the run computed them,
``core.photometry.observer_geometry`` on the recorded scenario at the emission times, in the
scenario's orbital frame. That frame is ecliptic J2000 for a scenario with a Kepler orbit or a
flyby (its elements are ecliptic J2000 by the project's convention, ``analysis.display``); a
circular-orbit run's frame is its own orbital frame: refused unless
``orbital_frame_is_ecliptic`` (then the pole found is in that frame).

Times: the run's time t [yr] (a sample's emission time; the recorded stamp is the reception
time t + Delta / c when ``lightcurve.light_time``) becomes JD TDB = ``epoch_jd`` + 365.25 t;
``epoch_jd`` default: the epoch of the scenario's Horizons perturber when it has one, else
J2000.0 (2451545.0), said in the notes.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from tumble_ros.analysis.display import ELEMENTS_FRAME, frame_name
from tumble_ros.analysis.recording import load_recording
from tumble_ros.core.photometry.lightcurve import observer_geometry
from tumble_ros.core.torques.ephemeris import DAYS_PER_YEAR
from tumble_ros.core.units import SECONDS_PER_YEAR
from tumble_ros.errors import AnalysisError
from tumble_ros.io import McapError

from .common import campaign, fail, MAX_CAMPAIGN_ROWS, Points, ReadOptions
from .geometry import EPOCH_JD
from ..campaign import Campaign, CampaignError

__all__ = ['read_recording', 'MCAP_MAGIC']

#: the first bytes of an MCAP file
MCAP_MAGIC = b'\x89MCAP'
#: the lightcurve topic's columns (topics.SAMPLE_TOPICS)
_BRIGHTNESS, _MAGNITUDE, _LIGHT_TIME = 0, 1, 7


def _epoch(scenario, options: ReadOptions) -> tuple[float, str]:
    if options.epoch_jd is not None:
        return float(options.epoch_jd), f'epoch_jd = {options.epoch_jd} (given)'
    for perturber in getattr(scenario, 'all_perturbers', ()):
        epoch = getattr(perturber.source, 'epoch_jd', 0.0)
        if epoch:
            return float(epoch), f"epoch_jd = {epoch} (the {perturber.name} ephemeris' epoch)"
    return EPOCH_JD, f"epoch_jd = {EPOCH_JD} (J2000.0: the default; give epoch_jd= the run's)"


def read_recording(path: Path, options: ReadOptions) -> Campaign:
    """Read a recording's lightcurve topic (module docstring) into a Campaign."""
    try:
        rec = load_recording(path)
    except (AnalysisError, McapError, OSError) as err:
        raise CampaignError(' '.join(f'{err}'.split()) if str(path) in str(err)
                            else f'{path}: {" ".join(str(err).split())}') from None
    scenario = rec.scenario
    if scenario is None:
        fail(path, None, f'no scenario in the recording ({rec.scenario_error or "none"}): '
             'its geometry cannot be recomputed')
    frame = frame_name(scenario)
    if frame != ELEMENTS_FRAME and not options.orbital_frame_is_ecliptic:
        fail(path, None, f"the run's frame is its {frame}, not ecliptic J2000 (a circular "
             'orbit): give orbital_frame_is_ecliptic=True to invert in that frame')
    magnitude = rec.lightcurve[:, _MAGNITUDE]
    lit = np.isfinite(magnitude) & (rec.lightcurve[:, _BRIGHTNESS] > 0.0)
    if not np.any(lit):
        fail(path, None, 'no lit sample on the lightcurve topic (lightcurve.enabled false?)')
    if lit.sum() > MAX_CAMPAIGN_ROWS:
        fail(path, None, f'{int(lit.sum()):,} lightcurve samples, above MAX_CAMPAIGN_ROWS = '
             f'{MAX_CAMPAIGN_ROWS:,}: record fewer samples')
    delay = rec.lightcurve[lit, _LIGHT_TIME] / SECONDS_PER_YEAR               # [yr]
    stamp = rec.lightcurve_t[lit]
    emitted = stamp - delay if scenario.lightcurve.light_time else stamp
    geometry = observer_geometry(scenario, emitted, scenario.lightcurve)
    sun = geometry.sun * geometry.sun_distance[:, None]
    observer = geometry.observer * geometry.observer_distance[:, None]
    epoch, said = _epoch(scenario, options)
    t = emitted if options.light_time else emitted + delay
    points = Points(path)
    points.new_block(f'{path.name} lightcurve', options.calibrated is False)
    points.magnitude = list(magnitude[lit])
    points.sigma = [options.sigma] * int(lit.sum())
    points.block = [0] * int(lit.sum())
    points.jd = list(epoch + t * DAYS_PER_YEAR)
    notes = (f'{path}: times JD TDB = {said} + 365.25 t', f'{path}: frame {frame}'
             + ('' if frame == ELEMENTS_FRAME else ' taken as ecliptic J2000 (as asked)'),
             f'{path}: synthetic magnitudes: each point given sigma = {options.sigma:g} mag')
    return campaign(path, np.asarray(points.jd), points, sun, observer, options.light_time,
                    notes)

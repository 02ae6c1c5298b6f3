"""
The time axis of a recording: how many samples, over what span, how evenly spaced.

Times are simulated years [yr] (``Recording.t``, the ``angular_velocity`` stamps converted with
the recorded seconds_per_year); no frame is involved. :func:`same_stamps` pairs the samples of
two series recorded at the same stamps (the comparator's and the attitude's against w).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tumble_ros.core.units import TIME_UNITS

__all__ = ['Sampling', 'UNIFORM_TOL', 'GAP_FACTOR', 'same_stamps', 'sampling', 'runs',
           'display_unit', 'DISPLAY_MIN_UNITS']

#: Intervals within this relative tolerance of the median count as uniform sampling.
UNIFORM_TOL = 1e-6
#: An interval longer than this many times the median is a gap (no samples in between).
GAP_FACTOR = 1.5


@dataclass(frozen=True)
class Sampling:
    """The ``/angular_velocity`` time axis."""

    n: int
    t_first: float
    t_last: float
    duration: float          # t_last - t_first [yr]
    dt: float | None         # median interval [yr] (None for one sample)
    dt_min: float | None
    dt_max: float | None
    uniform: bool            # every interval within UNIFORM_TOL of the median
    gaps: int                # intervals longer than GAP_FACTOR * dt
    duplicates: int          # repeated stamps


def sampling(t: np.ndarray) -> Sampling:
    """Return the time axis of the samples at ``t`` [yr] (repeated stamps counted once)."""
    t = np.asarray(t, dtype=float)
    unique = np.unique(t)
    d = np.diff(unique)
    if len(d) == 0:
        return Sampling(len(t), float(t[0]), float(t[-1]), float(t[-1] - t[0]), None, None, None,
                        True, 0, len(t) - len(unique))
    dt = float(np.median(d))
    uniform = bool(np.all(np.abs(d - dt) <= UNIFORM_TOL * dt))
    return Sampling(len(t), float(unique[0]), float(unique[-1]), float(unique[-1] - unique[0]),
                    dt, float(d.min()), float(d.max()), uniform, int(np.sum(d > GAP_FACTOR * dt)),
                    len(t) - len(unique))


def runs(t: np.ndarray) -> list[tuple[int, int]]:
    """
    Return the runs of samples without a gap: (start, stop) index pairs, in order.

    A gap is an interval longer than :data:`GAP_FACTOR` times the median interval: where the
    comparator published nothing (its model does not apply in an encounter window), or a
    recorder lost samples.
    """
    n = len(t)
    if n < 3:
        return [(0, n)]
    d = np.diff(np.asarray(t, dtype=float))
    cuts = (np.flatnonzero(d > GAP_FACTOR * float(np.median(d))) + 1).tolist()
    edges = [0, *cuts, n]
    return list(zip(edges[:-1], edges[1:]))


def same_stamps(t_a: np.ndarray, t_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the indices (ia, ib) of the samples of a and b at the same time (same stamp).

    Those of :func:`numpy.intersect1d` (each shared stamp once, its first sample); the same
    strictly increasing stamps (the topics of one simulator) are paired at once.
    """
    if (len(t_a) == len(t_b) and len(t_a) > 1 and np.array_equal(t_a, t_b)
            and bool(np.all(t_a[1:] > t_a[:-1]))):
        index = np.arange(len(t_a), dtype=np.intp)
        return index, index.copy()
    _, ia, ib = np.intersect1d(t_a, t_b, assume_unique=False, return_indices=True)
    return ia, ib


#: A run shorter than a year is shown in the largest unit it spans at least this many of.
DISPLAY_MIN_UNITS = 10.0


def display_unit(span: float) -> tuple[str, float]:
    """
    Return (name, years per unit) of the unit a time axis spanning ``span`` [yr] is shown in.

    Years for a year or more (the paper's runs); below, the largest of d, h, min, s that the
    span covers at least :data:`DISPLAY_MIN_UNITS` times: a 144-hour flyby (0.016 yr) in
    hours, a 0.2-year run in days.
    """
    if not span < 1.0:
        return 'yr', TIME_UNITS['yr']
    for name in ('d', 'h', 'min'):
        if span >= DISPLAY_MIN_UNITS * TIME_UNITS[name]:
            return name, TIME_UNITS[name]
    return 's', TIME_UNITS['s']

"""
The time axis of a recording: how many samples, over what span, how evenly spaced.

Times are simulated years [yr] (``Recording.t``, the ``angular_velocity`` stamps converted with
the recorded seconds_per_year); no frame is involved. :func:`same_stamps` pairs the samples of
two series recorded at the same stamps (the comparator's and the attitude's against w).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['Sampling', 'UNIFORM_TOL', 'same_stamps', 'sampling']

#: Intervals within this relative tolerance of the median count as uniform sampling.
UNIFORM_TOL = 1e-6


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
    gaps: int                # intervals longer than 1.5 * dt
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
                    dt, float(d.min()), float(d.max()), uniform, int(np.sum(d > 1.5 * dt)),
                    len(t) - len(unique))


def same_stamps(t_a: np.ndarray, t_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the indices (ia, ib) of the samples of a and b at the same time (same stamp)."""
    _, ia, ib = np.intersect1d(t_a, t_b, assume_unique=False, return_indices=True)
    return ia, ib

"""
A photometric campaign ready for inversion: the one type every reader returns and the fit takes.

Frames and units: times are Julian dates in the TDB scale [d]; when ``light_time_corrected``
they are the emission times at the asteroid (reception time minus distance / c), else the
reception times. Magnitudes [mag] (relative flux is read as -2.5 log10 flux), errors 1 sigma
[mag]. ``sun`` and ``observer`` are the vectors from the asteroid to the Sun and to the
observer, ecliptic J2000 [au], one per point. ``block`` numbers each point's lightcurve block
(a night, or one lightcurve of a DAMIT or ALCDEF file): each block with ``free_offset`` has its
own unknown magnitude offset (relative photometry); a block without is calibrated (reduced or
absolute magnitudes) and shares the model's one offset.

Validated once, at construction (:meth:`Campaign.__post_init__`): a reader gives the file and
line of a bad row itself; what reaches here is refused as :class:`CampaignError` in one line.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tumble_ros.errors import AnalysisError

__all__ = ['Campaign', 'CampaignError', 'MIN_DISTANCE_AU']

#: no real observation is closer to the asteroid's centre than this [au] (~1.5 km)
MIN_DISTANCE_AU = 1e-8


class CampaignError(AnalysisError):
    """Photometry that cannot be inverted as given; the message says why in one line."""


def _vectors(name: str, value: np.ndarray, n: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.shape != (n, 3):
        raise CampaignError(f'{name}: shape {array.shape}, expected ({n}, 3)')
    if not np.all(np.isfinite(array)):
        raise CampaignError(f'{name}: {int(np.sum(~np.isfinite(array).all(axis=1)))} '
                            'vectors are not finite')
    distance = np.linalg.norm(array, axis=1)
    if np.any(distance < MIN_DISTANCE_AU):
        raise CampaignError(f'{name}: {int(np.sum(distance < MIN_DISTANCE_AU))} vectors '
                            f'shorter than {MIN_DISTANCE_AU} au (the vector from the asteroid '
                            'is missing?)')
    return array


@dataclass(frozen=True)
class Campaign:
    """
    n photometric points of one asteroid, in time order, with their geometry.

    ``jd_tdb`` (n,) [d, TDB]; ``magnitude`` (n,) [mag]; ``sigma`` (n,) [mag] > 0;
    ``sun``, ``observer`` (n, 3) asteroid -> Sun, asteroid -> observer, ecliptic J2000 [au];
    ``block`` (n,) int in [0, len(block_names)); ``block_names`` one label per block (the file
    and the night); ``free_offset`` one bool per block; ``source`` the file(s) read;
    ``light_time_corrected`` whether ``jd_tdb`` are emission times.
    """

    jd_tdb: np.ndarray
    magnitude: np.ndarray
    sigma: np.ndarray
    sun: np.ndarray
    observer: np.ndarray
    block: np.ndarray
    block_names: tuple[str, ...]
    free_offset: tuple[bool, ...]
    source: str = ''
    light_time_corrected: bool = False
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        t = np.asarray(self.jd_tdb, dtype=float)
        n = t.size
        if t.ndim != 1 or n == 0:
            raise CampaignError(f'{self.source or "campaign"}: no points')
        for name in ('magnitude', 'sigma'):
            values = np.asarray(getattr(self, name), dtype=float)
            if values.shape != (n,):
                raise CampaignError(f'{name}: shape {values.shape}, expected ({n},)')
            if not np.all(np.isfinite(values)):
                raise CampaignError(f'{name}: {int(np.sum(~np.isfinite(values)))} values are '
                                    'not finite')
            object.__setattr__(self, name, values)
        if not np.all(np.isfinite(t)):
            raise CampaignError(f'jd_tdb: {int(np.sum(~np.isfinite(t)))} times are not finite')
        if np.any(np.diff(t) < 0):
            raise CampaignError('jd_tdb: times are not in order (sort the points, their '
                                'geometry and blocks together)')
        if np.any(self.sigma <= 0):
            raise CampaignError(f'sigma: {int(np.sum(self.sigma <= 0))} errors are not positive')
        block = np.asarray(self.block)
        if block.shape != (n,) or not np.issubdtype(block.dtype, np.integer):
            raise CampaignError(f'block: expected ({n},) integers, got {block.dtype} '
                                f'{block.shape}')
        blocks = len(self.block_names)
        if len(self.free_offset) != blocks:
            raise CampaignError(f'free_offset: {len(self.free_offset)} flags for {blocks} blocks')
        if n and (block.min() < 0 or block.max() >= blocks):
            raise CampaignError(f'block: indices outside [0, {blocks})')
        object.__setattr__(self, 'jd_tdb', t)
        object.__setattr__(self, 'block', block.astype(np.int64))
        object.__setattr__(self, 'sun', _vectors('sun', self.sun, n))
        object.__setattr__(self, 'observer', _vectors('observer', self.observer, n))
        object.__setattr__(self, 'block_names', tuple(self.block_names))
        object.__setattr__(self, 'free_offset', tuple(bool(f) for f in self.free_offset))

    def __len__(self) -> int:
        return int(self.jd_tdb.size)

    @property
    def span_days(self) -> float:
        """Last time minus first [d]."""
        return float(self.jd_tdb[-1] - self.jd_tdb[0])

    def phase_angle(self) -> np.ndarray:
        """Return the Sun-asteroid-observer angle of each point [rad]."""
        s = self.sun / np.linalg.norm(self.sun, axis=1)[:, None]
        o = self.observer / np.linalg.norm(self.observer, axis=1)[:, None]
        return np.arccos(np.clip(np.sum(s * o, axis=1), -1.0, 1.0))

    def reduced_magnitude(self) -> np.ndarray:
        """Magnitude minus 5 log10(r Delta), r and Delta in au [mag]: the distances removed."""
        r = np.linalg.norm(self.sun, axis=1)
        delta = np.linalg.norm(self.observer, axis=1)
        return self.magnitude - 5.0 * np.log10(r * delta)

    def merged(self, other: 'Campaign') -> 'Campaign':
        """Return this campaign and ``other`` as one, in time order, their blocks kept apart."""
        if self.light_time_corrected != other.light_time_corrected:
            raise CampaignError('cannot merge a light-time corrected campaign with one that '
                                'is not')
        order = np.argsort(np.concatenate([self.jd_tdb, other.jd_tdb]), kind='stable')
        both = lambda a, b: np.concatenate([a, b])[order]  # noqa: E731
        return Campaign(both(self.jd_tdb, other.jd_tdb), both(self.magnitude, other.magnitude),
                        both(self.sigma, other.sigma), both(self.sun, other.sun),
                        both(self.observer, other.observer),
                        both(self.block, other.block + len(self.block_names)),
                        self.block_names + other.block_names,
                        self.free_offset + other.free_offset,
                        ' + '.join(s for s in (self.source, other.source) if s),
                        self.light_time_corrected, self.notes + other.notes)

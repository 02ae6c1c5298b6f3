"""
The invariant: drift of the Jacobi integral per segment between impacts.

J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' (:func:`tumble_ros.core.jacobi_integral`; w in body
axes [rad/yr], I normalised, ws [rad/yr], u the Sun direction and z' the orbit normal in body
axes), evaluated with the attitude C body -> orbital from ``attitude`` (quaternion) or else
``euler_angles``, at the stamps of ``angular_velocity``. Times in simulated years.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from tumble_ros.core import jacobi_integral
from tumble_ros.core.model.rotation import euler_to_matrix, quaternion_to_matrix
from tumble_ros.topics import ANGULAR_VELOCITY, ATTITUDE, EULER_ANGLES, SCENARIO

from .impacts import impact_intervals
from .recording import Recording
from .timeaxis import same_stamps

__all__ = ['InvariantDrift', 'JacobiSegment', 'jacobi_drift', 'impact_segments']


@dataclass(frozen=True)
class JacobiSegment:
    """The Jacobi integral over one segment between impacts."""

    index: int
    t_start: float
    t_end: float
    n: int
    j0: float                # J at the segment's first sample
    max_drift: float         # max |J - j0|
    rel_drift: float | None  # max_drift / |j0| (None if j0 = 0)


@dataclass(frozen=True)
class InvariantDrift:
    """The drift of an invariant, per segment, and where the attitude came from."""

    name: str
    attitude_source: str
    segments: tuple[JacobiSegment, ...]
    excluded: int            # samples inside a pulse (J is not conserved there)

    @property
    def worst_rel(self) -> float | None:
        """Return the largest relative drift of any segment (None if none is known)."""
        values = [s.rel_drift for s in self.segments if s.rel_drift is not None]
        return max(values) if values else None


def _attitude_matrices(rec: Recording) -> tuple[np.ndarray, np.ndarray, str] | None:
    """Return (indices into rec.t, C body->orbital (k, 3, 3), source) at the omega stamps."""
    if len(rec.quaternion_t):
        ia, ib = same_stamps(rec.t, rec.quaternion_t)
        if len(ia):
            q = rec.quaternion[ib].T                 # (4, k): quaternion_to_matrix broadcasts
            c = np.moveaxis(quaternion_to_matrix(q), -1, 0)
            return ia, c, rec.topic(ATTITUDE)
    if len(rec.euler_t):
        ia, ib = same_stamps(rec.t, rec.euler_t)
        if len(ia):
            c = np.stack([euler_to_matrix(*e).T for e in rec.euler[ib]])
            return ia, c, rec.topic(EULER_ANGLES)
    return None


def jacobi_drift(rec: Recording) -> tuple[InvariantDrift | None, str | None]:
    """
    Return the drift of the Jacobi integral per segment between impacts.

    J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' (tumble_ros.core.jacobi_integral) at every sample
    that has both w and the attitude, split into segments at the impacts (samples inside a
    pulse are left out); per segment max |J - J(first)|.
    """
    if rec.scenario is None:
        why = f'no {rec.topic(SCENARIO)} in the recording (inertia and orbit rate unknown)'
        if rec.scenario_error:
            why = f'{rec.topic(SCENARIO)} could not be parsed: {rec.scenario_error}'
        return None, why
    if rec.scenario.all_perturbers:
        return None, ('not conserved on a Kepler orbit (orbit.kind kepler or flyby: the tidal '
                      'potential changes with the distance); see docs/physics.md')
    found = _attitude_matrices(rec)
    if found is None:
        return None, (f'no attitude at the stamps of {rec.topic(ANGULAR_VELOCITY)} '
                      f'(neither {rec.topic(ATTITUDE)} nor {rec.topic(EULER_ANGLES)})')
    idx, c, source = found
    t, w = rec.t[idx], rec.omega[idx]
    j = jacobi_integral(t, w, c, rec.scenario.inertia, rec.scenario.orbit_rate)
    segment, inside = impact_segments(t, impact_intervals(rec))
    segments = []
    # the samples outside the pulses, grouped by segment (in their order within each)
    kept = np.flatnonzero(~inside)
    kept = kept[np.argsort(segment[kept], kind='stable')]
    cuts = np.flatnonzero(np.diff(segment[kept])) + 1
    for sel in np.split(kept, cuts) if len(kept) else []:
        js, ts = j[sel], t[sel]
        drift = float(np.max(np.abs(js - js[0])))
        segments.append(JacobiSegment(
            index=int(segment[sel[0]]), t_start=float(ts[0]), t_end=float(ts[-1]), n=len(sel),
            j0=float(js[0]), max_drift=drift,
            rel_drift=drift / abs(float(js[0])) if js[0] != 0 else None))
    return InvariantDrift('Jacobi integral', source, tuple(segments), int(inside.sum())), None


def impact_segments(t: np.ndarray, intervals: list[tuple[float, float]]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return, for each time of ``t`` [yr], its segment and whether it lies inside a pulse.

    ``intervals``: the pulses [(start, end)], merged and sorted (:func:`impact_intervals`).
    Segment k is after the k-th pulse's end (0 before the first); inside means
    start < t < end. By binary search: O(n log m) for n samples and m pulses.
    """
    t = np.asarray(t, dtype=float)
    if not intervals:
        return np.zeros(len(t), dtype=int), np.zeros(len(t), dtype=bool)
    starts = np.array([start for start, _ in intervals], dtype=float)
    ends = np.array([end for _, end in intervals], dtype=float)
    segment = np.searchsorted(ends, t, side='right')          # pulses ended at or before t
    last = np.searchsorted(starts, t, side='left') - 1         # the last pulse started before t
    inside = (last >= 0) & (t < ends[np.maximum(last, 0)])
    return segment.astype(int), inside

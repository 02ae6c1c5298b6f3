"""
Integration segments: the span cut at every impact-pulse edge, the pulse torques constant on each.

An integrator never steps across a pulse edge (an adaptive step would step over a 3e-7-yr
pulse, the paper's "ode" failure): the span [0, duration] is cut at every pulse's start and end,
and each segment is integrated with the pulses active on it summed into a constant torque. One
builder for the :class:`~.propagator.Propagator` and the ensembles. Times in years, torques in
inertia units x rad/yr^2 (body torques in body axes, orbital ones in the orbital frame).
"""
from __future__ import annotations

from typing import NamedTuple, Sequence, TYPE_CHECKING

if TYPE_CHECKING:
    from tumble_ros.core.model.scenario import Impact

__all__ = ['Segment', 'segment_torques', 'split_at_impacts', 'split_span']


class Segment(NamedTuple):
    """One segment [t0, t1] [yr] and the pulse torques held on it."""

    t0: float
    t1: float
    torque_body: tuple[float, float, float]
    torque_orbital: tuple[float, float, float]


def segment_torques(impacts: Sequence[Impact], t0: float,
                    t1: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Return the (body, orbital) torques of the pulses active on [t0, t1], summed in order."""
    mid = 0.5 * (t0 + t1)
    b0 = b1 = b2 = o0 = o1 = o2 = 0.0
    for impact in impacts:
        if impact.start <= mid < impact.end:
            x, y, z = impact.torque
            if impact.frame == 'body':
                b0, b1, b2 = b0 + x, b1 + y, b2 + z
            else:
                o0, o1, o2 = o0 + x, o1 + y, o2 + z
    return (b0, b1, b2), (o0, o1, o2)


_ZERO_TORQUES = segment_torques((), 0.0, 1.0)


def split_at_impacts(duration: float, impacts: Sequence[Impact],
                     cuts: Sequence[float] = ()) -> list[Segment]:
    """
    Return the segments of [0, ``duration``] cut at the edges of ``impacts`` and at ``cuts``.

    ``cuts``: further times [yr] where a segment must end (a flyby's encounter window:
    :attr:`~.scenario.Scenario.segment_cuts`); no torque changes there.

    The torques are those of :func:`segment_torques` over the impacts sorted by start (in that
    order), found by a sweep over time rather than a scan of every impact for every segment
    (a body may have thousands of impacts): O(n log n) in the impacts.
    """
    return split_span(0.0, duration, sorted(impacts, key=lambda i: i.start), cuts)


def split_span(a: float, b: float, ordered: Sequence[Impact],
               cuts: Sequence[float] = ()) -> list[Segment]:
    """
    Return the segments of [``a``, ``b``]: :func:`split_at_impacts` restricted to that span.

    ``ordered``: the impacts sorted by start (ties in their order of scheduling); those that
    do not overlap the span change nothing. The segments are those :func:`split_at_impacts`
    gives over [0, duration] between two of its edges ``a`` and ``b``, bit for bit (the same
    edges, the same impacts summed in the same order): :class:`~.propagator.Propagator`
    re-splits only the span an impact scheduled late overlaps.
    """
    edges = {b, *(t for t in cuts if a < t < b)}
    for impact in ordered:
        edges.update(t for t in (impact.start, impact.end) if a < t < b)
    bounds = [a] + sorted(edges)
    segments, active, nxt = [], [], 0
    for t0, t1 in zip(bounds[:-1], bounds[1:]):
        mid = 0.5 * (t0 + t1)
        while nxt < len(ordered) and ordered[nxt].start <= mid:
            active.append(nxt)
            nxt += 1
        active = [k for k in active if mid < ordered[k].end]
        torques = (segment_torques([ordered[k] for k in active], t0, t1) if active
                   else _ZERO_TORQUES)
        segments.append(Segment(t0, t1, *torques))
    return segments

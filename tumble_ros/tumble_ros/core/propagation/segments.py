"""
Integration segments: the span cut at every impact-pulse edge, the pulse torques constant on each.

An integrator never steps across a pulse edge (an adaptive step would step over a 3e-7-yr
pulse, the paper's "ode" failure): the span [0, duration] is cut at every pulse's start and end,
and each segment is integrated with the pulses active on it summed into a constant torque. One
builder for the :class:`~.propagator.Propagator` and the ensembles. Times in years, torques in
inertia units x rad/yr^2 (body torques in body axes, orbital ones in the orbital frame).
"""
from __future__ import annotations

from typing import Iterable, NamedTuple, Sequence, TYPE_CHECKING

if TYPE_CHECKING:
    from tumble_ros.core.model.scenario import Impact

__all__ = ['NO_PULSE', 'Segment', 'SegmentRow', 'segment_torques', 'summed_torques',
           'split_at_impacts', 'split_rows', 'split_span']


class Segment(NamedTuple):
    """One segment [t0, t1] [yr] and the pulse torques held on it."""

    t0: float
    t1: float
    torque_body: tuple[float, float, float]
    torque_orbital: tuple[float, float, float]


#: The (body, orbital) pulse torques of a segment.
Torques = tuple[tuple[float, float, float], tuple[float, float, float]]
#: A pulse as the sums need it: its torque and whether it is fixed in the body.
Pulse = tuple[tuple[float, float, float], bool]


def segment_torques(impacts: Sequence[Impact], t0: float, t1: float) -> Torques:
    """Return the (body, orbital) torques of the pulses active on [t0, t1], summed in order."""
    mid = 0.5 * (t0 + t1)
    return summed_torques((impact.torque, impact.frame == 'body') for impact in impacts
                          if impact.start <= mid < impact.end)


def summed_torques(pulses: Iterable[Pulse]) -> Torques:
    """Return the (body, orbital) sums of the pulses' torques, in their order."""
    b0 = b1 = b2 = o0 = o1 = o2 = 0.0
    for (x, y, z), body in pulses:
        if body:
            b0, b1, b2 = b0 + x, b1 + y, b2 + z
        else:
            o0, o1, o2 = o0 + x, o1 + y, o2 + z
    return (b0, b1, b2), (o0, o1, o2)


_ZERO_TORQUES = segment_torques((), 0.0, 1.0)
#: The (body, orbital) torques of every segment without a pulse: these very tuple objects.
NO_PULSE = _ZERO_TORQUES
#: A :class:`Segment`'s fields as a plain tuple: (t0, t1, torque_body, torque_orbital).
SegmentRow = tuple[float, float, tuple[float, float, float], tuple[float, float, float]]


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
    return [Segment(*row) for row in split_rows(a, b, ordered, cuts)]


def split_rows(a: float, b: float, ordered: Sequence[Impact],
               cuts: Sequence[float] = ()) -> list[SegmentRow]:
    """
    Return :func:`split_span`'s segments as plain tuples (:data:`SegmentRow`), the same numbers.

    What :class:`~.propagator.Propagator` keeps for a whole run (two segments per impact):
    Python's garbage collector stops tracking a plain tuple of floats and such tuples, never a
    named tuple, which every full collection would traverse again.
    """
    starts = [impact.start for impact in ordered]
    ends = [impact.end for impact in ordered]
    edges = {b, *(t for t in cuts if a < t < b)}
    edges.update(t for t in starts if a < t < b)
    edges.update(t for t in ends if a < t < b)
    # each impact's torque and whether it is a body torque, looked up once (not per segment)
    pulses: list[Pulse] = [(impact.torque, impact.frame == 'body') for impact in ordered]
    segments: list[SegmentRow] = []
    active: list[int] = []
    nxt, count, t0 = 0, len(ordered), a
    for t1 in sorted(edges):
        mid = 0.5 * (t0 + t1)
        while nxt < count and starts[nxt] <= mid:
            active.append(nxt)
            nxt += 1
        if active:
            active = [k for k in active if mid < ends[k]]
        if active:   # (segment_torques of the active impacts)
            segments.append((t0, t1, *summed_torques(pulses[k] for k in active)))
        else:
            segments.append((t0, t1, *_ZERO_TORQUES))
        t0 = t1
    return segments

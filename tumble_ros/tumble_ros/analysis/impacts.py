"""
The impacts of a recording: the pulse intervals and the jump of w across each.

Times in simulated years; torques in the event's frame (``body`` or ``orbital``), delta_omega
and the recorded jump in rad/yr, body axes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import ImpactRecord, Recording

__all__ = ['ImpactSummary', 'impact_intervals', 'impact_summaries']


@dataclass(frozen=True)
class ImpactSummary:
    """An impact event and the jump of the recorded w across it."""

    event: ImpactRecord
    t_before: float | None   # last sample at or before the pulse start
    t_after: float | None    # first sample at or after the pulse end
    sampled_jump: tuple[float, float, float] | None   # w(t_after) - w(t_before)


def impact_summaries(rec: Recording) -> list[ImpactSummary]:
    """Return each recorded impact with the jump of w between the samples around its pulse."""
    out = []
    for event in rec.impacts:
        i = int(np.searchsorted(rec.t, event.start, side='right')) - 1
        k = int(np.searchsorted(rec.t, event.end, side='left'))
        if 0 <= i < rec.n and k < rec.n:
            dx, dy, dz = (float(v) for v in rec.omega[k] - rec.omega[i])
            jump = (dx, dy, dz)
            out.append(ImpactSummary(event, float(rec.t[i]), float(rec.t[k]), jump))
        else:
            out.append(ImpactSummary(event, None, None, None))
    return out


def impact_intervals(rec: Recording) -> list[tuple[float, float]]:
    """
    Return [(start, end)] of every pulse, merged and sorted.

    The pulses are the recorded events and the scenario's scheduled impacts.
    """
    intervals = {(i.start, i.end) for i in rec.impacts}
    if rec.scenario is not None:
        intervals |= {(i.start, i.end) for i in rec.scenario.impacts}
    merged: list[tuple[float, float]] = []
    for start, end in sorted(intervals):
        if merged and start <= merged[-1][1] * (1 + 1e-12):
            merged[-1] = (merged[-1][0], max(end, merged[-1][1]))
        else:
            merged.append((start, end))
    return merged

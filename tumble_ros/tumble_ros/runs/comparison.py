"""
The comparison of a run with an analytic model, without ROS, in one place.

A :class:`Comparison` anchors the model (:mod:`tumble_ros.core.analytic`) on each segment's
start (:class:`~.records.SegmentStart`: at t = 0 and again after every impact and at a flyby's
window edges, so the error measures the model, not the impact), evaluates it at the samples'
times and returns numeric - model, its norm and the relative error, and says once per segment
when the model leaves the numeric solution (relative error above
:data:`tumble_ros.core.DEPARTURE`). Each sample takes the model of the segment its time falls in
(the latest start at or before it): samples that trail a newer segment's start keep the
previous model. The model is evaluated on the run's output grid :data:`LOOKAHEAD` samples at a
time (:class:`GridModelValues`) one sample at a time, and for a block every segment's model on its
samples in one call (:func:`~tumble_ros.core.analytic.omega_many`): the same numbers.

Two entry points on the same state and arithmetic: :meth:`Comparison.compare_one` for one
sample (the live comparator, which receives samples one by one) and
:meth:`Comparison.compare` for a block (the offline recording), vectorised where the arithmetic
is elementwise and per sample where it is not (``math.hypot``), so both give the same bits.
It returns records (:mod:`.records`) and never publishes or writes.
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass
import functools
import math
from typing import Mapping, Sequence

import numpy as np

from tumble_ros.core import (AnalyticModel, DEPARTURE, departure_text, make_model, parse_scenario,
                             Scenario, ScenarioError, TimeBase)
from tumble_ros.core.analytic import omega_many
from tumble_ros.core.model.timebase import SampleGrid

from .records import (ComparedSample, ComparisonBlock, ComparisonStatus, Floats, OK,
                      SampleBlock, SegmentStart, WARN)

__all__ = ['Comparison', 'anchor_model', 'GridModelValues', 'error_norms', 'error_norms_of_rows',
           'LOOKAHEAD', 'SampleGate', 'WAITING']

#: Grid samples whose model value is computed in one vectorised call: the model's fixed numpy
#: cost (~50 us a call) is then shared by this many samples.
LOOKAHEAD = 64
#: The status before the first segment start.
WAITING = "waiting for the simulator's scenario description"


def anchor_model(model_name: str, start: SegmentStart,
                 scenario: Scenario | None = None) -> tuple[AnalyticModel, SampleGrid, str]:
    """
    Return (model, the run's output grid, a line saying so) for a segment's start.

    The model is anchored on the state the segment starts from. ``scenario``: the description's
    scenario when already parsed (``parse_scenario(start.parameters_yaml)``). Raises
    ScenarioError or ValueError (ModelNotApplicable) when the model cannot be built.
    """
    if scenario is None:
        scenario = parse_scenario(start.parameters_yaml)
    grid = _output_grid(start.seconds_per_year, scenario.output_interval, scenario.duration)
    model = make_model(model_name, scenario, t0=start.t0, omega=start.omega,
                       quaternion=start.quaternion)
    text = (f'model {model_name!r} ({model.label}) anchored at t = '
            f'{start.t0:.9g} yr (segment {start.revision})')
    return model, grid, text


@functools.lru_cache(maxsize=16)
def _output_grid(seconds_per_year: float, interval: float, duration: float) -> SampleGrid:
    """Return the run's output grid (the same for every segment of a run: made once)."""
    return TimeBase(seconds_per_year).grid(interval, duration)


def _start(segment: _Segment) -> float:
    return segment.start


def error_norms(numeric: Sequence[float], error: Sequence[float]) -> tuple[float, float]:
    """Return (|error|, |error| / |numeric|) of two 3-vectors [rad/yr] (inf for numeric 0)."""
    norm = math.hypot(*error)
    magnitude = math.hypot(*numeric)
    return norm, norm / magnitude if magnitude > 0 else math.inf


def error_norms_of_rows(numeric: Floats, error: Floats) -> tuple[Floats, Floats]:
    """
    Return (|error|, |error| / |numeric|) of (n, 3) rows [rad/yr]: :func:`error_norms` of each.

    The same numbers bit for bit (``math.hypot`` of each row, the quotient correctly rounded
    either way; tests/test_runs.py), without a Python call per sample.
    """
    norm = np.array(list(map(math.hypot, *error.T.tolist())), dtype=np.float64)
    magnitude = np.array(list(map(math.hypot, *numeric.T.tolist())), dtype=np.float64)
    relative = np.full(len(norm), math.inf)
    with np.errstate(over='ignore', invalid='ignore'):     # inf and nan, as Python's / gives
        np.divide(norm, magnitude, out=relative, where=magnitude > 0)
    return norm, relative


class SampleGate:
    """
    Which live samples are the followed run's: finite, in time order, within the run.

    A simulator publishes its samples in time order, each finite (a diverging run is stopped
    before it publishes a NaN) and none after the run's last grid sample. A sample that is not
    finite, not later than the last sample taken, or stamped after the run's end is another
    publisher's on the same topic (a second run, a test tool, a replay) and must not reach the
    comparison: :meth:`admit` returns why it is dropped and counts it, :meth:`text` says so in
    the comparator's status. A foreign sample that is finite, in order and within the run cannot
    be told apart by its content (a Vector3Stamped carries no run id): the comparator's
    second-source check (:class:`~tumble_ros.nodes.sources.SourceMonitor`) reports that case.
    :meth:`reset` when the followed run changes (a restart starts again from t = 0).
    """

    REASONS = ('not finite', 'not after the last sample', "after the run's end")

    def __init__(self) -> None:
        self.last_ns: int | None = None
        self.counts = dict.fromkeys(self.REASONS, 0)

    @property
    def dropped(self) -> int:
        """Count the samples dropped since the last :meth:`reset`."""
        return sum(self.counts.values())

    def reset(self) -> None:
        """Forget the last stamp and the counts (the run followed changed)."""
        self.last_ns = None
        self.counts = dict.fromkeys(self.REASONS, 0)

    def admit(self, stamp_ns: int, omega: Sequence[float], end_ns: int | None = None
              ) -> str | None:
        """
        Return None if the sample is taken, else the reason it is dropped (and count it).

        ``end_ns``: the stamp of the run's last grid sample (None: not known yet).
        """
        if not all(map(math.isfinite, omega)):
            reason = self.REASONS[0]
        elif self.last_ns is not None and stamp_ns <= self.last_ns:
            reason = self.REASONS[1]
        elif end_ns is not None and stamp_ns > end_ns:
            reason = self.REASONS[2]
        else:
            self.last_ns = stamp_ns
            return None
        self.counts[reason] += 1
        return reason

    def text(self) -> str:
        """Say what was dropped ('' if nothing)."""
        if not self.dropped:
            return ''
        parts = ', '.join(f'{n} {why}' for why, n in self.counts.items() if n)
        return (f"dropped {self.dropped} samples that are not the run's ({parts}): another "
                'publisher on angular_velocity?')


class GridModelValues:
    """A model's omega [rad/yr] on the output grid, :data:`LOOKAHEAD` samples computed at once."""

    def __init__(self) -> None:
        self._model: AnalyticModel | None = None
        self._first = 0
        self._array: Floats = np.empty((0, 3))
        self._values: list[list[float]] | None = None    # _array as lists, when asked for

    def _fill(self, model: AnalyticModel, grid: SampleGrid, k: int) -> None:
        """Evaluate the look-ahead from k unless it holds k already."""
        if model is not self._model or not 0 <= k - self._first < len(self._array):
            times = grid.times(k, min(k + LOOKAHEAD, grid.count))
            self._model, self._first = model, k
            self._array, self._values = model.omega(times), None

    def at(self, model: AnalyticModel, grid: SampleGrid, k: int) -> list[float]:
        """Return ``model``'s omega [rad/yr] at grid sample k."""
        self._fill(model, grid, k)
        if self._values is None:
            self._values = self._array.tolist()
        return self._values[k - self._first]


@dataclass(slots=True)
class _Segment:
    """A segment's start [yr], its model (None: the model does not apply), whether it left."""

    start: float
    model: AnalyticModel | None
    departed: bool = False


class Comparison:
    """
    The comparison of one run with the model ``model_name``; see the module docstring.

    ``history``: the segments kept for trailing samples (the newest included; None: all). The
    live comparator keeps as many as its description subscription holds. ``in_order``: the
    blocks given to :meth:`compare` come in time order, none trailing an earlier one (the
    offline recording): a block forgets the segments before its last sample's (a segment and
    its model per impact would otherwise be held to the end of the run).
    """

    def __init__(self, model_name: str, history: int | None = None,
                 described: Mapping[str, Scenario] | None = None, *,
                 in_order: bool = False) -> None:
        self.model_name = model_name
        self.history = history
        self.in_order = in_order
        self.grid: SampleGrid | None = None   # the run's output grid (None: not known yet)
        self.timebase = TimeBase()            # the run's, from its latest segment start
        self.latest: SegmentStart | None = None
        self._segments: list[_Segment] = []   # by start, the latest's last
        self._values = GridModelValues()
        # the last description parsed and its scenario (every segment after the first has the
        # same text: parsed once, not once per impact)
        self._parsed: tuple[str, Scenario] | None = None
        # descriptions whose scenario the caller already holds (the offline run writes them from
        # its session: SimulationSession.described), not parsed back (0.5 s at 10,000 impacts)
        self._described = dict(described or {})

    def waiting(self) -> ComparisonStatus:
        """Return the status before the first segment start (WARN, logged at 0)."""
        return ComparisonStatus(WARN, WAITING, 0)

    # -- anchoring --------------------------------------------------------------------------
    def anchor(self, start: SegmentStart) -> ComparisonStatus:
        """
        Anchor the model on a segment's start; return the status saying whether it applies.

        A later segment (higher revision, later start) keeps the earlier ones for the samples
        that trail it; a revision not above the latest's is a new run (the simulator restarted)
        and forgets them.
        """
        old = self.latest
        if old is None or start.revision <= old.revision:
            self._segments = []
        elif start.t0 > old.t0:
            pass   # a new segment: the previous ones stay for samples that trail it
        else:
            self._segments.pop()   # the latest segment described again
        self.latest = start
        if self.timebase.seconds_per_year != start.seconds_per_year:
            self.timebase = TimeBase(start.seconds_per_year)
        self._segments.append(_Segment(start.t0, None))
        if self.history is not None:
            del self._segments[:-self.history]
        return self._anchor_latest(start.stamp_ns)

    def set_model(self, model_name: str) -> ComparisonStatus | None:
        """Compare with ``model_name`` from now on (re-anchored on the latest segment start)."""
        self.model_name = model_name
        if self.latest is None:
            return None
        self._segments[-1] = _Segment(self.latest.t0, None)
        return self._anchor_latest(self.latest.stamp_ns)

    def _anchor_latest(self, stamp_ns: int) -> ComparisonStatus:
        assert self.latest is not None
        try:
            model, self.grid, text = anchor_model(self.model_name, self.latest,
                                                  self._scenario(self.latest.parameters_yaml))
        except (ScenarioError, ValueError) as err:
            return ComparisonStatus(WARN, str(err), stamp_ns)
        self._segments[-1].model = model
        return ComparisonStatus(OK, text, stamp_ns)

    def _scenario(self, text: str) -> Scenario:
        """Return the scenario of a description's text, parsed once while it does not change."""
        if text in self._described:
            return self._described[text]
        if self._parsed is None or self._parsed[0] != text:
            self._parsed = (text, parse_scenario(text))
        return self._parsed[1]

    # -- comparing ----------------------------------------------------------------------------
    def _segment_at(self, t: float) -> _Segment | None:
        """Return the segment ``t`` [yr] falls in (None before the first kept)."""
        if self._segments and t >= self._segments[-1].start:
            return self._segments[-1]   # (the latest: nearly every sample)
        i = bisect.bisect_right(self._segments, t, key=_start) - 1
        return self._segments[i] if i >= 0 else None

    def _departure(self, segment: _Segment, t: float, stamp_ns: int) -> ComparisonStatus | None:
        """Say, once per segment, that its model left the numeric solution at ``t`` [yr]."""
        if segment.departed:
            return None
        segment.departed = True
        return ComparisonStatus(WARN, departure_text(self.model_name, t), stamp_ns)

    def compare_one(self, stamp_ns: int, numeric: Sequence[float]) -> ComparedSample | None:
        """
        Compare one sample (stamp [ns], omega [rad/yr] body axes); None if it has no model value.

        Its model value is the grid's look-ahead when the stamp is on the run's grid, else the
        model evaluated at the sample's time alone.
        """
        t = self.timebase.to_years(stamp_ns)
        segment = self._segment_at(t)
        if segment is None or segment.model is None:
            return None
        k = self.grid.index_of(stamp_ns) if self.grid is not None else None
        if k is None or self.grid is None:
            model = segment.model.omega(np.array([t]))[0].tolist()
        else:
            model = self._values.at(segment.model, self.grid, k)
        if not all(map(math.isfinite, model)):
            return None
        error = [n - m for n, m in zip(numeric, model)]
        norm, relative = error_norms(numeric, error)
        departure = (self._departure(segment, t, stamp_ns) if relative > DEPARTURE else None)
        return ComparedSample(stamp_ns, model, error, norm, relative, departure)

    def compare(self, block: SampleBlock) -> ComparisonBlock:
        """
        Compare a block of grid samples; the same numbers as :meth:`compare_one` on each.

        The block's samples are on the run's grid (indices ``block.start`` ...).
        """
        n = len(block)
        times, omega = block.times, block.omega
        model: Floats = np.zeros((n, 3))
        has = np.zeros(n, dtype=bool)
        # the segments from the one the block's first sample falls in (the earlier ones kept for
        # the live comparator's trailing samples are not looked at: offline, one per impact)
        first = max(0, bisect.bisect_right(self._segments, times[0], key=_start) - 1) if n else 0
        starts = np.array([s.start for s in self._segments[first:]])
        which = np.searchsorted(starts, times, side='right') - 1 + first
        edges = [0, *(np.flatnonzero(np.diff(which)) + 1).tolist(), n]
        runs = list(zip(edges[:-1], edges[1:]))
        spans = [(a, b, self._segments[which[a]].model) for a, b in runs if which[a] >= 0]
        modelled = [(a, b, m) for a, b, m in spans if m is not None]
        if modelled and self.grid is not None:
            # every segment's model on its samples of the grid, in one evaluation (a segment
            # per impact): the numbers GridModelValues gives compare_one, bit for bit
            grid_times = self.grid.times(block.start, block.start + n)
            values = omega_many([m for *_, m in modelled],
                                [grid_times[a:b] for a, b, _ in modelled])
            # the modelled runs' rows, in order: one assignment rather than one per segment
            for a, b, _ in modelled:
                has[a:b] = True
            model[has] = np.concatenate(values)
        compared = has & np.isfinite(model).all(axis=1)
        error: Floats = np.where(compared[:, None], omega - model, 0.0)
        norm: Floats = np.zeros(n)
        relative: Floats = np.zeros(n)
        rows = np.flatnonzero(compared)
        norm[rows], relative[rows] = error_norms_of_rows(omega[rows], error[rows])
        model[~compared] = 0.0
        beyond = compared & (relative > DEPARTURE)
        departures = []
        hits = np.flatnonzero(beyond)
        if hits.size:
            # the first sample beyond of each run that has one, runs in order
            run_of = np.searchsorted(np.array(edges[1:]), hits, side='right')
            _, firsts = np.unique(run_of, return_index=True)
            for j in hits[firsts].tolist():
                if which[j] >= 0:
                    said = self._departure(self._segments[which[j]], float(times[j]),
                                           int(block.stamps[j]))
                    departures += [said] if said else []
        if self.in_order and n and which[-1] > 0:
            del self._segments[:which[-1]]   # (no later sample falls before the last one's)
        return ComparisonBlock(block.stamps, compared, model, error, norm, relative,
                               tuple(departures))

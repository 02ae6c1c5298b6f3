"""
The simulation session: what the simulator does each batch, without ROS, in one place.

A :class:`SimulationSession` integrates a :class:`~tumble_ros.core.Scenario` on its output grid
(:class:`~tumble_ros.core.model.timebase.SampleGrid`) with
:class:`~tumble_ros.core.Propagator`: ``advance(k_last)`` samples the grid up to index
``k_last`` and returns the batch's records
(:mod:`.records`), in the order they go out: the impacts that ended and the segments that
started within the batch (a segment's description precedes its samples, so a comparator keeps
the previous segment's model for samples that trail it), the samples, then a status change when
the run finished or diverged. Impacts requested on the way (the live simulator's service) are
scheduled at the next batch, never in the middle of one. The session never publishes or
writes: the live simulator (:mod:`tumble_ros.nodes.sim`) publishes the records, the offline
recording (:mod:`.offline`) writes them.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from tumble_ros import topics
from tumble_ros.core import dump_scenario, Impact, Propagator, Scenario, TimeBase
from tumble_ros.core.model.timebase import SampleGrid
from tumble_ros.core.photometry import LightcurveSampler

from .records import (DIVERGED, FINISHED, Floats, ImpactEnded, PAUSED, RUNNING, SampleBlock,
                      SegmentStart, SessionRecord, StatusChange)

__all__ = ['SimulationSession', 'output_grid']


def output_grid(scenario: Scenario, timebase: TimeBase) -> SampleGrid:
    """
    Return the scenario's output grid at ``timebase`` (``Scenario.output_times``' grid).

    Raises ScenarioError when ROS stamps at this ``seconds_per_year`` cannot carry the run.
    """
    timebase.check_span(scenario.duration)
    return timebase.grid(scenario.output_interval, scenario.duration)


class SimulationSession:
    """
    One run of a scenario on its output grid, batch by batch; see the module docstring.

    Parameters
    ----------
    scenario : Scenario
        Validated scenario (its impacts are scheduled from the start).
    grid : SampleGrid
        The output grid (:func:`output_grid`); its time base maps times to stamps.
    run_id : str
        The run's id, in every segment start (:class:`~.records.SegmentStart`).
    paused : bool
        Start in the state PAUSED (else RUNNING).
    fast : bool or None
        The propagator's compiled loop (:class:`~tumble_ros.core.Propagator`'s ``fast``).

    """

    def __init__(self, scenario: Scenario, grid: SampleGrid, *, run_id: str = '',
                 paused: bool = False, fast: bool | None = None) -> None:
        self.scenario = scenario
        self.grid = grid
        self.run_id = run_id
        self._propagator = Propagator(scenario, fast=fast)
        # The first description carries the scenario as started, its scheduled impacts included;
        # the later ones the same without the impacts list (each is on impact_events when it
        # ends): a description per impact would otherwise repeat every impact (quadratic).
        self._scenario_yaml = dump_scenario(scenario)
        self._segment_scenario = scenario.replace(impacts=()) if scenario.impacts else scenario
        self._segment_yaml = (dump_scenario(self._segment_scenario) if scenario.impacts
                              else self._scenario_yaml)
        self._next_k = 0        # index of the next sample
        self._revision = 0      # of the next segment start
        self._state = PAUSED if paused else RUNNING
        self._pending: deque[tuple[int, Impact]] = deque()   # (service id, impact)
        self._impact_ids: dict[int, int] = {}   # id(Impact) -> service id, until it ends
        self._lightcurve = LightcurveSampler.of(scenario)
        #: The per-sample topics a run publishes only sometimes, and whether this one does.
        self.optional_topics = {topics.PERTURBER: bool(scenario.all_perturbers),
                                topics.LIGHTCURVE: self._lightcurve is not None}

    # -- state ----------------------------------------------------------------------------
    @property
    def described(self) -> dict[str, Scenario]:
        """
        Return {description text: its scenario} for the texts this session's segment starts carry.

        ``parse_scenario(text) == scenario`` for each (tested): an in-process reader takes the
        scenario instead of parsing the text back.
        """
        return {self._scenario_yaml: self.scenario, self._segment_yaml: self._segment_scenario}

    @property
    def state(self) -> int:
        """Return the state: RUNNING, PAUSED, FINISHED or DIVERGED (:mod:`.records`)."""
        return self._state

    @property
    def samples(self) -> int:
        """Count the samples produced so far (the index of the next one)."""
        return self._next_k

    @property
    def t(self) -> float:
        """Return the time [yr] of the last sample produced (0 before the first)."""
        return self.grid.time(max(0, self._next_k - 1))

    @property
    def stamp_ns(self) -> int:
        """Return the stamp [ns] of the last sample produced (0 before the first)."""
        return self.grid.stamp(max(0, self._next_k - 1))

    @property
    def impacts_in_progress(self) -> int:
        """Count the impacts requested and not yet ended."""
        return len(self._pending) + len(self._impact_ids)

    def status(self, message: str) -> StatusChange:
        """Return the current state with ``message``, at the last sample produced."""
        return StatusChange(self._state, self.t, self.stamp_ns, message)

    def start(self) -> list[SessionRecord]:
        """Return the records of the run's start: the first segment, the state ('started')."""
        y0 = self._propagator.y
        return [self._segment_start(0.0, y0), self.status('started')]

    def pause(self) -> StatusChange | None:
        """Pause a running session; return the status change, None if it was not running."""
        if self._state != RUNNING:
            return None
        return self._set_state(PAUSED, f'paused at t = {self.t:g} yr')

    def resume(self) -> StatusChange | None:
        """Resume a paused session; return the status change, None if it was not paused."""
        if self._state != PAUSED:
            return None
        return self._set_state(RUNNING, f'resumed at t = {self.t:g} yr')

    def _set_state(self, state: int, message: str) -> StatusChange | None:
        if state == self._state:
            return None
        self._state = state
        return self.status(message)

    # -- impacts --------------------------------------------------------------------------
    def request_impact(self, impact: Impact, impact_id: int = 0) -> None:
        """
        Queue ``impact`` (checked by the caller), applied at the next batch.

        ``impact_id``: the id its :class:`~.records.ImpactEnded` will carry.
        """
        self._pending.append((impact_id, impact))

    # -- the batch ------------------------------------------------------------------------
    def advance(self, k_last: int, budget: float | None = None) -> list[SessionRecord]:
        """
        Sample the grid up to index ``k_last`` (at most its last); return the batch's records.

        ``budget``: the propagator's work budget for this call (``Propagator.sample_many``;
        None: its default). A batch cut by the budget returns the samples it made, bit for bit
        those of one uninterrupted call; the next call goes on. A failed integration returns
        the samples before it and a status change to DIVERGED (the message says why); the
        last sample of the grid, a status change to FINISHED.
        """
        k_last = min(k_last, self.grid.count - 1)
        records: list[SessionRecord] = []
        if self._next_k <= k_last:
            self._schedule_pending()
            k0 = self._next_k
            times = self.grid.times(k0, k_last + 1)
            done, arrays, failure = self._propagator.sample_many(times, budget=budget)
            records += self._segment_records()
            if done:
                records.append(self._block(k0, times[:done], arrays['omega'][:done],
                                           arrays['quaternion'][:done], arrays['euler'][:done]))
            self._next_k += done
            if failure:
                change = self._set_state(DIVERGED, failure)
                return records + ([change] if change else [])
        if self._next_k >= self.grid.count and self._state != FINISHED:
            change = self._set_state(FINISHED, f'finished at t = {self.t:g} yr')
            records += [change] if change else []
        return records

    def _schedule_pending(self) -> None:
        """Schedule the impacts requested since the last batch, in one pass."""
        if not self._pending:
            return
        pending = list(self._pending)
        self._propagator.schedule_many([impact for _, impact in pending])
        self._pending.clear()
        for impact_id, impact in pending:
            self._impact_ids[id(impact)] = impact_id

    def _block(self, k0: int, times: Floats, omega: Floats, quaternion: Floats,
               euler: Floats) -> SampleBlock:
        """
        Return the samples from grid index k0.

        With the perturber's position if it torques, and the lightcurve if the body has one.
        """
        stamps = (np.arange(k0, k0 + len(times), dtype=np.int64) * self.grid.interval_ns)
        perturber = (self.scenario.perturber_in_body(times, quaternion)
                     if self.scenario.all_perturbers else None)
        lightcurve = (self._lightcurve(times, quaternion) if self._lightcurve is not None
                      else None)
        return SampleBlock(k0, times, stamps, omega, quaternion, euler, perturber, lightcurve)

    def _segment_records(self) -> list[SessionRecord]:
        """
        Return the impacts that ended, then the segments that started (by time), since the last.

        Segments start at an impact's end and at a flyby's encounter window edges.
        """
        starts = dict(self._propagator.pop_window_edges())
        records: list[SessionRecord] = []
        for impact, y_start, y_end in self._propagator.pop_completed_impacts():
            (s0, s1, s2), (e0, e1, e2) = y_start[:3].tolist(), y_end[:3].tolist()
            records.append(ImpactEnded(impact, self._impact_ids.pop(id(impact), 0),
                                       self.grid.timebase.to_ns(impact.end),
                                       (e0 - s0, e1 - s1, e2 - s2)))
            starts[impact.end] = y_end
        records += [self._segment_start(t0, starts[t0]) for t0 in sorted(starts)]
        return records

    def _segment_start(self, t0: float, y0: Floats) -> SegmentStart:
        """Describe the segment starting at ``t0`` [yr] in state ``y0``; count the revision."""
        revision, self._revision = self._revision, self._revision + 1
        q0, q1, q2, q3 = self._propagator.quaternion_of(y0).tolist()
        w0, w1, w2 = y0[:3].tolist()
        text = self._segment_yaml if revision else self._scenario_yaml
        return SegmentStart(
            self.run_id, text, self.grid.timebase.seconds_per_year, revision,
            t0, self.grid.timebase.to_ns(t0), (w0, w1, w2), (q0, q1, q2, q3))

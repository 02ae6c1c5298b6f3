"""
Offline recording: the file the live pipeline records, written straight from the simulation.

``bringup --offline`` and the main job (``python -m tumble_ros``, ``make run``) use it when
nothing live needs the ROS graph. The simulator's samples (the same ``Propagator.sample_many``
on the same output grid), its impact events, scenario descriptions and states, and the
comparator's model, error and error norm (the same model anchoring, :func:`~.comparator.
anchor_model`, the same grid look-ahead and arithmetic, :mod:`.messages`) go to the MCAP file
without DDS: the per-sample messages encoded as numpy columns by the encoder the live simulator
publishes with (:class:`~.messages.SampleEncoder`), the others serialised by rclpy. Channels,
schemas and the offered QoS metadata are those the live recorder writes
(:func:`~.qos.as_discovered` of each publisher's profile).

Log times are simulated time on the ROS clock, as the live recorder's (its default ``log_time``
``sim``): a message's log time is the stamp of the sample it belongs to (``seconds_per_year``
mapping, :class:`~tumble_ros.core.TimeBase`): the per-sample topics and ``/clock`` their stamp,
``markers`` the stamp of their sample, ``scenario`` its segment start, ``impact_events`` the
impact's end, ``status`` the last sample written, ``comparison/status`` the sample it is about
(0 before the first, a segment's start for its anchoring, the first departing sample for a
departure). A viewer then plays, seeks and shows rates in the run's own time. Publish times are
the wall-clock times of writing (the live recorder's: the publishers' send times).

What differs from a live recording (tests/test_offline.py compares the two message by message, log
times included): the publish times; ``comparison/status``'s log times (a live recorder logs them at
the latest stamp it received, later by as much as the simulator runs ahead of the comparator); the
simulator's 1-Hz status heartbeats are absent (a live run has one per wall second while running;
the state changes are the same), the first messages of the depth-1 latched topics (``status``,
``comparison/status``) are always there (a live recorder that subscribes after them gets only the
latest), and messages of different topics may be interleaved differently. The CDR padding bytes no
longer differ: the per-sample messages are the same encoder's bytes in both (zero padding), the
others are serialised by rclpy in both.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path
import time
from typing import Callable

from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
from rclpy.serialization import serialize_message

from tumble_ros import topics
from tumble_ros.core import (DEPARTURE, departure_text, dump_scenario, Propagator, Scenario,
                             TimeBase)
from tumble_ros.core.propagator import FAST_WORK_BUDGET
from tumble_ros.core.scenario import ScenarioError
from tumble_ros.io import McapWriter, offered_qos_yaml
from tumble_ros.nodes.comparator import anchor_model, GridModelValues
from tumble_ros.nodes.markers import marker_every, marker_samples, MarkerScene
from tumble_ros.nodes.messages import (comparison_status, error_norms, impact_event,
                                       new_run_id, SampleEncoder, scenario_description,
                                       sim_status)
from tumble_ros.nodes.qos import as_discovered, PUBLISHER_QOS
from tumble_ros.nodes.recorder import qos_dict
from tumble_ros_interfaces.msg import SimStatus

__all__ = ['record_offline', 'OfflineResult', 'BATCH', 'SLICE_SECONDS', 'Slicer']

#: Most samples simulated, compared and written per step of the loop.
BATCH = 8192
#: Wall-clock seconds one step of the loop aims at: a stop request (SIGINT, SIGTERM, SIGHUP) and
#: the progress are served between steps, so within about twice this at any point of a run.
SLICE_SECONDS = 0.05
#: Smallest work budget of a step [integration steps or dense evaluations]
#: (``Propagator.sample_many``'s unit), and the first one; later steps' budgets follow the
#: measured wall time. Below it, a call's fixed cost dominates (with 1,000 impacts: a budget of
#: 64 takes 3 times as long as 256, and 16 does not finish).
MIN_BUDGET = 256


class Slicer:
    """
    The work budget of each integration slice, so that a slice takes about ``seconds`` of wall.

    ``Propagator.sample_many`` stops after ``budget`` units of work with what it sampled, bit
    for bit what one uninterrupted call gives; the budget follows the measured cost of a unit
    (at most doubling per slice, within [:data:`MIN_BUDGET`, ``FAST_WORK_BUDGET``]), whatever
    the scenario costs a step (a flyby, a thousand impacts, a fine fixed step).
    """

    def __init__(self, seconds: float = SLICE_SECONDS, budget: int = MIN_BUDGET) -> None:
        self.seconds = seconds
        self.budget = budget
        self.calls = 0

    def sample(self, propagator: Propagator, times: np.ndarray):
        """``propagator.sample_many(times)`` within this slice's budget; adapt the next one."""
        started = time.monotonic()
        result = propagator.sample_many(times, budget=self.budget)
        self.calls += 1
        elapsed = time.monotonic() - started
        scale = 2.0 if elapsed <= 0.0 else min(2.0, self.seconds / elapsed)
        self.budget = int(min(FAST_WORK_BUDGET, max(MIN_BUDGET, self.budget * scale)))
        return result


#: The live nodes' names (the comparator's DiagnosticStatus carries its node's name).
COMPARATOR_NAME = '/comparator'


@dataclass
class OfflineResult:
    """What an offline recording wrote (the fields of ``bringup.BringupResult``)."""

    output: Path
    state: int
    message: str
    samples: int
    t: float = 0.0  # time of the last sample written [yr]
    counts: dict[str, int] = field(default_factory=dict)
    wall_seconds: float = 0.0


class _Channels:
    """The recording's channels, as the live recorder makes them, and their encoders."""

    def __init__(self, writer: McapWriter, publish_clock: bool, perturber: bool, markers: bool):
        self.writer = writer
        self.ids: dict[str, int] = {}
        self._pending: list[tuple[int, str, bytes]] = []
        self.encoder = SampleEncoder()
        for topic in topics.RECORDED:
            if (topic == topics.CLOCK and not publish_clock
                    or topic == topics.PERTURBER and not perturber
                    or topic == topics.MARKERS and not markers):
                continue
            name = topic if topic.startswith('/') else '/' + topic
            type_name = topics.TYPES[topic]
            offered = offered_qos_yaml(qos_dict(as_discovered(PUBLISHER_QOS[topic])))
            self.ids[topic] = writer.add_channel(name, type_name, offered)

    def one(self, topic: str, msg, stamp_ns: int) -> None:
        """
        Queue one message (serialised by rclpy) logged at ``stamp_ns`` [ns, ROS time].

        Queued messages are written by :meth:`flush` in the order of their log times, so each
        channel's log times never decrease (a batch's departures may precede its anchorings).
        """
        self._pending.append((stamp_ns, topic, serialize_message(msg)))

    def flush(self) -> None:
        """Write the queued messages, by log time (stable); publish time = now (wall clock)."""
        now = time.time_ns()
        for stamp_ns, topic, data in sorted(self._pending, key=lambda m: m[0]):
            self.writer.write(self.ids[topic], data, stamp_ns, now)
        self._pending.clear()


def record_offline(scenario: Scenario, output, *, timebase: TimeBase | None = None,
                   model_name: str = 'paper', publish_clock: bool = True,
                   markers: bool = True, marker_decimation: int = 0,
                   stop: Callable[[], bool] = lambda: False,
                   progress: Callable[[float, int], None] | None = None) -> OfflineResult:
    """
    Simulate ``scenario``, compare it with ``model_name`` and write the recording ``output``.

    ``timebase``: the simulator's (its ``seconds_per_year``; default one second per year);
    ``publish_clock``, ``markers``, ``marker_decimation``: the simulator's parameters.
    ``stop()`` is checked between slices of the integration (:class:`Slicer`, about
    :data:`SLICE_SECONDS` of wall each): a stopped run keeps what it wrote (the file is
    finalised). ``progress(t [yr], samples)`` is called after each batch. Raises OSError when
    the file cannot be created or written, ScenarioError for a grid ROS stamps cannot carry.
    """
    started = time.monotonic()
    timebase = timebase or TimeBase()
    timebase.check_span(scenario.duration)
    grid = timebase.grid(scenario.output_interval, scenario.duration)
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    propagator = Propagator(scenario)
    # the scenario as started and the recording's run id, in every description
    described = (dump_scenario(scenario), new_run_id())
    state, message, k = SimStatus.RUNNING, '', 0
    scene = _Scene(MarkerScene(scenario), marker_every(marker_decimation, grid.count),
                   grid) if markers else None
    slicer = Slicer()
    with McapWriter(output, chunk_seconds=math.inf) as writer:
        channels = _Channels(writer, publish_clock, perturber=scenario.orbit is not None,
                             markers=markers)
        comparator = _Comparator(channels, model_name)
        channels.one(topics.COMPARISON_STATUS, comparison_status(
            DiagnosticStatus.WARN, COMPARATOR_NAME,
            "waiting for the simulator's scenario description", model_name), 0)
        revision = _describe(channels, comparator, described, timebase, 0, 0.0,
                             propagator.y, propagator)
        channels.one(topics.STATUS, sim_status(state, 0.0, 'started', 0), 0)
        while k < grid.count and not stop():
            k1 = min(grid.count, k + BATCH)
            done, arrays, failure = slicer.sample(propagator, grid.times(k, k1))
            segment_starts = dict(propagator.pop_window_edges())
            for impact, y_start, y_end in propagator.pop_completed_impacts():
                end_ns = timebase.to_ns(impact.end)
                channels.one(topics.IMPACT_EVENTS, impact_event(
                    impact, 0, end_ns, y_end[:3] - y_start[:3]), end_ns)
                segment_starts[impact.end] = y_end
            for t0 in sorted(segment_starts):
                revision = _describe(channels, comparator, described, timebase, revision, t0,
                                     segment_starts[t0], propagator)
            _write_samples(channels, comparator, grid, k, done, arrays, publish_clock, scenario)
            if scene is not None:
                scene.write(channels, k, done, arrays)
            channels.flush()
            k += done
            if progress is not None:
                progress(grid.time(max(0, k - 1)), k)
            if failure:
                state, message = SimStatus.DIVERGED, failure
                break
        if state == SimStatus.RUNNING and k >= grid.count:
            state, message = SimStatus.FINISHED, f'finished at t = {grid.time(k - 1):g} yr'
        if state != SimStatus.RUNNING:
            last = grid.stamp(max(0, k - 1))
            channels.one(topics.STATUS, sim_status(state, grid.time(max(0, k - 1)), message,
                                                   last), last)
        channels.flush()
        counts = dict(writer.counts)
    return OfflineResult(output=output, state=state, message=message or 'stopped', samples=k,
                         t=grid.time(max(0, k - 1)), counts=counts,
                         wall_seconds=time.monotonic() - started)


def _describe(channels, comparator, described, timebase, revision, t0, y0, propagator):
    """
    Write a segment's description, anchor the comparator on it; return the next revision.

    ``described``: (the scenario as started as YAML, the recording's run id).
    """
    scenario_yaml, run_id = described
    description = scenario_description(scenario_yaml, timebase.seconds_per_year, revision,
                                       timebase.to_ns(t0), t0, y0[:3],
                                       propagator.quaternion_of(y0), run_id)
    channels.one(topics.SCENARIO, description, timebase.to_ns(t0))
    comparator.anchor(description, timebase.to_ns(t0))
    return revision + 1


class _Comparator:
    """The comparator node's work on the samples, without its node."""

    def __init__(self, channels: _Channels, model_name: str):
        self.channels = channels
        self.model_name = model_name
        self.segments: list[tuple[float, object]] = []   # (segment start, model or None)
        self.grid = None
        self.values = GridModelValues()
        self.departed: set[int] = set()    # segments whose model left the numeric solution

    def anchor(self, description, stamp_ns: int) -> None:
        """Anchor a model on a segment's description (stamped ``stamp_ns``); say so."""
        try:
            model, self.grid, text = anchor_model(self.model_name, description)
            level = DiagnosticStatus.OK
        except (ScenarioError, ValueError) as err:
            model, level, text = None, DiagnosticStatus.WARN, str(err)
        self.segments.append((description.segment_start, model))
        self.channels.one(topics.COMPARISON_STATUS, comparison_status(
            level, COMPARATOR_NAME, text, self.model_name), stamp_ns)

    def compare(self, k0: int, times: np.ndarray, stamps: np.ndarray, omega: np.ndarray):
        """
        Return (mask of the samples compared, model, error, norm, relative) of a batch.

        ``times`` [yr] and ``stamps`` [ns] are the batch's samples (grid indices from ``k0``).

        Each sample takes the model of the segment its time falls in (the latest description
        starting at or before it), evaluated on the grid's look-ahead blocks as the node does;
        the arithmetic is the node's (messages.comparison_values), vectorised where it is
        elementwise, per sample where it is not (math.hypot).
        """
        n = len(times)
        model = np.zeros((n, 3))
        has = np.zeros(n, dtype=bool)
        starts = np.array([start for start, _ in self.segments])
        which = np.searchsorted(starts, times, side='right') - 1
        edges = [0, *(np.flatnonzero(np.diff(which)) + 1).tolist(), n]
        for a, b in zip(edges[:-1], edges[1:]):
            m = self.segments[which[a]][1] if which[a] >= 0 else None
            if m is not None:
                model[a:b] = self.values.span(m, self.grid, k0 + a, k0 + b)
                has[a:b] = True
        compared = has & np.isfinite(model).all(axis=1)
        error = np.where(compared[:, None], omega - model, 0.0)
        norm = np.zeros(n)
        relative = np.zeros(n)
        numeric, errors = omega.tolist(), error.tolist()   # (numeric - model: elementwise)
        for j in np.flatnonzero(compared).tolist():
            norm[j], relative[j] = error_norms(numeric[j], errors[j])
        model[~compared] = 0.0
        self._report_departures(times, stamps, which, edges, compared & (relative > DEPARTURE))
        return compared, model, error, norm, relative

    def _report_departures(self, times, stamps, which, edges, beyond) -> None:
        """Say on the status when a segment's model first leaves the numeric solution."""
        for a, b in zip(edges[:-1], edges[1:]):
            segment = int(which[a])
            hits = np.flatnonzero(beyond[a:b])
            if segment < 0 or not len(hits) or segment in self.departed:
                continue
            self.departed.add(segment)
            self.channels.one(topics.COMPARISON_STATUS, comparison_status(
                DiagnosticStatus.WARN, COMPARATOR_NAME,
                departure_text(self.model_name, float(times[a + hits[0]])), self.model_name),
                int(stamps[a + hits[0]]))


@dataclass
class _Scene:
    """The simulator's markers (nodes.markers): the same scenes of the same samples."""

    scene: MarkerScene
    every: int
    grid: object

    def write(self, channels: _Channels, k0: int, n: int, arrays: dict) -> None:
        """Write the scenes of the samples k0 .. k0 + n - 1 that get one."""
        rows = self.scene.encode_samples(self.grid, self.every, k0, n, arrays)
        if not len(rows):
            return
        # logged at their samples' stamps (the samples encode_samples picks)
        stamps = marker_samples(k0, k0 + n, self.every, self.grid.count) * self.grid.interval_ns
        channels.writer.write_rows([channels.ids[topics.MARKERS]], [rows], stamps,
                                   np.full(len(rows), time.time_ns(), dtype=np.int64))


def _write_samples(channels: _Channels, comparator: _Comparator, grid, k0: int, n: int,
                   arrays: dict, publish_clock: bool, scenario: Scenario) -> None:
    """
    Write n samples from grid index k0: the simulator's topics, the comparator's three.

    The simulator's: /clock (if published), ω, attitude, Euler angles, and the perturber's
    position when the scenario has a Kepler orbit (as the live simulator), encoded as the live
    simulator encodes them (:class:`~.messages.SampleEncoder`).
    """
    if n == 0:
        return
    ns = np.arange(k0, k0 + n, dtype=np.int64) * grid.interval_ns
    omega, quaternion = arrays['omega'][:n], arrays['quaternion'][:n]
    perturber = (scenario.perturber_in_body(grid.times(k0, k0 + n), quaternion)
                 if topics.PERTURBER in channels.ids else None)
    sim = channels.encoder.simulator(ns, omega, quaternion, arrays['euler'][:n],
                                     clock=publish_clock, perturber=perturber)
    compared, model, error, norm, relative = comparator.compare(k0, grid.times(k0, k0 + n),
                                                                ns, omega)
    comparison = channels.encoder.comparator(ns, model, error, norm, relative,
                                             comparator.model_name)
    # log time = the sample's stamp (ROS time); publish time = now (wall clock)
    sent = np.full(n, time.time_ns(), dtype=np.int64)
    # runs of samples with and without comparison, in order
    edges = np.flatnonzero(np.diff(compared.astype(np.int8))) + 1
    for a, b in zip([0, *edges.tolist()], [*edges.tolist(), n]):
        parts = sim + (comparison if compared[a] else [])
        channels.writer.write_rows([channels.ids[t] for t, _ in parts],
                                   [rows[a:b] for _, rows in parts], ns[a:b], sent[a:b])

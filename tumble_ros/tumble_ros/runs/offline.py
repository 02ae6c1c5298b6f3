"""
Offline recording: the file the live pipeline records, written straight from the simulation.

``bringup --offline`` and the main job (``python -m tumble_ros``, ``make run``) use it when
nothing live needs the ROS graph. The records of the run (:mod:`.records`) the live nodes
publish, from the same run layer: the simulator's samples, impact events, segment starts and
states (:class:`~.session.SimulationSession`, the live simulator's session) and the
comparator's model, error and error norm (:class:`~.comparison.Comparison`, the live
comparator's) go to the MCAP file without DDS: the per-sample messages encoded as numpy columns
by the encoder the live simulator publishes with (:class:`~tumble_ros.runs.messages.builders.
SampleEncoder`), the others (descriptions, impact events, statuses) encoded from their
records without rclpy's message classes (:class:`~tumble_ros.runs.messages.records.
RecordEncoder`: the fields and length of rclpy's serialisation, zero padding). Channels,
schemas and the offered QoS metadata are those the live recorder writes
(:func:`~tumble_ros.runs.messages.qos.as_discovered` of each publisher's profile).

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
latest), and messages of different topics may be interleaved differently; the per-sample messages
are the same encoder's bytes in both (zero padding), the others' padding bytes may differ (rclpy
leaves its own as they were, the offline recording's are zero).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import operator
from pathlib import Path
import time
from typing import Callable

import numpy as np

from tumble_ros import topics
from tumble_ros.core import Scenario, TimeBase
from tumble_ros.core.model.timebase import SampleGrid
from tumble_ros.core.propagation.propagator import FAST_WORK_BUDGET
from tumble_ros.io import McapWriter, offered_qos_yaml, WrittenMessages
from tumble_ros.runs.messages.builders import new_run_id, SampleEncoder
from tumble_ros.runs.messages.markers import marker_every, marker_samples, MarkerScene
from tumble_ros.runs.messages.qos import as_discovered, publisher_qos, qos_dict
from tumble_ros.runs.messages.records import RecordEncoder

from .comparison import Comparison
from .records import (ComparisonStatus, DIVERGED, ImpactEnded, RUNNING, SampleBlock,
                      SegmentStart, SessionRecord, StatusChange)
from .session import output_grid, SimulationSession

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

    ``Propagator.sample_many`` (through :meth:`SimulationSession.advance`) stops after
    ``budget`` units of work with what it sampled, bit for bit what one uninterrupted call
    gives; the budget follows the measured cost of a unit (at most doubling per slice, within
    [:data:`MIN_BUDGET`, ``FAST_WORK_BUDGET``]), whatever the scenario costs a step (a flyby,
    a thousand impacts, a fine fixed step).
    """

    def __init__(self, seconds: float = SLICE_SECONDS, budget: int = MIN_BUDGET) -> None:
        self.seconds = seconds
        self.budget = budget
        self.calls = 0

    def advance(self, session: SimulationSession, k_last: int) -> list[SessionRecord]:
        """Advance ``session`` to ``k_last`` within this slice's budget; adapt the next one."""
        started = time.monotonic()
        records = session.advance(k_last, budget=self.budget)
        self.calls += 1
        elapsed = time.monotonic() - started
        scale = 2.0 if elapsed <= 0.0 else min(2.0, self.seconds / elapsed)
        self.budget = int(min(FAST_WORK_BUDGET, max(MIN_BUDGET, self.budget * scale)))
        return records


#: A queued message's log time (its first field): the key :meth:`_Channels.flush` sorts by.
_LOG_TIME = operator.itemgetter(0)
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

    def __init__(self, writer: McapWriter, publish_clock: bool, optional: dict[str, bool],
                 markers: bool) -> None:
        self.writer = writer
        self.ids: dict[str, int] = {}
        self._pending: list[tuple[int, str, bytes]] = []
        self.encoder = SampleEncoder()
        self.records = RecordEncoder()
        for topic in topics.recorded():
            if (topic == topics.CLOCK and not publish_clock
                    or not optional.get(topic, True)
                    or topic == topics.MARKERS and not markers):
                continue
            name = topic if topic.startswith('/') else '/' + topic
            type_name = topics.TYPES.get(topic) or topics.sample_topic(topic).type_name
            offered = offered_qos_yaml(qos_dict(as_discovered(publisher_qos(topic))))
            self.ids[topic] = writer.add_channel(name, type_name, offered)

    def one(self, topic: str, data: bytes, stamp_ns: int) -> None:
        """
        Queue one message (CDR bytes) logged at ``stamp_ns`` [ns, ROS time].

        Queued messages are written by :meth:`flush` in the order of their log times, so each
        channel's log times never decrease (a batch's departures may precede its anchorings).
        """
        self._pending.append((stamp_ns, topic, data))

    def comparison_status(self, status: ComparisonStatus, model_name: str) -> None:
        """Queue a ``comparison/status`` of the comparator, logged at its stamp."""
        self.one(topics.COMPARISON_STATUS,
                 self.records.comparison_status(status, COMPARATOR_NAME, model_name),
                 status.stamp_ns)

    def flush(self) -> None:
        """Write the queued messages, by log time (stable); publish time = now (wall clock)."""
        now = time.time_ns()
        ids = self.ids
        self.writer.write_many([(ids[topic], data, stamp_ns, now) for stamp_ns, topic, data
                                in sorted(self._pending, key=_LOG_TIME)])
        self._pending.clear()


def record_offline(scenario: Scenario, output: str | Path, *, timebase: TimeBase | None = None,
                   model_name: str = 'paper', publish_clock: bool = True,
                   markers: bool = True, marker_decimation: int = 0,
                   stop: Callable[[], bool] = lambda: False,
                   progress: Callable[[float, int], None] | None = None,
                   keep: WrittenMessages | None = None) -> OfflineResult:
    """
    Simulate ``scenario``, compare it with ``model_name`` and write the recording ``output``.

    ``timebase``: the simulator's (its ``seconds_per_year``; default the scenario's own, one
    ROS second per ``time_unit``: the grid of ``simulate(scenario)``);
    ``publish_clock``, ``markers``, ``marker_decimation``: the simulator's parameters.
    ``stop()`` is checked between slices of the integration (:class:`Slicer`, about
    :data:`SLICE_SECONDS` of wall each): a stopped run keeps what it wrote (the file is
    finalised). ``progress(t [yr], samples)`` is called after each batch. ``keep``: receives
    the messages as written (:class:`~tumble_ros.io.WrittenMessages`: the main job's analysis
    takes them instead of reading the file back). Raises OSError when
    the file cannot be created or written, ScenarioError for a grid ROS stamps cannot carry.
    """
    started = time.monotonic()
    grid = output_grid(scenario, timebase or scenario.timebase)
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    # the recording's run id, in every description
    session = SimulationSession(scenario, grid, run_id=new_run_id())
    comparison = Comparison(model_name, described=session.described, in_order=True)
    scene = _Scene(MarkerScene(scenario), marker_every(marker_decimation, grid.count),
                   grid) if markers else None
    slicer = Slicer()
    ended: StatusChange | None = None   # the run's end (finished or diverged)
    # chunks compressed and written in a thread while the next batch is simulated: the same file
    with McapWriter(output, chunk_seconds=math.inf, keep=keep, background=True) as writer:
        channels = _Channels(writer, publish_clock, session.optional_topics, markers=markers)
        writer_of = _Writer(channels, comparison, scene, publish_clock)
        channels.comparison_status(comparison.waiting(), model_name)
        writer_of.records(session.start())
        while session.samples < grid.count and not stop():
            k = session.samples
            ended = writer_of.records(
                slicer.advance(session, min(grid.count, k + BATCH) - 1)) or ended
            channels.flush()
            if progress is not None:
                progress(session.t, session.samples)
            if session.state == DIVERGED:
                break
        channels.flush()
        counts = dict(writer.counts)
    return OfflineResult(output=output, state=session.state,
                         message=ended.message if ended is not None else 'stopped',
                         samples=session.samples, t=session.t, counts=counts,
                         wall_seconds=time.monotonic() - started)


@dataclass
class _Writer:
    """The records of a run into the recording's channels: the simulator's and comparator's."""

    channels: _Channels
    comparison: Comparison
    scene: _Scene | None
    publish_clock: bool

    def records(self, records: list[SessionRecord]) -> StatusChange | None:
        """
        Write (or queue) a batch's records; return its change to a final state, if any.

        A segment start anchors the comparison (its status queued too); samples are written
        with their comparison and markers.
        """
        final, encode = None, self.channels.records
        for record in records:
            if isinstance(record, SampleBlock):
                self.samples(record)
            elif isinstance(record, SegmentStart):
                self.channels.one(topics.SCENARIO, encode.description(record), record.stamp_ns)
                self.channels.comparison_status(self.comparison.anchor(record),
                                                self.comparison.model_name)
            elif isinstance(record, ImpactEnded):
                self.channels.one(topics.IMPACT_EVENTS, encode.impact(record), record.stamp_ns)
            else:
                self.channels.one(topics.STATUS, encode.status(record), record.stamp_ns)
                final = record if record.state != RUNNING else None
        return final

    def samples(self, block: SampleBlock) -> None:
        """
        Write a block of samples: the simulator's topics, the comparator's three, the markers.

        The simulator's: /clock (if published), ω, attitude, Euler angles, the perturber's
        position when the scenario has a Kepler orbit and the lightcurve when the body has one
        (as the live simulator), encoded as the live simulator encodes them
        (:class:`~tumble_ros.runs.messages.builders.SampleEncoder`).
        """
        channels, n, ns = self.channels, len(block), block.stamps
        sim = channels.encoder.simulator(ns, block.omega, block.quaternion, block.euler,
                                         clock=self.publish_clock, perturber=block.perturber,
                                         lightcurve=block.lightcurve)
        compared = self.comparison.compare(block)
        for departure in compared.departures:
            channels.comparison_status(departure, self.comparison.model_name)
        comparison = channels.encoder.comparator(ns, compared.model, compared.error,
                                                 compared.norm, compared.relative,
                                                 self.comparison.model_name)
        # log time = the sample's stamp (ROS time); publish time = now (wall clock)
        sent = np.full(n, time.time_ns(), dtype=np.int64)
        # runs of samples with and without comparison, in order
        mask = compared.compared
        edges = np.flatnonzero(np.diff(mask.astype(np.int8))) + 1
        for a, b in zip([0, *edges.tolist()], [*edges.tolist(), n]):
            parts = sim + (comparison if mask[a] else [])
            channels.writer.write_rows([channels.ids[t] for t, _ in parts],
                                       [rows[a:b] for _, rows in parts], ns[a:b], sent[a:b])
        if self.scene is not None:
            self.scene.write(channels, block)


@dataclass
class _Scene:
    """The simulator's markers (runs.messages.markers): the same scenes of the same samples."""

    scene: MarkerScene
    every: int
    grid: SampleGrid

    def write(self, channels: _Channels, block: SampleBlock) -> None:
        """Write the scenes of the block's samples that get one."""
        k0, n = block.start, len(block)
        rows = self.scene.encode_samples(self.grid, self.every, k0, n,
                                         {'omega': block.omega, 'quaternion': block.quaternion})
        if not len(rows):
            return
        # logged at their samples' stamps (the samples encode_samples picks)
        stamps = marker_samples(k0, k0 + n, self.every, self.grid.count) * self.grid.interval_ns
        channels.writer.write_rows([channels.ids[topics.MARKERS]], [rows], stamps,
                                   np.full(len(rows), time.time_ns(), dtype=np.int64))

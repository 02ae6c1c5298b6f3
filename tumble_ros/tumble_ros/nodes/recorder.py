"""
The recorder node: ``ros2 run tumble_ros recorder``.

Records topics to one rosbag2-compatible MCAP file (:class:`tumble_ros.io.McapWriter`: profile
``ros2``, ``ros2msg`` schemas with their dependencies, ``cdr`` messages, chunked and compressed)
from raw subscriptions: the bytes written are the bytes received, never re-serialised.

What it records: the tumble topics (:data:`DEFAULT_TOPICS`) by default, or the ``topics`` list,
plus every topic whose name matches the ``topic_pattern`` regular expression; topics that appear
later are picked up by a discovery timer. Each subscription copies its publishers' durability
and reliability (a latched topic is received even when published before the recorder started),
and its publishers' QoS go into the channel's ``offered_qos_profiles``.

Durability: SIGINT/SIGTERM finalise the file (summary, statistics, indexes). A write that fails
(disk full, file size limit, I/O error) stops the recording with an error in the log and in
:attr:`RecorderNode.error`: what was flushed before stays readable, the node leaves the
simulator's consumers so nothing waits for it, and keeps running otherwise. A SIGKILL loses at
most the chunk in progress: fewer than ``chunk_bytes`` bytes of message data, and nothing older
than ``chunk_seconds`` (plus the polling period, ``chunk_seconds / 4``); what was flushed is read
back by a non-seeking reader. The recorder reports its progress on ``consumer_progress`` so the
simulator never outruns it: at the default settings nothing is dropped (``/clock`` is best effort,
as time sources expect, and recorded as received).

Log times (``log_time``): ``sim`` (default) records on the simulated clock, as ``ros2 bag record
--use-sim-time`` does, but exactly: a message of a tumble topic is logged at the ROS time of the
sample it belongs to, its stamp (``header.stamp``, ``/clock``'s ``clock``, a MarkerArray's first
marker's stamp, a TFMessage's first transform's; the ``seconds_per_year`` mapping of
:class:`~tumble_ros.core.TimeBase`), and
a message without a stamp (``comparison/status``, a topic matched by ``topic_pattern``) at the
latest stamp received so far (0 before any), so a viewer plays, seeks and shows rates in the
run's own time. ``receive`` logs the receive time on the node's clock instead: the wall clock,
or ``/clock`` with ``use_sim_time:=true``. The publish time is the publisher's send time
(wall clock; the receive time where the executor cannot tell it). A second
publisher on a recorded tumble topic (another run on the same topics) is reported in the log and
in :attr:`RecorderNode.warnings`.
"""
from __future__ import annotations

from datetime import datetime, timezone
import math
import os
from pathlib import Path
import re
import struct
import time
from typing import Callable

from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import InvalidTopicNameException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from tumble_ros import topics
from tumble_ros.errors import NodeError
from tumble_ros.io import McapWriter, offered_qos_yaml
from tumble_ros.io.mcap_writer import COMPRESSIONS
from tumble_ros.io.msgdefs import message_spec, normalize_type_name
from tumble_ros.nodes.clocks import steady_timer
from tumble_ros.nodes.guarded import GuardedNode
from tumble_ros.nodes.parameters import declare_node_parameters
from tumble_ros.nodes.progress import ProducedTopics, ProgressReporter
from tumble_ros.nodes.runner import chosen_executor, run_node
from tumble_ros.nodes.sources import SourceMonitor
from tumble_ros.runs.messages.qos import qos_dict, STATE_QOS

__all__ = ['RecorderNode', 'DEFAULT_TOPICS', 'main']

#: Recorded when ``topics`` is not given (relative names resolve in the recorder's namespace);
#: ``topic_pattern`` adds to them, as it adds to ``topics``.
DEFAULT_TOPICS = topics.RECORDED
#: Recorded tumble topics with one publisher per simulator by design (/tf, /tf_static): not
#: watched for a second source.
SHARED_TOPICS = frozenset(topics.SHARED_TOPICS)
#: Types whose CDR starts with a header stamp: one message per simulator sample. The recorder's
#: progress is the oldest of their latest stamps. Not /clock: it is best effort (CLOCK_QOS).
PER_SAMPLE_TYPES = {topics.TYPES[t] for t in topics.PER_SAMPLE}
#: A per-sample topic silent for this long [s] no longer holds the recorder's progress back.
STALE_TOPIC = 2.0
#: A per-sample topic silent for this long [s] is checked for publishers (at most this often):
#: one whose publishers all left (a comparator stopped) no longer holds the progress back.
QUIET_TOPIC = 0.05

PARAMETERS = {
    'output': ('', '', 'MCAP file to write; empty = recordings/tumble_<UTC time>.mcap', None,
               True),
    'topics': ([''], '', 'topics to record (empty: the tumble topics)', None, True),
    'topic_pattern': ('', '', 'also record every topic whose full name matches this regex', None,
                      True),
    'chunk_bytes': (1_000_000, 'B', 'a chunk is written once it holds this much message data',
                    (1, 2**30), True),
    'chunk_seconds': (1.0, 's', '... or once its first message is this old', (0.01, 3600.0), True),
    'compression': ('zstd', '', 'chunk compression: ' + ', '.join(COMPRESSIONS), None, True),
    'discovery_period': (0.5, 's', 'how often to look for new matching topics', (0.01, 60.0),
                         True),
    'log_time': ('sim', '', "log time of a record: 'sim' = the simulated time of the sample it "
                 "belongs to (its stamp); 'receive' = the receive time on the node's clock",
                 None, True),
}
#: Accepted values of ``log_time``.
LOG_TIMES = ('sim', 'receive')


def _header_stamp_ns(data: bytes, offset: int = 4) -> int:
    """Read the builtin_interfaces/Time at ``offset`` of a CDR message (default: its start)."""
    little = data[1] == 1  # encapsulation CDR_LE = 0x0001
    sec, nanosec = struct.unpack_from('<iI' if little else '>iI', data, offset)
    return sec * 1_000_000_000 + nanosec


def stamp_reader(type_name: str) -> Callable[[bytes], int | None] | None:
    """
    Return a reader of the stamp [ns] in a CDR message of ``type_name``, or None if it has none.

    A stamp is the first field when it is a ``std_msgs/Header`` or a ``builtin_interfaces/Time``
    (at byte 4, after the encapsulation), or the first element's when the first field is a
    sequence of such messages (``visualization_msgs/MarkerArray``: at byte 8, after the length;
    the reader returns None for an empty sequence).
    """
    def first_stamp(name: str) -> bool:
        try:
            spec = message_spec(normalize_type_name(name))
        except (LookupError, ValueError):
            return False
        return bool(spec.fields) and spec.fields[0].array is None and (
            spec.fields[0].type in ('std_msgs/Header', 'builtin_interfaces/Time'))

    if first_stamp(type_name):
        return _header_stamp_ns
    try:
        fields = message_spec(normalize_type_name(type_name)).fields
    except (LookupError, ValueError):
        return None
    if fields and fields[0].array == '' and not fields[0].is_primitive and first_stamp(
            fields[0].type):
        def element_stamp(data: bytes) -> int | None:
            little = data[1] == 1
            (count,) = struct.unpack_from('<I' if little else '>I', data, 4)
            return _header_stamp_ns(data, 8) if count else None
        return element_stamp
    return None


class RecorderNode(GuardedNode):
    """Recorder node; see the module docstring."""

    def __init__(self, *, message_info: bool = True, **kwargs) -> None:
        """
        Create the recorder node (its parameters: :data:`PARAMETERS`).

        ``message_info=False``: subscription callbacks take the message only (executors that
        cannot pass rclpy's MessageInfo, e.g. Jazzy's EventsExecutor); the publish time of
        each record is then its receive time instead of the publisher's source timestamp.
        """
        super().__init__('recorder', message_info, **kwargs)

    def _set_up(self, message_info: bool) -> None:
        self._message_info = message_info
        self.add_on_set_parameters_callback(self._on_set_parameters)
        p = declare_node_parameters(self, PARAMETERS)
        if p['log_time'] not in LOG_TIMES:
            raise NodeError(f"log_time: must be one of {', '.join(LOG_TIMES)}, "
                            f"got {p['log_time']!r}")
        topics = [t for t in p['topics'] if t]
        self._explicit = {self._resolve('topics', t)
                          for t in (topics or DEFAULT_TOPICS)}
        self._pattern = re.compile(p['topic_pattern']) if p['topic_pattern'] else None
        path = Path(p['output'] or default_output())
        path.parent.mkdir(parents=True, exist_ok=True)
        self._writer = McapWriter(path, chunk_bytes=p['chunk_bytes'],
                                  chunk_seconds=p['chunk_seconds'],
                                  compression=p['compression'])
        self._channels: dict[str, int] = {}
        self.error: str | None = None  # why recording stopped early (None: it did not)
        self.warnings: list[str] = []  # second sources seen on the recorded tumble topics
        self._sim_time = bool(self.get_parameter('use_sim_time').value)
        self._log_sim = p['log_time'] == 'sim'
        self._sim_now = 0  # latest stamp of a tumble topic received [ns] (log_time sim)
        # per-sample topic -> (stamp ns, wall time)
        self._last_stamp: dict[str, tuple[int, float]] = {}
        # (monotonic time of the last look, the quiet per-sample topics without publishers)
        self._gone_checked: tuple[float, set[str]] = (-math.inf, set())
        self._per_sample_discovered_at = -math.inf  # monotonic time of the last look
        #: this namespace's tumble topics (resolved names)
        self._tumble_topics = {self.resolve_topic_name(t) for t in DEFAULT_TOPICS}
        self._progress = ProgressReporter(self, source=self._slowest_live_stamp,
                                          heard=lambda: self._produced.heard())
        # per-sample topics other consumers announce (the comparator's): subscribed at once
        self._produced = ProducedTopics(
            self, on_new=lambda: self._discover(quick=True),
            on_late=lambda topic: self.get_logger().warning(
                f'{topic}: announced but not found on the graph within '
                f'{self._produced.wait:g} s: not waiting for it'))
        self._discover()
        steady_timer(self, p['discovery_period'], self._discover)
        steady_timer(self, p['chunk_seconds'] / 4, self._poll)
        # (/tf and /tf_static: every asteroid publishes there, with its own frames)
        self._sources = SourceMonitor(
            self, lambda: [t for t, c in self._channels.items()
                           if c >= 0 and t in self._tumble_topics
                           and t not in SHARED_TOPICS],
            self._on_sources)
        self.get_logger().info(f'recording to {path}')

    @property
    def path(self) -> Path:
        """Return the file being written."""
        return self._writer.path

    @property
    def counts(self) -> dict[str, int]:
        """Return the count of messages written per topic."""
        return self._writer.counts

    def _resolve(self, parameter: str, topic: str) -> str:
        try:
            return self.resolve_topic_name(topic)
        except (InvalidTopicNameException, _rclpy.RCLError) as err:
            reason = ' '.join(str(err).split())
            raise NodeError(f'{parameter}: invalid topic name {topic!r}: {reason}') from None

    def _on_sources(self, problem: str | None) -> None:
        if problem:
            self.warnings.append(problem)

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for p in parameters:
            if p.name == 'compression' and p.value not in COMPRESSIONS:
                return SetParametersResult(
                    successful=False,
                    reason=f"compression: must be one of {', '.join(COMPRESSIONS)}")
            if p.name == 'topic_pattern':
                try:
                    re.compile(p.value)
                except re.error as err:
                    return SetParametersResult(successful=False,
                                               reason=f'topic_pattern: not a regex: {err}')
        return SetParametersResult(successful=True)

    # -- discovery ----------------------------------------------------------------------
    def _wanted(self, topic: str) -> bool:
        return topic in self._explicit or (self._pattern is not None
                                           and self._pattern.search(topic) is not None)

    def _discover(self, quick: bool = False) -> None:
        """
        Subscribe to the wanted topics not recorded yet.

        ``quick``: only the per-sample topics and the tumble topics of this namespace
        (:data:`DEFAULT_TOPICS`), looked for every QUIET_TOPIC whatever ``discovery_period``: a
        simulator's ``/clock``, ``status`` and markers, discovered a moment after its first
        topics, are subscribed at once, not a ``discovery_period`` later (a short run could be
        over by then, and those topics lost).
        """
        for topic, types in self.get_topic_names_and_types():
            if topic in self._channels or not self._wanted(topic):
                continue
            if quick and topic not in self._tumble_topics and not (
                    len(types) == 1 and types[0] in PER_SAMPLE_TYPES):
                continue
            if len(types) != 1:
                self.get_logger().warning(f'not recording {topic}: it has several types {types}')
                self._channels[topic] = -1
                continue
            self._subscribe(topic, types[0])

    def _subscribe(self, topic: str, type_name: str) -> None:
        publishers = self.get_publishers_info_by_topic(topic)
        if not publishers:
            return  # only subscribers so far: the type is known but nobody offers QoS yet
        try:
            msg_class = _import_type(type_name)
            offered = offered_qos_yaml(*[qos_dict(p.qos_profile) for p in publishers])
            channel = self._writer.add_channel(topic, type_name, offered)
        except NotAnInterface as err:
            self.get_logger().warning(f'not recording {topic} ({type_name}): {err}')
            self._channels[topic] = -1
            return
        except (LookupError, ImportError, ValueError) as err:
            self.get_logger().error(f'cannot record {topic} ({type_name}): {err}')
            self._channels[topic] = -1
            return
        self._channels[topic] = channel
        latched = all(p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                      for p in publishers)
        reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
        qos = QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=STATE_QOS.depth,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)
        per_sample = type_name in PER_SAMPLE_TYPES
        # the tumble topics' stamps are simulated time; a foreign topic's may be anything
        stamp_of = (stamp_reader(type_name)
                    if topic in {self.resolve_topic_name(t) for t in DEFAULT_TOPICS} else None)

        def on_message(data: bytes, info) -> None:
            if self.error is not None:
                return
            wall = time.time_ns()
            stamp = stamp_of(data) if stamp_of is not None else None
            if not self._log_sim:
                logged = self.get_clock().now().nanoseconds if self._sim_time else wall
            elif stamp is not None:
                logged = stamp
                self._sim_now = max(self._sim_now, stamp)
            else:
                logged = self._sim_now
            sent = (info.get('source_timestamp') or wall) if info else wall
            try:
                self._writer.write(channel, data, logged, sent)
            except OSError as err:
                self._stop_recording(err)
                return
            if per_sample:
                self._last_stamp[topic] = (_header_stamp_ns(data), time.monotonic())

        callback = on_message if self._message_info else (lambda data: on_message(data, None))
        # (rclpy hands a two-argument callback the MessageInfo too; its stubs know one argument)
        self.create_subscription(msg_class, topic, callback,  # type: ignore[arg-type]
                                 qos, raw=True)
        self.get_logger().info(f'recording {topic} ({type_name})')

    def _slowest_live_stamp(self) -> int | None:
        """
        Return the progress [ns]: the latest stamp every live per-sample topic has reached.

        Live: heard from within STALE_TOPIC, and still published (:meth:`_gone_topics`).
        Wanted per-sample topics are looked for here too, every QUIET_TOPIC whatever
        ``discovery_period``: one that appears mid-run (a comparator started after the
        simulator) is subscribed before the simulator, paced on this progress, has published
        more samples than its transient-local history (STATE_QOS depth) replays; and while a
        per-sample topic that a consumer announced (``ConsumerProgress.produces``) is not
        subscribed yet, the progress holds (None: the last report stands).
        """
        now = time.monotonic()
        if now - self._per_sample_discovered_at >= QUIET_TOPIC:
            self._per_sample_discovered_at = now
            self._discover(quick=True)
        if self._produced.awaited(lambda t: t in self._channels or not self._wanted(t)):
            return None   # a consumer's announced topic is not subscribed yet: hold
        gone = self._gone_topics(now)
        live = [ns for topic, (ns, seen) in self._last_stamp.items()
                if now - seen < STALE_TOPIC and topic not in gone]
        return min(live) if live else None

    def _gone_topics(self, now: float) -> set[str]:
        """
        Return the per-sample topics silent for QUIET_TOPIC [s] that have no publisher left.

        A consumer that stops (a comparator's Ctrl-C) says goodbye to the simulator, then its
        publishers go; without this its topics held the recorder's progress, so the simulator,
        until STALE_TOPIC. The graph is asked at most every QUIET_TOPIC, only about quiet topics.
        """
        if now - self._gone_checked[0] >= QUIET_TOPIC:
            gone = {topic for topic, (_, seen) in self._last_stamp.items()
                    if now - seen >= QUIET_TOPIC and self.count_publishers(topic) == 0}
            self._gone_checked = (now, gone)
        return self._gone_checked[1]

    def _poll(self) -> None:
        if self.error is None:
            try:
                self._writer.poll()
            except OSError as err:
                self._stop_recording(err)

    def _stop_recording(self, err: OSError) -> None:
        """Stop recording on a failed write: keep what was flushed, stop holding the simulator."""
        flushed = self._writer.messages_flushed
        self.error = (f'recording stopped: cannot write {self.path}: {err.strerror or err}; '
                      f'the file keeps the {flushed} messages flushed before the failure')
        self.get_logger().error(self.error)
        try:
            # finalise if the disk allows; the flushed chunks stay readable anyway
            self._writer.close()
        except OSError:
            pass
        self._progress.close()

    def close(self) -> None:
        """Finalise the file (idempotent) and tell the simulator this consumer leaves."""
        if not self._writer.closed:
            try:
                self._writer.close()
            except OSError as err:
                self._stop_recording(err)
            else:
                self.get_logger().info(f'wrote {self.path}: {sum(self.counts.values())} '
                                       f'messages on {len(self.counts)} topics')
                self._say_clock_missed()
        self._progress.close()

    @property
    def clock_missed(self) -> tuple[int, int] | None:
        """
        Return (``/clock`` messages missed, samples recorded); None without both topics.

        ``/clock`` is best effort (CLOCK_QOS) and volatile: it may drop under load, and what was
        published before the subscription is never replayed. The simulator publishes one per
        sample, with the sample's stamp: missed = the samples recorded on ``angular_velocity``
        (the namespace with the most) minus the ``/clock`` messages recorded.
        """
        counts = self.counts
        samples = [n for topic, n in counts.items()
                   if topic.rsplit('/', 1)[-1] == topics.ANGULAR_VELOCITY]
        if topics.CLOCK not in counts or not samples:
            return None
        return max(0, max(samples) - counts[topics.CLOCK]), max(samples)

    def _say_clock_missed(self) -> None:
        """Log how many /clock messages the recording misses (a warning when some)."""
        missed = self.clock_missed
        if missed is None:
            return
        text = (f'{topics.CLOCK}: {missed[0]} of {missed[1]} samples missed '
                '(best effort, recorded as received)')
        (self.get_logger().warning if missed[0] else self.get_logger().info)(text)


def default_output(stem: str = 'tumble') -> Path:
    """
    Claim a new recording's path: recordings/<stem>_<UTC time>.mcap, created empty.

    The name is claimed atomically (created with ``O_EXCL``, the directory too if needed): a
    run started in the same second as another gets _2, _3, ... appended, never a refusal to
    start. The writer then takes the empty file (:func:`tumble_ros.io.mcap_writer.open_new`);
    a file with content is still never overwritten.
    """
    base = f'recordings/{stem}_{datetime.now(timezone.utc):%Y%m%dT%H%M%S}'
    Path(base).parent.mkdir(parents=True, exist_ok=True)
    k = 1
    while True:
        path = Path(base + ('.mcap' if k == 1 else f'_{k}.mcap'))
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL
                             | getattr(os, 'O_CLOEXEC', 0), 0o666))
        except FileExistsError:
            k += 1
            continue
        return path


#: The interface kinds a recorded type may be of (rosidl's namespaces in a package).
INTERFACE_KINDS = ('msg', 'srv', 'action')


class NotAnInterface(LookupError):
    """An advertised type that is not one of an installed ROS interface package: not imported."""


def _interface_files(package: str) -> set[str]:
    """Return the interface files ('msg/Foo.msg', ...) the ament index lists for ``package``."""
    from ament_index_python.packages import get_resource, PackageNotFoundError

    try:
        content, _ = get_resource('rosidl_interfaces', package)
    except (LookupError, PackageNotFoundError, ValueError):
        return set()
    return {line.strip() for line in content.splitlines() if line.strip()}


def _import_type(type_name: str):
    """
    Import the Python class of 'pkg/msg/Type' (also 'pkg/srv/Name_Event', 'pkg/action/...').

    Only from an installed ament interface package (the ``rosidl_interfaces`` resource of the
    ament index lists ``kind/Name``): the type name comes from any participant on the domain,
    and importing ``pkg.kind`` runs ``pkg``'s top-level code. Anything else raises
    :class:`NotAnInterface` before any import (the topic is not recorded, with a warning).
    """
    import importlib

    parts = type_name.split('/')
    if (len(parts) != 3 or parts[1] not in INTERFACE_KINDS
            or not all(p.isidentifier() and p.isascii() for p in parts)):
        raise NotAnInterface(f'not an interface type name (pkg/msg/Type, pkg/srv/Type, '
                             f'pkg/action/Type): {type_name!r}')
    package, kind, name = parts
    names = {Path(f).stem for f in _interface_files(package)
             if f.startswith(kind + '/') and f.endswith(('.msg', '.srv', '.action', '.idl'))}
    # msg/Type exactly; a service's or an action's topics are named Type_Event, Type_Feedback...
    if name not in names and (kind == 'msg' or not any(name.startswith(n + '_') for n in names)):
        raise NotAnInterface(f'{kind}/{name} is no interface of an installed ROS interface '
                             f'package {package!r} (ament index: rosidl_interfaces): not imported')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run tumble_ros recorder``."""
    # the events executor cannot hand MessageInfo over: publish times are then receipt times
    return run_node(lambda: RecorderNode(message_info=chosen_executor() != 'events'), args,
                    'recorder')


if __name__ == '__main__':
    raise SystemExit(main())

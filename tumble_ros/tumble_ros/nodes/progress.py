"""
Flow control between the simulator and the consumers that must not lose samples.

DDS alone does not give "as fast as the subscribers take it": a reliable writer with a
bounded history overwrites samples a slow reader has not taken yet, and rclpy executors
take one message per subscription per wait cycle. So the consumers that need every
sample (comparator, recorder) report how far they got on ``consumer_progress``
(:class:`ProgressReporter`), and the simulator never runs more than a window of samples
ahead of the slowest of them (:class:`ConsumerTracker`). The window is well below the
depth of the state topics' queues, so nothing is ever overwritten.
"""
from __future__ import annotations

import time
from typing import Callable, Iterable

from builtin_interfaces.msg import Time
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from tumble_ros import topics
from tumble_ros.nodes.clocks import steady_timer
from tumble_ros_interfaces.msg import ConsumerProgress  # type: ignore[attr-defined]  # ROS message

__all__ = ['ProgressReporter', 'ConsumerTracker', 'ProducedTopics', 'PROGRESS_TOPIC',
           'CONSUMER_TIMEOUT']

PROGRESS_TOPIC = topics.CONSUMER_PROGRESS
PROGRESS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                          reliability=ReliabilityPolicy.RELIABLE)
#: Reporting period of a consumer [s] (when it made progress).
REPORT_PERIOD = 0.002
#: A consumer re-sends its progress at least this often [s], so a simulator that starts later
#: learns about it, and a silent consumer can be told from a slow one.
HEARTBEAT_PERIOD = 0.5
#: A consumer silent for this long [s] while behind is taken for dead and no longer waited for
#: (six missed heartbeats): the longest a killed consumer can hold the simulator.
CONSUMER_TIMEOUT = 3.0
#: How long a leaving consumer waits for its goodbye to be acknowledged [s].
GOODBYE_TIMEOUT = 0.5
#: How long a recorder holds the run for a per-sample topic a live consumer announced but its
#: graph does not show yet [s]. Discovery of a new publisher took over 3 s beside two CPU hogs
#: and a test suite (1611 comparator samples lost with a 3 s wait): a generous bound, reached
#: only if the announced publisher never appears; a consumer that dies lapses in
#: CONSUMER_TIMEOUT.
ANNOUNCED_TOPIC_WAIT = 30.0
_NOTHING_YET = -1


class ProgressReporter:
    """
    Publishes a consumer's progress (the stamp of the last sample it fully processed).

    The consumer calls :meth:`mark` as it goes, or passes ``source``: a function returning its
    progress stamp [ns] (or None), asked once per report instead of once per message.
    ``produces``: the per-sample topics the consumer publishes (resolved names), announced in
    every report so that a recorder of them waits until it receives them. ``heard`` (recorders
    only): returns the consumers whose announcements the recorder has taken in, reported so
    that the simulator waits until every recorder has heard every producing consumer.
    """

    def __init__(self, node: Node, source: Callable[[], int | None] | None = None,
                 produces: Iterable[str] = (),
                 heard: Callable[[], Iterable[str]] | None = None) -> None:
        self._node = node
        self._source = source
        self._produces = list(produces)
        self._heard = heard
        self._sent_heard: list[str] = []
        self._pub = node.create_publisher(ConsumerProgress, PROGRESS_TOPIC, PROGRESS_QOS)
        self._last_ns = _NOTHING_YET
        self._sent_ns: int | None = None
        self._sent_at = 0.0
        self._timer = steady_timer(node, REPORT_PERIOD, self._report)

    def mark(self, stamp_ns: int) -> None:
        """Record that every sample up to ``stamp_ns`` (ROS time, ns) has been processed."""
        if stamp_ns > self._last_ns:
            self._last_ns = stamp_ns

    def _report(self) -> None:
        if self._source is not None:
            stamp_ns = self._source()
            if stamp_ns is not None:
                self.mark(stamp_ns)
        heard = sorted(self._heard()) if self._heard is not None else []
        if (self._last_ns == self._sent_ns and heard == self._sent_heard
                and time.monotonic() - self._sent_at < HEARTBEAT_PERIOD):
            return
        self._sent_heard = heard
        self._publish(True)

    def _publish(self, active: bool) -> None:
        msg = ConsumerProgress(consumer=self._node.get_fully_qualified_name(), active=active,
                               produces=self._produces, records=self._heard is not None,
                               heard=self._sent_heard)
        if self._last_ns == _NOTHING_YET:
            msg.last_stamp = Time(sec=-1, nanosec=0)
        else:
            msg.last_stamp = Time(sec=self._last_ns // 1_000_000_000,
                                  nanosec=self._last_ns % 1_000_000_000)
        self._pub.publish(msg)
        self._sent_ns, self._sent_at = self._last_ns, time.monotonic()

    def close(self) -> None:
        """
        Tell the simulator this consumer is leaving, and wait (briefly) until it heard it.

        Called before the node is destroyed, with the context still valid (nodes.runner), so a
        stopped consumer never makes the simulator wait for it. Calling it again does nothing.
        """
        if self._timer.is_canceled():
            return
        self._timer.cancel()
        if self._node.context.ok():
            self._publish(False)
            self._pub.wait_for_all_acked(Duration(seconds=GOODBYE_TIMEOUT))


class ConsumerTracker:
    """
    The simulator's view of its consumers' progress.

    Parameters
    ----------
    node : the simulator node.
    timeout : seconds without a report after which a consumer that is behind is dropped
        (it died without saying so), with a warning.
    on_drop : called with a one-line message when a consumer is dropped (the simulator puts it
        on its ``status``).

    """

    def __init__(self, node: Node, timeout: float = CONSUMER_TIMEOUT,
                 on_drop: Callable[[str], None] | None = None) -> None:
        self._node = node
        self._timeout = timeout
        self._on_drop = on_drop
        # consumer -> (last ns, wall time of report)
        self._progress: dict[str, tuple[int, float]] = {}
        self._producers: dict[str, float] = {}  # producing consumer -> when first heard
        self._recorders: dict[str, frozenset[str]] = {}  # recorder -> the producers it heard
        self._given_up: set[tuple[str, str]] = set()  # (recorder, producer) no longer awaited
        node.create_subscription(ConsumerProgress, PROGRESS_TOPIC, self._on_progress, PROGRESS_QOS)

    def _on_progress(self, msg: ConsumerProgress) -> None:
        if not msg.active:
            if self._progress.pop(msg.consumer, None) is not None:
                self._node.get_logger().info(f'consumer {msg.consumer} left')
            self._forget(msg.consumer)
            return
        if msg.produces:
            self._producers.setdefault(msg.consumer, time.monotonic())
        if msg.records:
            self._recorders[msg.consumer] = frozenset(msg.heard)
        ns = (_NOTHING_YET if msg.last_stamp.sec < 0
              else msg.last_stamp.sec * 1_000_000_000 + msg.last_stamp.nanosec)
        if msg.consumer not in self._progress:
            self._node.get_logger().info(
                f'consumer {msg.consumer} registered: pacing on its progress')
        self._progress[msg.consumer] = (ns, time.monotonic())

    @property
    def count(self) -> int:
        """
        Return the number of consumers present (what ``min_consumers`` waits for).

        Present: heard from within the timeout and not gone (goodbye). A consumer that
        registered and then died before the first sample (no goodbye: killed, crashed) is
        dropped once silent for longer than the timeout, so it is not counted.
        """
        self._drop_silent(lambda ns: True)
        return len(self._progress)

    def slowest_ns(self, published_ns: int) -> int | None:
        """
        Stamp the slowest consumer has processed (-1: nothing yet); None without consumers.

        ``published_ns`` is the stamp of the last published sample: a consumer that is
        behind it and silent for longer than the timeout is dropped.
        """
        self._drop_silent(lambda ns: ns < published_ns)
        if not self._progress:
            return None
        return min(ns for ns, _ in self._progress.values())

    def recorders_behind(self) -> list[tuple[str, str]]:
        """
        Return the (recorder, producer) pairs where the recorder has not heard the producer yet.

        A producer is a present consumer that announces per-sample topics (the comparator); a
        recorder reports the producers whose announcements it has taken in. While a pair is
        listed the simulator publishes nothing more, so the recorder, whose discovery of the
        producer can lag the simulator's by seconds, cannot miss its first samples. A pair is
        waited for at most ANNOUNCED_TOPIC_WAIT after the producer was first heard (then a
        warning, once).
        """
        now = time.monotonic()
        behind = []
        for producer, first in self._producers.items():
            if producer not in self._progress:
                continue
            for recorder, heard in self._recorders.items():
                pair = (recorder, producer)
                if (recorder == producer or producer in heard or pair in self._given_up
                        or recorder not in self._progress):
                    continue
                if now - first > ANNOUNCED_TOPIC_WAIT:
                    self._given_up.add(pair)
                    self._node.get_logger().warning(
                        f'recorder {recorder} has not heard consumer {producer} within '
                        f'{ANNOUNCED_TOPIC_WAIT:g} s: no longer waiting for it')
                    continue
                behind.append(pair)
        return behind

    def _forget(self, name: str) -> None:
        self._producers.pop(name, None)
        self._recorders.pop(name, None)

    def _drop_silent(self, behind: Callable[[int], bool]) -> None:
        """Drop, with a warning, the consumers ``behind`` and silent longer than the timeout."""
        now = time.monotonic()
        for name, (ns, seen) in list(self._progress.items()):
            if behind(ns) and now - seen > self._timeout:
                message = (f'consumer {name} silent for {now - seen:.1f} s: '
                           'no longer waiting for it')
                self._node.get_logger().warning(message)
                del self._progress[name]
                self._forget(name)
                if self._on_drop is not None:
                    self._on_drop(message)


class ProducedTopics:
    """
    The per-sample topics that consumers announce they publish (``ConsumerProgress.produces``).

    A recorder holds its own progress while one it records is announced but not subscribed yet
    (:meth:`awaited`): the simulator, paced on that progress, then cannot run past what the
    topic's transient-local history replays once the subscription matches, however late the
    recorder's graph shows the new publisher (seconds under CPU contention). An announcement
    lapses when its consumer says goodbye or is silent for ``timeout`` [s], and is waited for
    at most ``wait`` [s] after it was first heard (then ``on_late`` is told, once): no
    announcement can hold the run for longer.
    """

    def __init__(self, node: Node, on_new: Callable[[], None] | None = None,
                 on_late: Callable[[str], None] | None = None,
                 timeout: float = CONSUMER_TIMEOUT,
                 wait: float = ANNOUNCED_TOPIC_WAIT) -> None:
        self._timeout = timeout
        self.wait = wait
        self._on_new = on_new
        self._on_late = on_late
        self._heard: dict[str, tuple[tuple[str, ...], float]] = {}  # consumer -> (topics, when)
        self._first: dict[str, float] = {}   # topic -> monotonic time first announced
        self._late: set[str] = set()
        node.create_subscription(ConsumerProgress, PROGRESS_TOPIC, self._on_progress, PROGRESS_QOS)

    def _on_progress(self, msg: ConsumerProgress) -> None:
        if not msg.active:
            self._heard.pop(msg.consumer, None)
            return
        if not msg.produces:
            return
        now = time.monotonic()
        topics = tuple(msg.produces)
        new = [t for t in topics if t not in self._first]
        for topic in new:
            self._first[topic] = now
        self._heard[msg.consumer] = (topics, now)
        if new and self._on_new is not None:
            self._on_new()

    def heard(self) -> list[str]:
        """Return the consumers whose announcement is current (a recorder reports them)."""
        return list(self._heard)

    def awaited(self, has: Callable[[str], bool]) -> set[str]:
        """Return the announced topics for which ``has(topic)`` is false, within the wait."""
        now = time.monotonic()
        for consumer in [c for c, (_, t) in self._heard.items() if now - t > self._timeout]:
            del self._heard[consumer]
        waiting = set()
        for topic in {t for topics, _ in self._heard.values() for t in topics}:
            if has(topic) or topic in self._late:
                continue
            if now - self._first[topic] > self.wait:
                self._late.add(topic)
                if self._on_late is not None:
                    self._on_late(topic)
                continue
            waiting.add(topic)
        return waiting

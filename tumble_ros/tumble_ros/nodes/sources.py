"""
Noticing a second source on topics that must have exactly one.

Every tumble topic has one publisher: the simulator's (state, ``/clock``, ``scenario``, ...) or
the comparator's (``comparison/*``). A second publisher means two runs mix: another simulator
on the same topics (two runs in one ROS domain), a foreign ``/clock``. DDS merges them silently;
:class:`SourceMonitor` looks at the ROS graph every ``period`` seconds and calls ``report`` with a
one-line message when the set of topics with more than one publisher changes (``None`` when it is
back to a single source). Each node puts that message where its users look: the simulator on
``status``, the comparator on ``comparison/status``, the recorder in its log and its summary.
"""
from __future__ import annotations

from typing import Callable, Iterable

from rclpy.node import Node

from tumble_ros.nodes.clocks import steady_timer

__all__ = ['SourceMonitor', 'SOURCE_CHECK_PERIOD']

#: Seconds between two looks at the graph.
SOURCE_CHECK_PERIOD = 1.0


class SourceMonitor:
    """
    Reports topics of ``node`` that have more than one publisher.

    Parameters
    ----------
    node : the node watching (its graph view is used).
    topics : callable returning the topic names to watch (relative names resolve in the node's
        namespace); called at each check, so a recorder can watch what it discovered.
    report : called with a message when the problem appears or changes, ``None`` when it clears.

    """

    def __init__(self, node: Node, topics: Callable[[], Iterable[str]],
                 report: Callable[[str | None], None],
                 period: float = SOURCE_CHECK_PERIOD) -> None:
        self._node = node
        self._topics = topics
        self._report = report
        self._last: str | None = None
        self._timer = steady_timer(node, period, self.check)

    def problem(self) -> str | None:
        """Return the current problem, or None if every watched topic has at most one publisher."""
        crowded = []
        for topic in self._topics():
            name = self._node.resolve_topic_name(topic)
            publishers = self._node.get_publishers_info_by_topic(name)
            if len(publishers) > 1:
                nodes = ', '.join(sorted(f"{p.node_namespace.rstrip('/')}/{p.node_name}"
                                         for p in publishers))
                crowded.append(f'{name} ({nodes})')
        if not crowded:
            return None
        return (f'second source: {len(crowded)} topic(s) with several publishers: '
                f"{'; '.join(crowded)}. "
                'Another run shares these topics (same ROS domain and namespace): '
                'their messages mix. Give each run its own ROS_DOMAIN_ID or namespace.')

    def check(self) -> None:
        """Look at the graph now; report a change."""
        problem = self.problem()
        if problem != self._last:
            self._last = problem
            if problem:
                self._node.get_logger().error(problem)
            else:
                self._node.get_logger().info('single source again on every watched topic')
            self._report(problem)

    @property
    def current(self) -> str | None:
        """Return the last problem reported (None: none)."""
        return self._last

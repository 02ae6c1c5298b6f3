"""QoS profiles shared by the tumble_ros nodes (one place, so publishers and subscribers match)."""
from typing import Any

from rclpy.duration import Duration
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                       ReliabilityPolicy)

from tumble_ros import topics

__all__ = ['STATE_QOS', 'CLOCK_QOS', 'LATCHED_QOS', 'DESCRIPTION_QOS', 'SERVICE_QOS',
           'PUBLISHER_QOS', 'publisher_qos', 'as_discovered']

#: Sampled state (w, attitude, Euler angles, /clock, events, comparisons): reliable with a deep
#: queue, and transient-local, so a subscriber whose subscription is matched a moment after the
#: publisher started (a recorder discovering topics, a late comparator) still receives the last
#: 1000 samples. The simulator never runs more than a window of 40 samples ahead of the slowest
#: consumer (nodes.progress), so the queue is never overrun for them.
STATE_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

#: ``/clock``: what rclpy's and rclcpp's time sources subscribe with (KEEP_LAST 1, best effort,
#: volatile; rclpy.time_source, rclcpp::ClockQoS). A node with ``use_sim_time`` only needs the
#: latest time; a reliable, transient-local /clock would replay old times to a late joiner.
#: Recorded as received: the per-sample topics, not /clock, carry the guarantee of completeness.
CLOCK_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
)

#: Latched descriptions (scenario, status): the last message reaches late joiners.
LATCHED_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

#: The simulator's segment descriptions (``scenario``): transient-local with a history, so a node
#: that starts late receives the last 100 segments of the run (the initial state and each
#: post-impact state) in order, and can compare samples from any of them. One description per
#: segment, each of constant size (the scenario as started, not the growing impact list): the
#: traffic grows linearly with the number of impacts. ``ros2 topic echo --once scenario`` prints
#: the oldest kept; the current segment is the one with the highest ``revision``.
DESCRIPTION_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

#: ``apply_impact`` (server side; clients that fire many requests without waiting should use it
#: too): KEEP_ALL, reliable. rclpy's default service QoS keeps the last 10 requests, so a burst of
#: more than 10 requests in flight silently lost the rest before the node saw them; with KEEP_ALL a
#: request that reached the node is never overwritten, and every one gets an answer (accepted, or
#: refused with a reason: the simulator bounds the impacts it holds, MAX_PENDING_IMPACTS).
SERVICE_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

#: The QoS each of the simulator's and the comparator's topics is published with.
PUBLISHER_QOS = {
    **{t.name: STATE_QOS for t in topics.SAMPLE_TOPICS},   # every per-sample topic
    topics.CLOCK: CLOCK_QOS,
    topics.IMPACT_EVENTS: STATE_QOS,
    topics.STATUS: LATCHED_QOS,
    topics.SCENARIO: DESCRIPTION_QOS,
    topics.MARKERS: STATE_QOS,
    # sent once: a viewer or recorder that comes later still gets it
    topics.BODY_MARKERS: LATCHED_QOS,
    # the attitude per sample, like every per-sample topic (tf2's listeners subscribe volatile:
    # they match it and get what is published from then on)
    topics.TF: STATE_QOS,
    # tf2's static broadcaster's QoS: reliable, transient local, depth 1
    topics.TF_STATIC: LATCHED_QOS,
    topics.COMPARISON_STATUS: LATCHED_QOS,
}


def publisher_qos(topic: str) -> QoSProfile:
    """Return the QoS ``topic`` is published with; every per-sample topic's is STATE_QOS."""
    if topic in PUBLISHER_QOS:
        return PUBLISHER_QOS[topic]
    topics.sample_topic(topic)   # KeyError for a topic that is neither
    return STATE_QOS


_INFINITE = Duration(nanoseconds=2**63 - 1)


def as_discovered(profile: QoSProfile) -> QoSProfile:
    """
    Return ``profile`` as another node discovers it (``get_publishers_info_by_topic``).

    DDS discovery carries reliability and durability, not history nor depth (reported as
    unknown / 0), and the default deadline, lifespan and lease duration as infinite; what the
    recorder stores as a channel's offered QoS (the offline recording writes the same).
    """
    return QoSProfile(history=HistoryPolicy.UNKNOWN, depth=0, reliability=profile.reliability,
                      durability=profile.durability, deadline=_INFINITE, lifespan=_INFINITE,
                      liveliness=LivelinessPolicy.AUTOMATIC,
                      liveliness_lease_duration=_INFINITE)


def _policy_name(policy: Any) -> str:
    return str(policy.name.lower())


def qos_dict(qos: QoSProfile) -> dict[str, Any]:
    """Return ``qos`` as the recorded form's fields (policy names lower case, (s, ns))."""
    def duration(d: Duration) -> tuple[int, int]:
        ns: int = d.nanoseconds
        return divmod(ns, 1_000_000_000)

    return {
        'history': _policy_name(qos.history), 'depth': qos.depth,
        'reliability': _policy_name(qos.reliability), 'durability': _policy_name(qos.durability),
        'deadline': duration(qos.deadline), 'lifespan': duration(qos.lifespan),
        'liveliness': _policy_name(qos.liveliness),
        'liveliness_lease_duration': duration(qos.liveliness_lease_duration),
        'avoid_ros_namespace_conventions': qos.avoid_ros_namespace_conventions,
    }

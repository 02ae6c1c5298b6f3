"""QoS profiles shared by the tumble_ros nodes (one place, so publishers and subscribers match)."""
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

__all__ = ['STATE_QOS', 'CLOCK_QOS', 'LATCHED_QOS', 'DESCRIPTION_QOS', 'SERVICE_QOS']

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

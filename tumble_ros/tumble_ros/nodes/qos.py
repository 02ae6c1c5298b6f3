"""QoS profiles shared by the tumble_ros nodes (one place, so publishers and subscribers match)."""
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

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

#: Latched descriptions (scenario, status): the last message reaches late joiners.
LATCHED_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

#: The simulator's segment descriptions (``scenario``): transient-local with a history, so a node
#: that starts late receives every segment of the run (the initial state and each post-impact
#: state) in order, and can compare samples from any of them.
DESCRIPTION_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

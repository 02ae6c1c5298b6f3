"""QoS profiles shared by the tumble_ros nodes (one place, so publishers and subscribers match)."""
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

#: Sampled state (w, attitude, Euler angles, /clock, events): reliable, deep queue, so a
#: subscriber that keeps up loses nothing; the simulator also waits for acknowledgements
#: between batches when it runs as fast as possible.
STATE_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

#: Latched descriptions (scenario, status): the last message reaches late joiners.
LATCHED_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

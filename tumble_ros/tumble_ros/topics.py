"""
The tumble topics and services: names, types, frames, in one place, without ROS.

And the simulator's own parameters (:data:`SIM_NODE_PARAMETERS`), the rest of its interface.

Names are relative (they resolve in a node's namespace, so two asteroids run side by side in
``/ast1`` and ``/ast2``), except ``/clock``, which is global by ROS convention. The nodes, the
recorder's defaults, the offline analysis and the tests all take them from here.
"""
from __future__ import annotations

__all__ = [
    'SIM_NODE_PARAMETERS', 'MARKER_FRAMES',
    'ANGULAR_VELOCITY', 'ATTITUDE', 'EULER_ANGLES', 'CLOCK', 'IMPACT_EVENTS', 'STATUS', 'SCENARIO',
    'CONSUMER_PROGRESS', 'PERTURBER', 'MARKERS', 'MODEL_ANGULAR_VELOCITY', 'ERROR', 'ERROR_NORM',
    'COMPARISON_STATUS',
    'APPLY_IMPACT', 'PAUSE', 'RESUME', 'STEP', 'TYPES', 'SIM_TOPICS', 'COMPARATOR_TOPICS',
    'RECORDED', 'PER_SAMPLE', 'SIM_PER_SAMPLE', 'COMPARATOR_PER_SAMPLE', 'FRAME_BODY',
    'FRAME_ORBITAL', 'FRAME_EULER', 'MARKER_BODY', 'MARKER_AXES', 'MARKER_MOMENTUM',
    'MARKER_SUN', 'MARKER_PERTURBER', 'in_namespace',
]

# -- the simulator's (sim) ---------------------------------------------------------------------
#: w [rad/yr] in body axes (geometry_msgs/Vector3Stamped, frame ``body``).
ANGULAR_VELOCITY = 'angular_velocity'
#: rotation body -> orbital frame (geometry_msgs/QuaternionStamped, frame ``orbital``).
ATTITUDE = 'attitude'
#: the paper's (phi, psi, theta) [rad] in x, y, z (geometry_msgs/Vector3Stamped).
EULER_ANGLES = 'euler_angles'
#: the simulated clock (global).
CLOCK = '/clock'
#: one message per impact, after it ended.
IMPACT_EVENTS = 'impact_events'
#: RUNNING / PAUSED / FINISHED / DIVERGED (latched).
STATUS = 'status'
#: one description per integration segment (latched, history).
SCENARIO = 'scenario'
#: consumers' progress, for the simulator's pacing (subscribed by the simulator).
CONSUMER_PROGRESS = 'consumer_progress'
#: where the torquing body is [km] in body axes (geometry_msgs/Vector3Stamped, frame ``body``):
#: its direction is the u of the tidal torque, its norm the distance; one per sample, published
#: when the scenario has a Kepler orbit or a flyby (orbit.kind kepler or flyby).
PERTURBER = 'perturber'
#: the 3D scene (visualization_msgs/MarkerArray, frame ``orbital``): body, axes, L, Sun.
MARKERS = 'markers'

# -- the comparator's --------------------------------------------------------------------------
MODEL_ANGULAR_VELOCITY = 'comparison/model_angular_velocity'
ERROR = 'comparison/error'
ERROR_NORM = 'comparison/error_norm'
COMPARISON_STATUS = 'comparison/status'

# -- the simulator's services --------------------------------------------------------------------
APPLY_IMPACT = 'apply_impact'
PAUSE = 'pause'
RESUME = 'resume'
STEP = 'step'

#: ROS type of every topic.
TYPES = {
    ANGULAR_VELOCITY: 'geometry_msgs/msg/Vector3Stamped',
    PERTURBER: 'geometry_msgs/msg/Vector3Stamped',
    ATTITUDE: 'geometry_msgs/msg/QuaternionStamped',
    EULER_ANGLES: 'geometry_msgs/msg/Vector3Stamped',
    CLOCK: 'rosgraph_msgs/msg/Clock',
    IMPACT_EVENTS: 'tumble_ros_interfaces/msg/ImpactEvent',
    STATUS: 'tumble_ros_interfaces/msg/SimStatus',
    SCENARIO: 'tumble_ros_interfaces/msg/ScenarioDescription',
    CONSUMER_PROGRESS: 'tumble_ros_interfaces/msg/ConsumerProgress',
    MARKERS: 'visualization_msgs/msg/MarkerArray',
    MODEL_ANGULAR_VELOCITY: 'geometry_msgs/msg/Vector3Stamped',
    ERROR: 'geometry_msgs/msg/Vector3Stamped',
    ERROR_NORM: 'tumble_ros_interfaces/msg/ErrorNorm',
    COMPARISON_STATUS: 'diagnostic_msgs/msg/DiagnosticStatus',
}

#: What the simulator publishes (``/clock`` unless ``publish_clock`` is false, ``perturber``
#: with a Kepler orbit, ``markers`` unless ``markers`` is false).
SIM_TOPICS = (ANGULAR_VELOCITY, ATTITUDE, EULER_ANGLES, CLOCK, IMPACT_EVENTS, STATUS, SCENARIO,
              PERTURBER, MARKERS)
#: What the comparator publishes.
COMPARATOR_TOPICS = (MODEL_ANGULAR_VELOCITY, ERROR, ERROR_NORM, COMPARISON_STATUS)
#: What the recorder records by default.
RECORDED = SIM_TOPICS + COMPARATOR_TOPICS
#: One message per simulator sample, reliable: a complete recording has as many of each as the
#: simulator published samples (comparisons: one per compared sample). Not ``/clock``: best effort.
SIM_PER_SAMPLE = (ANGULAR_VELOCITY, ATTITUDE, EULER_ANGLES)
COMPARATOR_PER_SAMPLE = (MODEL_ANGULAR_VELOCITY, ERROR, ERROR_NORM)
PER_SAMPLE = SIM_PER_SAMPLE + COMPARATOR_PER_SAMPLE

#: ``header.frame_id`` of body-axis vectors, of the attitude (and the markers), of the Euler
#: angles.
FRAME_BODY = 'body'
FRAME_ORBITAL = 'orbital'
FRAME_EULER = 'euler_phi_psi_theta'

#: Namespaces (``ns``) of the ``markers`` scene: the body, its principal axes (ids 0, 1, 2: x, y,
#: z), the angular momentum's direction, the Sun (circular orbit) or the perturber (Kepler orbit).
MARKER_BODY = 'body'
MARKER_AXES = 'axes'
MARKER_MOMENTUM = 'angular_momentum'
MARKER_SUN = 'sun'
MARKER_PERTURBER = 'perturber'


def in_namespace(namespace: str, topic: str) -> str:
    """
    Return the full name of ``topic`` in ``namespace`` (``'/ast1'``, ``'/'`` or ``''``).

    A global name (``/clock``) is returned as it is, as ROS resolves it.
    """
    if topic.startswith('/'):
        return topic
    namespace = namespace.strip('/')
    return f'/{namespace}/{topic}' if namespace else f'/{topic}'


#: Auto decimation (``marker_decimation`` 0): at most about this many scenes per run.
MARKER_FRAMES = 10_000

#: The simulator's own parameters, not the scenario's: name -> (default, unit, description,
#: (min, max) or None, read_only). Here, without ROS, so that the tools reading a simulator's
#: params file for its scenario (``cli.ensemble``, ``cli.encounter``) skip them.
SIM_NODE_PARAMETERS = {
    'seconds_per_year': (0.0, 's/yr', 'ROS seconds per simulated year in every stamp and /clock; '
                         '0 = one ROS second per time_unit (1 for yr, 8766 for h)',
                         (0.0, 1e6), True),
    'real_time_factor': (0.1, 'yr/s', 'simulated years per wall-clock second; 0 = as fast as the '
                         'subscribers take it', (0.0, 1e6), False),
    'start_paused': (False, '', 'start paused (resume or step with the services)', None, True),
    'min_consumers': (0, '', 'wait until this many consumers report progress before publishing',
                      None, True),
    'publish_clock': (True, '', 'publish /clock (one simulator per ROS domain should)', None,
                      True),
    'max_impact_duration': (1e-3, 'yr', 'longest impact pulse the service accepts', (1e-15, 1e6),
                            False),
    'max_impact_impulse': (1e3, 'I rad/yr', 'largest |M| * duration the service accepts',
                           (1e-12, 1e15), False),
    'markers': (False, '', 'publish the 3D scene (body, axes, L, Sun) on markers (bringup, '
                'make run and the launch files turn it on)', None, True),
    'marker_decimation': (0, '', 'a scene every k-th sample (and the last); 0 = auto: every '
                          f'sample up to {MARKER_FRAMES} samples, at most ~{MARKER_FRAMES} '
                          'scenes', (0, 1_000_000), True),
}

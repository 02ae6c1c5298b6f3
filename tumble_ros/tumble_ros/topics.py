"""
The tumble topics and services: names, types, frames, in one place, without ROS.

And the simulator's own parameters (:data:`SIM_NODE_PARAMETERS`), the rest of its interface.

Names are relative (they resolve in a node's namespace, so two asteroids run side by side in
``/ast1`` and ``/ast2``), except ``/clock``, which is global by ROS convention. The nodes, the
recorder's defaults, the offline analysis and the tests all take them from here.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = [
    'SampleTopic', 'SAMPLE_TOPICS', 'SIM', 'COMPARATOR', 'sample_topics', 'sample_topic',
    'recorded',
    'SIM_NODE_PARAMETERS', 'MARKER_FRAMES',
    'ANGULAR_VELOCITY', 'ATTITUDE', 'EULER_ANGLES', 'CLOCK', 'IMPACT_EVENTS', 'STATUS', 'SCENARIO',
    'CONSUMER_PROGRESS', 'PERTURBER', 'LIGHTCURVE', 'MARKERS', 'MODEL_ANGULAR_VELOCITY', 'ERROR',
    'ERROR_NORM', 'COMPARISON_STATUS',
    'APPLY_IMPACT', 'PAUSE', 'RESUME', 'STEP', 'TYPES', 'SIM_TOPICS', 'COMPARATOR_TOPICS',
    'RECORDED', 'PER_SAMPLE', 'SIM_PER_SAMPLE', 'COMPARATOR_PER_SAMPLE', 'FRAME_BODY',
    'FRAME_ORBITAL', 'FRAME_EULER', 'MARKER_BODY', 'MARKER_AXES', 'MARKER_MOMENTUM',
    'MARKER_SUN', 'MARKER_PERTURBER', 'in_namespace', 'BODY_MARKERS', 'TF', 'TF_STATIC',
    'SHARED_TOPICS', 'FRAME_GIVEN', 'frame_id',
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
#: where the (first) torquing body is [km] in body axes (geometry_msgs/Vector3Stamped, frame
#: ``body``): its direction is the u of the tidal torque, its norm the distance; one per sample,
#: published when the scenario has a perturber (orbit.kind kepler or flyby, or perturbers.*):
#: the first of ``Scenario.all_perturbers`` (the markers draw each).
PERTURBER = 'perturber'
#: what a telescope sees (tumble_ros_interfaces/Lightcurve, frame ``body``): brightness,
#: magnitude, phase angle, the Sun's and the observer's latitude and longitude in body axes;
#: one per sample, published when the body is physical and ``lightcurve.enabled``.
LIGHTCURVE = 'lightcurve'
#: the 3D scene's moving part (visualization_msgs/MarkerArray, frame ``orbital``): L and the
#: Sun or the perturbers, one per shown sample.
MARKERS = 'markers'
#: the 3D scene's fixed part (visualization_msgs/MarkerArray, frame ``body``, ``frame_locked``):
#: the body's shape and its principal axes, sent once (latched); TF turns it.
BODY_MARKERS = 'body_markers'
#: the attitude as a transform ``orbital`` -> ``body`` (tf2_msgs/TFMessage), one per sample;
#: global, as tf2 has it: the frames carry the namespace (:func:`frame_id`).
TF = '/tf'
#: what is fixed: ``body`` -> ``body_as_given`` (tf2_msgs/TFMessage, latched), once.
TF_STATIC = '/tf_static'

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

#: ``header.frame_id`` of body-axis vectors, of the attitude (and the markers), of the Euler
#: angles.
FRAME_BODY = 'body'
FRAME_ORBITAL = 'orbital'
FRAME_EULER = 'euler_phi_psi_theta'
#: The frame the body was given in (a shape file's vertices; for an ellipsoid or given moments
#: the principal axes themselves): a child of ``body`` on ``/tf_static``.
FRAME_GIVEN = 'body_as_given'

#: Who publishes a per-sample topic (:attr:`SampleTopic.source`).
SIM = 'sim'
COMPARATOR = 'comparator'

#: A sample block: name -> (n,) or (n, k) numpy array of n samples (what a
#: :attr:`SampleTopic.columns` reads). The simulator's: ``omega`` (n, 3) [rad/yr] body axes,
#: ``quaternion`` (n, 4) body -> orbital (scalar first), ``euler`` (n, 3) the continuous
#: (phi, psi, theta) [rad], ``perturber`` (n, 3) [km] body axes or None (no orbit),
#: ``lightcurve`` a ``core.photometry.LightcurveRecord`` or None (no body); the
#: comparator's: ``model``, ``error`` (n, 3) [rad/yr] body axes, ``norm`` [rad/yr] and
#: ``relative`` (n,).
SampleBlock = Mapping[str, Any]


@dataclass(frozen=True)
class SampleTopic:
    """
    One per-sample topic, described once: what it is and how its columns come from a sample block.

    The live encoder (``runs.messages.builders.SampleEncoder``: the simulator, the comparator, the
    offline writer), the columnar decoder (``io.columns.sample_values``), the analysis and the
    viewer layouts' check (tests/test_foxglove_layout.py) all read it.
    ``name``: relative topic name; ``type_name``: its ROS type (flat: a header, numbers, maybe
    strings); ``fields``: the dotted names of its numeric value fields, in the columns' order
    (the header stamp apart); ``frame``: its ``header.frame_id``; ``source``: :data:`SIM` or
    :data:`COMPARATOR`; ``columns(block)``: its value columns from a :data:`SampleBlock`, one
    (n,) sequence per field, or None when the block does not have them (then it is not
    published: ``perturber`` without an orbit); ``strings``: its other string fields, whose
    values the publisher gives (``model``: the comparator's model name); ``always``: published
    for every sample of every run (``perturber``: only with an orbit).
    """

    name: str
    type_name: str
    fields: tuple[str, ...]
    frame: str
    source: str
    columns: Callable[[SampleBlock], Sequence[Any] | None]
    strings: tuple[str, ...] = ()
    always: bool = True


def _rows_of(key: str) -> Callable[[SampleBlock], Sequence[Any] | None]:
    """Return the columns of the block's (n, k) array ``key`` (None when it is absent)."""
    def columns(block: SampleBlock) -> Sequence[Any] | None:
        value = block.get(key)
        return None if value is None else value.T
    return columns


def _each_of(*keys: str) -> Callable[[SampleBlock], Sequence[Any] | None]:
    """Return the block's (n,) arrays ``keys`` as the columns."""
    def columns(block: SampleBlock) -> Sequence[Any] | None:
        return tuple(block[key] for key in keys)
    return columns


def _lightcurve(block: SampleBlock) -> Sequence[Any] | None:
    """Return the columns of the block's lightcurve record (None without one)."""
    record = block.get('lightcurve')
    if record is None:
        return None
    return (record.brightness, record.magnitude, record.phase_angle, *record.sun_aspect.T,
            *record.observer_aspect.T, record.light_time)


_XYZ = ('vector.x', 'vector.y', 'vector.z')
_WXYZ = ('quaternion.w', 'quaternion.x', 'quaternion.y', 'quaternion.z')
_VECTOR = 'geometry_msgs/msg/Vector3Stamped'

#: The per-sample topics, in the order they are published for a sample (the one place a new
#: per-sample topic is added: docs/ros.md, "Adding a per-sample topic").
SAMPLE_TOPICS: tuple[SampleTopic, ...] = (
    SampleTopic(ANGULAR_VELOCITY, _VECTOR, _XYZ, FRAME_BODY, SIM, _rows_of('omega')),
    SampleTopic(ATTITUDE, 'geometry_msgs/msg/QuaternionStamped', _WXYZ, FRAME_ORBITAL, SIM,
                _rows_of('quaternion')),
    SampleTopic(EULER_ANGLES, _VECTOR, _XYZ, FRAME_EULER, SIM, _rows_of('euler')),
    SampleTopic(PERTURBER, _VECTOR, _XYZ, FRAME_BODY, SIM, _rows_of('perturber'), always=False),
    SampleTopic(LIGHTCURVE, 'tumble_ros_interfaces/msg/Lightcurve',
                ('brightness', 'magnitude', 'phase_angle', 'sun_aspect_lat', 'sun_aspect_lon',
                 'observer_aspect_lat', 'observer_aspect_lon', 'light_time'),
                FRAME_BODY, SIM, _lightcurve, always=False),
    SampleTopic(MODEL_ANGULAR_VELOCITY, _VECTOR, _XYZ, FRAME_BODY, COMPARATOR,
                _rows_of('model')),
    SampleTopic(ERROR, _VECTOR, _XYZ, FRAME_BODY, COMPARATOR, _rows_of('error')),
    SampleTopic(ERROR_NORM, 'tumble_ros_interfaces/msg/ErrorNorm', ('norm', 'relative'),
                FRAME_BODY, COMPARATOR, _each_of('norm', 'relative'), strings=('model',)),
)


def sample_topics(source: str | None = None) -> tuple[SampleTopic, ...]:
    """Return the per-sample topics (of ``source``: :data:`SIM`, :data:`COMPARATOR`), in order."""
    return tuple(t for t in SAMPLE_TOPICS if source is None or t.source == source)


def sample_topic(name: str) -> SampleTopic:
    """Return the description of the per-sample topic ``name``; KeyError if it is not one."""
    for topic in SAMPLE_TOPICS:
        if topic.name == name:
            return topic
    raise KeyError(f'{name}: not a per-sample topic')


#: ROS type of every topic.
TYPES = {
    **{t.name: t.type_name for t in SAMPLE_TOPICS},
    CLOCK: 'rosgraph_msgs/msg/Clock',
    IMPACT_EVENTS: 'tumble_ros_interfaces/msg/ImpactEvent',
    STATUS: 'tumble_ros_interfaces/msg/SimStatus',
    SCENARIO: 'tumble_ros_interfaces/msg/ScenarioDescription',
    CONSUMER_PROGRESS: 'tumble_ros_interfaces/msg/ConsumerProgress',
    MARKERS: 'visualization_msgs/msg/MarkerArray',
    BODY_MARKERS: 'visualization_msgs/msg/MarkerArray',
    TF: 'tf2_msgs/msg/TFMessage',
    TF_STATIC: 'tf2_msgs/msg/TFMessage',
    COMPARISON_STATUS: 'diagnostic_msgs/msg/DiagnosticStatus',
}

#: What the simulator publishes (``/clock`` unless ``publish_clock`` is false, ``perturber``
#: with a Kepler orbit, ``markers`` and ``body_markers`` unless ``markers`` is false).
SIM_TOPICS = (*(t.name for t in sample_topics(SIM)), CLOCK, IMPACT_EVENTS, STATUS, SCENARIO,
              MARKERS, BODY_MARKERS, TF, TF_STATIC)
#: Topics every simulator of a domain shares by design (tf2's): two asteroids publish on them
#: with their own frames, so a second publisher there is no second source.
SHARED_TOPICS = (TF, TF_STATIC)
#: What the comparator publishes.
COMPARATOR_TOPICS = (*(t.name for t in sample_topics(COMPARATOR)), COMPARISON_STATUS)
#: What the recorder records by default.
RECORDED = SIM_TOPICS + COMPARATOR_TOPICS
#: One message per simulator sample, reliable: a complete recording has as many of each as the
#: simulator published samples (comparisons: one per compared sample). Not ``/clock``: best effort.
SIM_PER_SAMPLE = tuple(t.name for t in sample_topics(SIM) if t.always)
COMPARATOR_PER_SAMPLE = tuple(t.name for t in sample_topics(COMPARATOR) if t.always)
PER_SAMPLE = SIM_PER_SAMPLE + COMPARATOR_PER_SAMPLE


def recorded() -> tuple[str, ...]:
    """Return :data:`RECORDED` and every per-sample topic described since (in that order)."""
    return RECORDED + tuple(t.name for t in SAMPLE_TOPICS if t.name not in RECORDED)


#: Namespaces (``ns``) of the ``markers`` scene: the body, its principal axes (ids 0, 1, 2: x, y,
#: z), the angular momentum's direction, the Sun (circular orbit) or the perturbers (ids 0, 1...).
MARKER_BODY = 'body'
MARKER_AXES = 'axes'
MARKER_MOMENTUM = 'angular_momentum'
MARKER_SUN = 'sun'
MARKER_PERTURBER = 'perturber'


def frame_id(namespace: str, frame: str) -> str:
    """
    Return the TF frame id of ``frame`` in a node's ``namespace`` (``'/ast1'``, ``'/'``, ``''``).

    ``frame_id('/ast1', 'body') == 'ast1/body'``, ``frame_id('/', 'body') == 'body'``: tf2 frame
    ids carry no leading slash, and two asteroids' frames on the shared ``/tf`` never collide.
    """
    namespace = namespace.strip('/')
    return f'{namespace}/{frame}' if namespace else frame


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
                         '0 = one ROS second per time_unit (1 for yr, 8766 for h): the grid of '
                         'simulate(scenario); another value samples its own grid',
                         (0.0, 1e6), True),
    'real_time_factor': (0.1, 'time_unit/s', 'simulated time per wall-clock second, in the '
                         "scenario's time_unit (the default 0.1: the default run's 2 yr in 20 s, "
                         'a 144-h flyby in 24 min); 0 = as fast as the subscribers take it',
                         (0.0, 1e6), False),
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

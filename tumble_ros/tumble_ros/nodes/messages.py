"""
The messages the simulator and the comparator publish, built in one place.

The live nodes publish them; the offline recorder (:mod:`.offline`) writes the same messages
straight to a file. Units as on the topics: time [yr], angular velocity [rad/yr] (body axes),
attitude quaternion body -> orbital (scalar first), stamps [ns] of ROS time.
"""
from __future__ import annotations

import math

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Quaternion, Vector3, Vector3Stamped

from tumble_ros import topics
from tumble_ros.core import Impact
from tumble_ros_interfaces.msg import ErrorNorm, ImpactEvent, ScenarioDescription, SimStatus
from tumble_ros_interfaces.srv import ApplyImpact

__all__ = ['stamp', 'FRAMES', 'FRAME_CODES', 'scenario_description', 'impact_event',
           'sim_status', 'comparison_status', 'comparison_values', 'error_norms',
           'comparison_messages']

#: ApplyImpact / ImpactEvent frame codes <-> Impact frames.
FRAMES = {ApplyImpact.Request.FRAME_BODY: topics.FRAME_BODY,
          ApplyImpact.Request.FRAME_ORBITAL: topics.FRAME_ORBITAL}
FRAME_CODES = {name: code for code, name in FRAMES.items()}


def stamp(ns: int) -> Time:
    """builtin_interfaces/Time of integer nanoseconds."""
    sec, nanosec = divmod(ns, 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _vector(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def scenario_description(scenario_yaml: str, seconds_per_year: float, revision: int,
                         stamp_ns: int, t0: float, omega, quaternion) -> ScenarioDescription:
    """Describe the scenario and the state (omega, quaternion) its segment starts from at t0."""
    msg = ScenarioDescription()
    msg.header.stamp = stamp(stamp_ns)
    msg.parameters_yaml = scenario_yaml
    msg.seconds_per_year = seconds_per_year
    msg.revision = revision
    msg.segment_start = t0
    msg.omega = _vector(omega)
    msg.attitude = Quaternion(w=float(quaternion[0]), x=float(quaternion[1]),
                              y=float(quaternion[2]), z=float(quaternion[3]))
    return msg


def impact_event(impact: Impact, impact_id: int, stamp_ns: int, delta_omega) -> ImpactEvent:
    """Report an impact that ended: its pulse and the jump of omega it made [rad/yr]."""
    event = ImpactEvent()
    event.header.stamp = stamp(stamp_ns)
    event.header.frame_id = topics.FRAME_BODY
    event.id = impact_id
    event.start, event.end = impact.start, impact.end
    event.frame = FRAME_CODES[impact.frame]
    event.torque = _vector(impact.torque)
    event.delta_omega = _vector(delta_omega)
    return event


def sim_status(state: int, t: float, message: str, stamp_ns: int) -> SimStatus:
    """Return the simulator's state at simulated time t [yr], stamped like its last sample."""
    msg = SimStatus(state=state, t=t, message=message)
    msg.header.stamp = stamp(stamp_ns)
    return msg


def comparison_status(level: bytes, node_name: str, message: str,
                      model_name: str) -> DiagnosticStatus:
    """Return the comparator's status: whether its model applies (``level``), which model."""
    status = DiagnosticStatus(level=level, name=node_name, message=message)
    status.values = [KeyValue(key='model', value=model_name)]
    return status


def comparison_values(numeric, model) -> tuple[list[float], float, float]:
    """Return (numeric - model, its norm, norm / |numeric|) of two 3-vectors [rad/yr]."""
    error = [n - m for n, m in zip(numeric, model)]
    return (error, *error_norms(numeric, error))


def error_norms(numeric, error) -> tuple[float, float]:
    """Return (|error|, |error| / |numeric|) of two 3-vectors [rad/yr] (inf for numeric 0)."""
    norm = math.hypot(*error)
    magnitude = math.hypot(*numeric)
    return norm, norm / magnitude if magnitude > 0 else math.inf


def comparison_messages(header, numeric, model, model_name: str
                        ) -> tuple[Vector3Stamped, Vector3Stamped, ErrorNorm]:
    """Return the comparator's three messages for one sample: model, error, error norm."""
    error, norm, relative = comparison_values(numeric, model)
    return (Vector3Stamped(header=header, vector=_vector(model)),
            Vector3Stamped(header=header, vector=_vector(error)),
            ErrorNorm(header=header, model=model_name, norm=norm, relative=relative))

"""
The run layer's records (:mod:`tumble_ros.runs.records`) as the ROS messages that carry them.

The live simulator and comparator publish these, the offline recording
(:mod:`tumble_ros.runs.offline`) writes them: one conversion each, built by
:mod:`.messages`. And back: a ``scenario`` message as the segment start the comparison anchors on.
"""
from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus

from tumble_ros.core import TimeBase
from tumble_ros.runs.messages.builders import (comparison_status, impact_event,
                                               scenario_description, sim_status)
from tumble_ros.runs.records import ComparisonStatus, ImpactEnded, SegmentStart, StatusChange
from tumble_ros_interfaces.msg import (  # type: ignore[attr-defined]  # rosidl-generated
    ImpactEvent, ScenarioDescription, SimStatus)

__all__ = ['description_message', 'segment_start_of', 'impact_message', 'status_message',
           'comparison_status_message']


def description_message(start: SegmentStart) -> ScenarioDescription:
    """Return the ``scenario`` message describing a segment's start."""
    return scenario_description(start.parameters_yaml, start.seconds_per_year, start.revision,
                                start.stamp_ns, start.t0, start.omega, start.quaternion,
                                start.run_id)


def segment_start_of(msg: ScenarioDescription) -> SegmentStart:
    """Return the segment start a ``scenario`` message describes."""
    q, w = msg.attitude, msg.omega
    s = msg.header.stamp
    return SegmentStart(msg.run_id, msg.parameters_yaml, msg.seconds_per_year, msg.revision,
                        msg.segment_start, TimeBase.stamp_ns(s.sec, s.nanosec),
                        (w.x, w.y, w.z), (q.w, q.x, q.y, q.z))


def impact_message(ended: ImpactEnded) -> ImpactEvent:
    """Return the ``impact_events`` message of an impact that ended."""
    return impact_event(ended.impact, ended.impact_id, ended.stamp_ns, ended.delta_omega)


def status_message(change: StatusChange) -> SimStatus:
    """Return the ``status`` message of the simulator's state."""
    return sim_status(change.state, change.t, change.message, change.stamp_ns)


def comparison_status_message(status: ComparisonStatus, node_name: str,
                              model_name: str) -> DiagnosticStatus:
    """Return the ``comparison/status`` message of the comparator ``node_name``."""
    return comparison_status(status.level, node_name, status.message, model_name)

"""
The run layer's records (:mod:`tumble_ros.runs.records`) as the ROS messages that carry them.

The live simulator and comparator publish these, the offline recording
(:mod:`tumble_ros.runs.offline`) writes them: one conversion each, built by
:mod:`.messages`. And back: a ``scenario`` message as the segment start the comparison anchors on.
:class:`RecordEncoder` gives the same messages as CDR bytes without building them (the offline
recording: each impact writes three).
"""
from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus

from tumble_ros import topics
from tumble_ros.core import TimeBase
from tumble_ros.io import message_definition, MessageEncoder
from tumble_ros.runs.messages.builders import (comparison_status, FRAME_CODES, impact_event,
                                               scenario_description, sim_status)
from tumble_ros.runs.records import ComparisonStatus, ImpactEnded, SegmentStart, StatusChange
from tumble_ros_interfaces.msg import (  # type: ignore[attr-defined]  # rosidl-generated
    ImpactEvent, ScenarioDescription, SimStatus)

__all__ = ['description_message', 'segment_start_of', 'impact_message', 'status_message',
           'comparison_status_message', 'RecordEncoder']


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


class RecordEncoder:
    """
    The records' messages as CDR bytes, without rclpy's message classes.

    Those of :func:`description_message`, :func:`impact_message`, :func:`status_message` and
    :func:`comparison_status_message`, built from the records' numbers and strings
    (:class:`~tumble_ros.io.MessageEncoder`): ~3 us a message instead of ~10-18 us for building
    and serialising one.

    The same fields and length as rclpy's serialisation of those messages, zero padding
    (tests/test_record_messages.py).
    """

    def __init__(self) -> None:
        def encoder(topic: str) -> MessageEncoder:
            return MessageEncoder(topics.TYPES[topic], message_definition(topics.TYPES[topic]))

        self._description = encoder(topics.SCENARIO)
        self._impact = encoder(topics.IMPACT_EVENTS)
        self._status = encoder(topics.STATUS)
        self._comparison = encoder(topics.COMPARISON_STATUS)

    def description(self, start: SegmentStart) -> bytes:
        """Return :func:`description_message` of ``start``, serialised."""
        sec, nanosec = divmod(start.stamp_ns, 1_000_000_000)
        (wx, wy, wz), (qw, qx, qy, qz) = start.omega, start.quaternion
        return self._description.encode(
            sec, nanosec, '', start.revision, start.parameters_yaml, start.seconds_per_year,
            start.t0, float(wx), float(wy), float(wz), float(qx), float(qy), float(qz),
            float(qw), start.run_id)

    def impact(self, ended: ImpactEnded) -> bytes:
        """Return :func:`impact_message` of ``ended``, serialised."""
        sec, nanosec = divmod(ended.stamp_ns, 1_000_000_000)
        impact, (dx, dy, dz) = ended.impact, ended.delta_omega
        tx, ty, tz = impact.torque
        return self._impact.encode(
            sec, nanosec, topics.FRAME_BODY, ended.impact_id, impact.start, impact.end,
            FRAME_CODES[impact.frame], float(tx), float(ty), float(tz), float(dx), float(dy),
            float(dz))

    def status(self, change: StatusChange) -> bytes:
        """Return :func:`status_message` of ``change``, serialised."""
        sec, nanosec = divmod(change.stamp_ns, 1_000_000_000)
        return self._status.encode(sec, nanosec, '', change.state, change.t, change.message)

    def comparison_status(self, status: ComparisonStatus, node_name: str,
                          model_name: str) -> bytes:
        """Return :func:`comparison_status_message` of ``status``, serialised."""
        return self._comparison.encode(status.level, node_name, status.message, '',
                                       (('model', model_name),))

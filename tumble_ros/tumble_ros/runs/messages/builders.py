"""
The messages the simulator and the comparator publish, built in one place.

The live nodes publish them; the offline recorder (:mod:`.offline`) writes the same messages
straight to a file. Units as on the topics: time [yr], angular velocity [rad/yr] (body axes),
attitude quaternion body -> orbital (scalar first), stamps [ns] of ROS time.
"""
from __future__ import annotations

import importlib
import struct
from typing import Any, Sequence
import uuid

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Quaternion, Vector3, Vector3Stamped
import numpy as np
from rclpy.serialization import deserialize_message

from tumble_ros import topics
from tumble_ros.core import Impact, TimeBase
from tumble_ros.io.columns import FlatEncoder, FlatLayout
from tumble_ros.io.msgdefs import message_definition
# (the generated ROS message modules name their classes at run time: mypy sees none of them)
from tumble_ros_interfaces.msg import (  # type: ignore[attr-defined]
    ImpactEvent, ScenarioDescription, SimStatus)
from tumble_ros_interfaces.srv import ApplyImpact  # type: ignore[attr-defined]

__all__ = ['stamp', 'FRAMES', 'FRAME_CODES', 'new_run_id', 'scenario_description', 'impact_event',
           'sim_status', 'comparison_status',
           'SampleEncoder', 'Vector3StampedReader', 'message_class']

#: ApplyImpact / ImpactEvent frame codes <-> Impact frames.
FRAMES = {ApplyImpact.Request.FRAME_BODY: topics.FRAME_BODY,
          ApplyImpact.Request.FRAME_ORBITAL: topics.FRAME_ORBITAL}
FRAME_CODES = {name: code for code, name in FRAMES.items()}


def stamp(ns: int) -> Time:
    """builtin_interfaces/Time of integer nanoseconds."""
    sec, nanosec = divmod(ns, 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _vector(v: Sequence[float]) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def new_run_id() -> str:
    """
    Draw a run id: 12 random hex digits, the ``run_id`` of every scenario description of a run.

    It tells two runs on the same topics apart (the comparator follows its own, ``analyze``
    separates them), also two runs of the same scenario.
    """
    return uuid.uuid4().hex[:12]


def scenario_description(scenario_yaml: str, seconds_per_year: float, revision: int,
                         stamp_ns: int, t0: float, omega: Sequence[float],
                         quaternion: Sequence[float],
                         run_id: str) -> ScenarioDescription:
    """
    Describe the scenario and the state (omega, quaternion) its segment starts from at t0.

    ``run_id``: the run's :func:`new_run_id`.
    """
    msg = ScenarioDescription()
    msg.run_id = run_id
    msg.header.stamp = stamp(stamp_ns)
    msg.parameters_yaml = scenario_yaml
    msg.seconds_per_year = seconds_per_year
    msg.revision = revision
    msg.segment_start = t0
    msg.omega = _vector(omega)
    msg.attitude = Quaternion(w=float(quaternion[0]), x=float(quaternion[1]),
                              y=float(quaternion[2]), z=float(quaternion[3]))
    return msg


def impact_event(impact: Impact, impact_id: int, stamp_ns: int,
                 delta_omega: Sequence[float]) -> ImpactEvent:
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


_STAMP = ('header.stamp.sec', 'header.stamp.nanosec')


def _split(ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the (sec, nanosec) columns of integer nanosecond stamps."""
    ns = np.asarray(ns, dtype=np.int64)
    return ns // 1_000_000_000, ns % 1_000_000_000


def _layout(type_name: str) -> FlatLayout:
    layout = FlatLayout.from_schema(type_name, message_definition(type_name))
    if layout is None:
        raise ValueError(f'{type_name}: not a flat message type (a header, numbers, strings)')
    return layout


def message_class(type_name: str) -> type:
    """Return the rclpy message class of a ROS type name (``geometry_msgs/msg/Vector3Stamped``)."""
    package, kind, name = type_name.split('/')
    cls: type = getattr(importlib.import_module(f'{package}.{kind}'), name)
    return cls


class SampleEncoder:
    """
    The per-sample messages as CDR bytes, built from numbers (no message objects).

    Every per-sample topic is encoded from its description (:class:`tumble_ros.topics.
    SampleTopic`: type, fields, frame) and a sample block (:data:`tumble_ros.topics.
    SampleBlock`): what the simulator publishes for each sample (``/clock``, ω, attitude, Euler
    angles, the perturber's position with a Kepler orbit, and any simulator topic described
    since) and what the comparator publishes for it (model, error, error norm), encoded by
    :class:`tumble_ros.io.columns.FlatEncoder`: the bytes rclpy would serialise from the message
    objects (tests/test_node_messages.py compares them), at ~1 µs a message instead of ~12 µs
    for building and converting one. n samples at a time as numpy rows (the live simulator
    publishes their bytes, the offline recording writes them), or one sample's bytes (the live
    comparator, which receives samples one by one). Stamps ``ns`` are integer nanoseconds of
    ROS time; units as on the topics.
    """

    def __init__(self) -> None:
        self._encoders: dict[tuple[Any, ...], FlatEncoder] = {}
        self._comparison: dict[str, tuple[FlatEncoder, ...]] = {}

    def _encoder(self, topic: topics.SampleTopic,
                 strings: tuple[tuple[str, str], ...] = ()) -> FlatEncoder:
        key = (topic, strings)
        encoder = self._encoders.get(key)
        if encoder is None:
            encoder = self._encoders[key] = FlatEncoder(
                _layout(topic.type_name), {'header.frame_id': topic.frame, **dict(strings)})
        return encoder

    def encode(self, topic: topics.SampleTopic, ns: np.ndarray, columns: Any,
               strings: dict[str, str] | None = None) -> np.ndarray:
        """
        Return n messages of ``topic`` as (n, size) uint8 rows.

        ``ns`` (n,) integer stamps [ns]; ``columns``: one (n,) column per field of
        ``topic.fields``, in order; ``strings``: the values of ``topic.strings``.
        """
        sec, nanosec = _split(ns)
        values = dict(zip(_STAMP, (sec, nanosec)))
        values.update(zip(topic.fields, columns))
        given = tuple(sorted((strings or {}).items()))
        return self._encoder(topic, given).rows(len(sec), values)

    def samples(self, source: str, ns: np.ndarray, block: topics.SampleBlock,
                strings: dict[str, str] | None = None) -> list[tuple[str, np.ndarray]]:
        """
        Return [(topic, rows)] of every per-sample topic of ``source`` the block has, in order.

        ``source``: :data:`tumble_ros.topics.SIM` or :data:`~tumble_ros.topics.COMPARATOR`; a
        topic whose ``columns(block)`` is None is left out (the perturber without an orbit).
        """
        out = []
        for topic in topics.sample_topics(source):
            columns = topic.columns(block)
            if columns is not None:
                out.append((topic.name, self.encode(topic, ns, columns, strings)))
        return out

    def simulator(self, ns: np.ndarray, omega: np.ndarray, quaternion: np.ndarray,
                  euler: np.ndarray, *, clock: bool = True, perturber: np.ndarray | None = None,
                  lightcurve: Any = None) -> list[tuple[str, np.ndarray]]:
        """
        Return the simulator's messages of n samples: [(topic, (n, size) uint8 rows)], in order.

        ``omega`` (n, 3) [rad/yr] body axes, ``quaternion`` (n, 4) body -> orbital (scalar
        first), ``euler`` (n, 3) the continuous (φ, ψ, θ) [rad], ``perturber`` (n, 3) [km] body
        axes or None, ``lightcurve`` a ``core.photometry.LightcurveRecord`` or None; ``clock``:
        whether ``/clock`` goes out (first, as the node publishes it).
        Then every simulator topic of :data:`tumble_ros.topics.SAMPLE_TOPICS` from that block.
        """
        out = [(topics.CLOCK, self._clock(ns))] if clock else []
        block = {'omega': omega, 'quaternion': quaternion, 'euler': euler,
                 'perturber': perturber, 'lightcurve': lightcurve}
        return out + self.samples(topics.SIM, ns, block)

    def _clock(self, ns: np.ndarray) -> np.ndarray:
        encoder = self._encoders.get((topics.CLOCK,))
        if encoder is None:
            encoder = self._encoders[(topics.CLOCK,)] = FlatEncoder(
                _layout(topics.TYPES[topics.CLOCK]), {})
        sec, nanosec = _split(ns)
        return encoder.rows(len(sec), {'clock.sec': sec, 'clock.nanosec': nanosec})

    def comparator(self, ns: np.ndarray, model: np.ndarray, error: np.ndarray,
                   norm: np.ndarray, relative: np.ndarray, model_name: str
                   ) -> list[tuple[str, np.ndarray]]:
        """Return the comparator's messages of n samples (model, error, norms), in order."""
        block = {'model': model, 'error': error, 'norm': norm, 'relative': relative}
        return self.samples(topics.COMPARATOR, ns, block, {'model': model_name})

    def one(self, topic: topics.SampleTopic, ns: int, numbers: Sequence[float],
            strings: dict[str, str] | None = None) -> bytes:
        """Return one message of ``topic`` (``numbers``: its fields' values, in order) as bytes."""
        sec, nanosec = divmod(ns, 1_000_000_000)
        given = tuple(sorted((strings or {}).items()))
        return self._encoder(topic, given).one(sec, nanosec, *numbers)

    def comparison(self, ns: int, model: Sequence[float], error: Sequence[float], norm: float,
                   relative: float,
                   model_name: str) -> tuple[bytes, bytes, bytes]:
        """Return one sample's comparator messages (model, error, norms) as bytes."""
        encoders = self._comparison.get(model_name)
        if encoders is None:   # (looked up once: ~1 us a message, as the comparator needs)
            given = (('model', model_name),)
            encoders = self._comparison[model_name] = tuple(
                self._encoder(topics.sample_topic(name), strings)
                for name, strings in ((topics.MODEL_ANGULAR_VELOCITY, ()), (topics.ERROR, ()),
                                      (topics.ERROR_NORM, given)))
        sec, nanosec = divmod(ns, 1_000_000_000)
        return (encoders[0].one(sec, nanosec, *model), encoders[1].one(sec, nanosec, *error),
                encoders[2].one(sec, nanosec, norm, relative))


class Vector3StampedReader:
    """
    Read a serialised geometry_msgs/Vector3Stamped: (stamp [ns], (x, y, z)).

    Little-endian CDR is read in place (the layout's walk and ``struct``); anything else goes
    through rclpy's deserialisation.
    """

    def __init__(self) -> None:
        self._layout = _layout(topics.TYPES[topics.ANGULAR_VELOCITY])
        self._stamp = struct.Struct('<iI')
        self._vector = struct.Struct('<ddd')

    def __call__(self, data: bytes) -> tuple[int, tuple[float, float, float]]:
        """Return (stamp [ns], vector) of one message; ValueError if it is not one."""
        found = self._layout.offsets(data)
        if found is None:
            try:
                msg = deserialize_message(data, Vector3Stamped)
            except Exception as err:  # (rclpy raises its own error types)
                raise ValueError(f'not a geometry_msgs/Vector3Stamped: {err}') from err
            s = msg.header.stamp
            return (TimeBase.stamp_ns(s.sec, s.nanosec),
                    (msg.vector.x, msg.vector.y, msg.vector.z))
        offsets, _ = found
        sec, nanosec = self._stamp.unpack_from(data, offsets['header.stamp.sec'])
        return (TimeBase.stamp_ns(sec, nanosec),
                self._vector.unpack_from(data, offsets['vector.x']))

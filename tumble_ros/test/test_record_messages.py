"""
The run's records encoded without rclpy (RecordEncoder, io.MessageEncoder) against rclpy's own.

The offline recording writes these bytes for every scenario description, impact event, status
and comparator status, so the check must not come from the encoder: each encoding is
deserialised by rclpy and compared, field by field and by repr (signed zeros), with the message
the live nodes build (runs.messages.records) and its length with rclpy's serialisation of that
message; the padding bytes are zero (rclpy leaves its own as they were).
"""
import itertools
import math
import struct

import pytest
from rclpy.serialization import deserialize_message, serialize_message

from tumble_ros.core import Impact
from tumble_ros.io import MessageEncoder
from tumble_ros.runs.messages.records import (comparison_status_message, description_message,
                                              impact_message, RecordEncoder, status_message)
from tumble_ros.runs.records import (ComparisonStatus, DIVERGED, ERROR, ImpactEnded, OK,
                                     RUNNING, SegmentStart, StatusChange, WARN)

#: Awkward numbers: signed zero, a subnormal, extremes, infinities, a NaN.
AWKWARD = [0.0, -0.0, 5e-324, -1.7976931348623157e308, math.inf, -math.inf, 1.0 / 3.0, math.nan]
#: Strings of every length modulo 8 (the alignment of what follows), empty and not ASCII.
TEXTS = ['', 'a', 'ab', 'abc', 'abcd', 'abcde', 'abcdef', 'abcdefg', 'phi = 1.5 rad, ω → ∞',
         'line one\nline two\n' * 40]
#: Stamps [ns]: 0, the last of the first second, the last a ROS stamp holds.
STAMPS = [0, 999_999_999, 1_234_567_891_011, (2**31 - 1) * 1_000_000_000 + 999_999_999]


def _reprs(msg) -> list[str]:
    """Return repr() of every leaf field of a message, depth first (NaN and -0.0 told apart)."""
    if isinstance(msg, list):
        return [r for item in msg for r in _reprs(item)]
    if not hasattr(msg, 'get_fields_and_field_types'):
        return [repr(msg)]
    return [r for name in msg.get_fields_and_field_types() for r in _reprs(getattr(msg, name))]


def _same(data: bytes, expected) -> None:
    assert len(data) == len(serialize_message(expected))
    assert _reprs(deserialize_message(data, type(expected))) == _reprs(expected)


def test_descriptions_are_the_messages_rclpy_builds():
    encoder = RecordEncoder()
    for k, (text, stamp, number) in enumerate(itertools.product(TEXTS, STAMPS, AWKWARD)):
        start = SegmentStart(TEXTS[(k + 3) % len(TEXTS)], text, number, k, -number, stamp,
                             (number, 1.5, -2.0), (0.5, number, -0.5, 0.25))
        _same(encoder.description(start), description_message(start))


def test_impact_events_are_the_messages_rclpy_builds():
    encoder = RecordEncoder()
    for k, (frame, stamp, number) in enumerate(itertools.product(('body', 'orbital'), STAMPS,
                                                                 AWKWARD)):
        finite = number if math.isfinite(number) else 0.0   # (an Impact is validated)
        impact = Impact(1.25 + k, 3e-7, (finite, -1e3, -finite), frame)
        ended = ImpactEnded(impact, k * 1_000_003 % 2**32, stamp, (-number, number, 7.0))
        _same(encoder.impact(ended), impact_message(ended))


def test_statuses_are_the_messages_rclpy_builds():
    encoder = RecordEncoder()
    for state, text, stamp, number in itertools.product((RUNNING, DIVERGED), TEXTS, STAMPS,
                                                        AWKWARD):
        change = StatusChange(state, number, stamp, text)
        _same(encoder.status(change), status_message(change))


def test_comparator_statuses_are_the_messages_rclpy_builds():
    encoder = RecordEncoder()
    for level, text, node, model in itertools.product((OK, WARN, ERROR), TEXTS, TEXTS[:5],
                                                      ('paper', 'torque_free_exact', '')):
        status = ComparisonStatus(level, text, 0)
        _same(encoder.comparison_status(status, node, model),
              comparison_status_message(status, node, model))


def test_the_padding_is_zero():
    # ImpactEvent after the encapsulation header: stamp 0-8, frame_id 8-17 ('body' + NUL),
    # 3 bytes of padding, id 20-24, start 24-32, end 32-40, frame 40, 7 bytes of padding,
    # torque 48-72, delta_omega 72-96. rclpy leaves its padding bytes as they were.
    ended = ImpactEnded(Impact(1.0, 0.5, (1.0, 2.0, 3.0)), 7, 5, (4.0, 5.0, 6.0))
    data = RecordEncoder().impact(ended)
    body = data[4:]
    assert len(data) == len(serialize_message(impact_message(ended))) == 4 + 96
    assert body[8:17] == (5).to_bytes(4, 'little') + b'body\x00'
    assert body[17:20] == bytes(3)
    assert body[20:24] == (7).to_bytes(4, 'little')
    assert struct.unpack_from('<dd', body, 24) == (1.0, 1.5)
    assert body[40:48] == bytes(8)   # FRAME_BODY, then padding
    assert struct.unpack_from('<6d', body, 48) == (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)


def test_sequences_of_messages_and_their_lengths():
    schema = ('diagnostic_msgs/KeyValue[<=2] values\nuint8 flag\n'
              '================================================================================\n'
              'MSG: diagnostic_msgs/KeyValue\nstring key\nstring value\n')
    encoder = MessageEncoder('test_msgs/msg/Pairs', schema)
    assert encoder.fields == ('values', 'flag')
    data = encoder.encode((('k', 'v'), ('key', '')), 3)
    assert data == (b'\x00\x01\x00\x00' + (2).to_bytes(4, 'little')
                    + b'\x02\x00\x00\x00k\x00\x00\x00' + b'\x02\x00\x00\x00v\x00\x00\x00'
                    + b'\x04\x00\x00\x00key\x00' + b'\x01\x00\x00\x00\x00' + b'\x03')
    with pytest.raises(ValueError, match='values: at most 2 elements, got 3'):
        encoder.encode((('a', 'b'),) * 3, 0)


def test_arrays_of_numbers_are_refused_by_name():
    with pytest.raises(ValueError, match='test_msgs/msg/Samples: data: arrays of float64'):
        MessageEncoder('test_msgs/msg/Samples', 'uint8 n\nfloat64[] data\n')

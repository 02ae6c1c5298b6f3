"""
Columnar reading (io.columns) against the generic decoder (io.read_messages), its reference.

Identical values, bit for bit, in the same order: on the committed golden file, on a live
recording with impacts (the bringup of config/fig10.yaml), and on files built to make the
columnar path fall back (strings that change length, a message outside chunks, a big-endian
message).
"""
from pathlib import Path
import struct

import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.io import FlatLayout, McapWriter, read_columns, read_messages, summarize
from tumble_ros.io.msgdefs import message_definition

DATA = Path(__file__).resolve().parent / 'data'
CONFIG = Path(__file__).resolve().parents[1] / 'config'


def _attribute(message, dotted):
    for part in dotted.split('.'):
        message = getattr(message, part)
    return message


def assert_same_as_generic(path):
    """Return the columns after checking them against read_messages, field by field."""
    names = sorted(summarize(path).topics)
    columns, others = read_columns(path, names)
    reference: dict[str, list] = {}
    other_reference = []
    for m in read_messages(path, names):
        (reference.setdefault(m.topic, []) if m.topic in columns else other_reference).append(m)
    assert set(columns) | {m.topic for m in others} == set(reference) | {
        m.topic for m in other_reference}
    for topic, table in columns.items():
        messages = reference[topic]
        assert len(table) == len(messages)
        assert table.log_time_ns.tolist() == [m.log_time_ns for m in messages]
        for name, kind in table.layout.fields:
            values = [_attribute(m.message, name) for m in messages]
            if kind == 'string':
                assert table.strings[name] == list(dict.fromkeys(map(str, values)))
            else:
                column = table.columns[name]
                assert column.tobytes() == np.array(values, dtype=column.dtype).tobytes(), name
    assert [(m.topic, m.log_time_ns, m.publish_time_ns) for m in others] == [
        (m.topic, m.log_time_ns, m.publish_time_ns) for m in other_reference]
    return columns


def test_the_golden_file_reads_the_same_both_ways():
    columns = assert_same_as_generic(DATA / 'golden.mcap')
    velocity = columns['/' + topics.ANGULAR_VELOCITY]
    assert len(velocity) == 200 and velocity.columnar == 200 and velocity.generic == 0


def test_a_live_recording_with_impacts_reads_the_same_both_ways(tmp_path):
    from tumble_ros.nodes.bringup import run_bringup

    output = tmp_path / 'fig10.mcap'
    result = run_bringup(str(CONFIG / 'fig10.yaml'), str(output), progress=None)
    assert result.ok, result
    columns = assert_same_as_generic(output)
    assert len(columns['/' + topics.ANGULAR_VELOCITY]) > 100
    assert summarize(output).topics['/' + topics.IMPACT_EVENTS].message_count >= 1
    assert columns['/' + topics.ERROR_NORM].strings['model'] == ['paper']


def _vector3_stamped(sec, nanosec, frame, x, y, z, little=True):
    """CDR bytes of a geometry_msgs/Vector3Stamped, written out here."""
    e = '<' if little else '>'
    name = frame.encode() + b'\0'
    body = struct.pack(e + 'iI', sec, nanosec) + struct.pack(e + 'I', len(name)) + name
    body += b'\0' * (-len(body) % 8)
    body += struct.pack(e + 'ddd', x, y, z)
    return (b'\x00\x01' if little else b'\x00\x00') + b'\x00\x00' + body


def test_changing_strings_and_big_endian_fall_back_in_file_order(tmp_path):
    path = tmp_path / 'mixed.mcap'
    rng = np.random.default_rng(3)
    frames = ['body', 'b', 'a_longer_frame_id', 'body', '']
    with McapWriter(path, chunk_bytes=700) as writer:
        channel = writer.add_channel('/v', 'geometry_msgs/msg/Vector3Stamped')
        for k in range(60):
            x, y, z = rng.normal(size=3)
            data = _vector3_stamped(k, 7 * k, frames[k % 5], x, y, z, little=(k % 17 != 5))
            writer.write(channel, data, 1000 + k, 1000 + k)
    columns = assert_same_as_generic(path)
    table = columns['/v']
    assert table.generic >= 3 and table.columnar > 40   # the big-endian ones went the slow way
    assert table.strings['header.frame_id'] == ['body', 'b', 'a_longer_frame_id', '']


def test_the_layout_comes_from_the_schema():
    layout = FlatLayout.from_schema('geometry_msgs/msg/Vector3Stamped',
                                    message_definition('geometry_msgs/msg/Vector3Stamped'))
    assert layout.fields == (('header.stamp.sec', 'int32'), ('header.stamp.nanosec', 'uint32'),
                             ('header.frame_id', 'string'), ('vector.x', 'float64'),
                             ('vector.y', 'float64'), ('vector.z', 'float64'))
    # a type with a sequence is not flat: the generic decoder reads it
    assert FlatLayout.from_schema('diagnostic_msgs/msg/DiagnosticStatus', message_definition(
        'diagnostic_msgs/msg/DiagnosticStatus')) is None


@pytest.mark.parametrize('cut', [0.5, 0.9])
def test_a_truncated_file_gives_the_same_complete_chunks(tmp_path, cut):
    whole = (DATA / 'golden.mcap').read_bytes()
    path = tmp_path / 'cut.mcap'
    path.write_bytes(whole[:int(len(whole) * cut)])
    assert_same_as_generic(path)

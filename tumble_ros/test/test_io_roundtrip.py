"""
McapWriter -> our reader, the rosbags library and mcap's own reader.

Every message decodes, per-topic counts and values equal what was written (messages serialised
by rclpy).
"""
from collections import Counter
import dataclasses
import math
from pathlib import Path

from geometry_msgs.msg import QuaternionStamped, Vector3Stamped
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import pytest
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from service_msgs.msg import ServiceEventInfo
from tumble_ros import topics
from tumble_ros.io import McapWriter, offered_qos_yaml, read_messages, summarize
from tumble_ros_interfaces.msg import ImpactEvent, ScenarioDescription, SimStatus
from tumble_ros_interfaces.srv import ApplyImpact

TYPES = {
    '/' + topics.ANGULAR_VELOCITY: 'geometry_msgs/msg/Vector3Stamped',
    '/' + topics.ATTITUDE: 'geometry_msgs/msg/QuaternionStamped',
    topics.CLOCK: 'rosgraph_msgs/msg/Clock',
    '/' + topics.IMPACT_EVENTS: 'tumble_ros_interfaces/msg/ImpactEvent',
    '/' + topics.SCENARIO: 'tumble_ros_interfaces/msg/ScenarioDescription',
    '/' + topics.STATUS: 'tumble_ros_interfaces/msg/SimStatus',
}
#: The latched topics (offered transient local).
LATCHED = ('/' + topics.SCENARIO, '/' + topics.STATUS)
LATCHED_QOS = offered_qos_yaml({'depth': 1, 'durability': 'transient_local'})


def plain(value):
    """Return a comparable structure of a message from rclpy, mcap_ros2 or rosbags."""
    if hasattr(value, 'get_fields_and_field_types'):                      # rclpy
        return {name: plain(getattr(value, name)) for name in value.get_fields_and_field_types()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):   # rosbags
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not f.name.startswith('__') and not f.name.isupper()}  # no constants
    if hasattr(value, '__slots__') and hasattr(value, '_type'):           # mcap_ros2
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if isinstance(value, (list, tuple)) or hasattr(value, 'tolist'):
        return [plain(v) for v in (value.tolist() if hasattr(value, 'tolist') else value)]
    return value


def stamp_of(ns):
    return ns // 1_000_000_000, ns % 1_000_000_000


def sample_messages():
    """(topic, log_time_ns, publish_time_ns, rclpy message) in log-time order."""
    out = []
    scenario = ScenarioDescription()
    scenario.revision = 3
    scenario.parameters_yaml = 'sim:\n  ros__parameters:\n    duration: 10000.0\n'
    scenario.seconds_per_year = 1.0
    scenario.segment_start = 9999.5
    scenario.omega.z = 30.0
    scenario.attitude.w = 1.0
    out.append(('/' + topics.SCENARIO, 10, 5, scenario))
    base = 9_999_000_000_000   # t = 9999 yr: sec = 9999, well inside int32
    for k in range(40):
        ns = base + k * 2_000_000 + 123
        sec, nanosec = stamp_of(ns)
        w = Vector3Stamped()
        w.header.stamp.sec, w.header.stamp.nanosec = sec, nanosec
        w.header.frame_id = topics.FRAME_BODY
        t = k * 0.002
        w.vector.x, w.vector.y, w.vector.z = math.cos(94.2 * t), -math.sin(94.2 * t), 30.0 + k
        out.append(('/' + topics.ANGULAR_VELOCITY, ns + 1000, ns, w))
        if k % 4 == 0:
            q = QuaternionStamped()
            q.header.stamp.sec, q.header.stamp.nanosec = sec, nanosec
            q.header.frame_id = topics.FRAME_ORBITAL
            q.quaternion.z, q.quaternion.w = math.sin(0.1 * k), math.cos(0.1 * k)
            out.append(('/' + topics.ATTITUDE, ns + 1001, ns, q))
            c = Clock()
            c.clock.sec, c.clock.nanosec = sec, nanosec
            out.append((topics.CLOCK, ns + 1002, ns, c))
        if k == 17:
            e = ImpactEvent()
            e.header.stamp.sec, e.header.stamp.nanosec = sec, nanosec
            e.header.frame_id = topics.FRAME_BODY
            e.id, e.start, e.end, e.frame = 7, 9999.03, 9999.0300003, ImpactEvent.FRAME_ORBITAL
            e.torque.y, e.delta_omega.y = -2.5e5, -0.075
            out.append(('/' + topics.IMPACT_EVENTS, ns + 1003, ns, e))
    status = SimStatus()
    status.state, status.t = SimStatus.DIVERGED, 9999.08
    status.message = 'non-finite state: ω=nan'
    out.append(('/' + topics.STATUS, base + 90_000_000, base + 90_000_000, status))
    return out


def write_file(path, compression, chunk_bytes, messages):
    with McapWriter(path, compression=compression, chunk_bytes=chunk_bytes,
                    chunk_seconds=math.inf) as writer:
        channels = {topic: writer.add_channel(topic, type_name,
                                              LATCHED_QOS if topic in LATCHED
                                              else '')
                    for topic, type_name in TYPES.items()}
        for topic, log_time, publish_time, message in messages:
            writer.write(channels[topic], serialize_message(message), log_time, publish_time)
        counts = writer.counts
    return counts


@pytest.mark.parametrize('chunk_bytes', [150, 1_000_000])
@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_round_trip(tmp_path, compression, chunk_bytes):
    path = tmp_path / 'run.mcap'
    messages = sample_messages()
    written = Counter(topic for topic, *_ in messages)
    assert write_file(path, compression, chunk_bytes, messages) == dict(written)
    expected = [(topic, log, pub, plain(m)) for topic, log, pub, m in messages]

    # Our reader: same order, times, types and values.
    ours = list(read_messages(path))
    got = [(m.topic, m.log_time_ns, m.publish_time_ns, plain(m.message)) for m in ours]
    assert got == expected
    assert all(m.type_name == TYPES[m.topic] for m in ours)
    first = ours[1]
    assert first.message.header.stamp.sec == 9999 and first.message.vector.z == 30.0
    selected = [topics.CLOCK, '/' + topics.STATUS]
    assert [m.topic for m in read_messages(path, topics=selected)] == [
        t for t, *_ in messages if t in selected]

    summary = summarize(path)
    assert summary.finalised and not summary.truncated and summary.profile == 'ros2'
    assert {t: s.message_count for t, s in summary.topics.items()} == dict(written)
    assert {t: s.type_name for t, s in summary.topics.items()} == TYPES
    assert summary.message_count == len(messages)
    assert summary.start_time_ns == min(m[1] for m in messages)
    assert summary.end_time_ns == max(m[1] for m in messages)
    assert summary.compressions == (compression,)
    if chunk_bytes == 1_000_000:
        assert summary.chunk_count == 1
    else:
        assert summary.chunk_count > 5

    # rosbags (third party), on the bare .mcap file: no metadata.yaml needed.
    from rosbags.highlevel import AnyReader
    with AnyReader([path]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TYPES
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        assert (qos['/' + topics.SCENARIO][0].durability.name == 'TRANSIENT_LOCAL'
                and qos[topics.CLOCK] == [])
        theirs = [(c.topic, t, plain(reader.deserialize(raw, c.msgtype)))
                  for c, t, raw in reader.messages()]
    assert sorted(theirs, key=lambda x: x[1]) == [(t, log, v) for t, log, _, v in expected]

    # mcap's own reader with its ROS 2 decoder.
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        mcap_out = [(channel.topic, message.log_time, message.publish_time, plain(decoded))
                    for _, channel, message, decoded in reader.iter_decoded_messages(
                        log_time_order=False)]
        schemas = reader.get_summary().schemas
        channels = reader.get_summary().channels
    assert mcap_out == expected
    assert {s.name for s in schemas.values()} == set(TYPES.values())
    assert {s.encoding for s in schemas.values()} == {'ros2msg'}
    assert {c.message_encoding for c in channels.values()} == {'cdr'}
    assert all(c.metadata['topic_type_hash'].startswith('RIHS01_') for c in channels.values())
    assert {c.topic: c.metadata['offered_qos_profiles'] for c in channels.values()}[
        '/' + topics.STATUS] == LATCHED_QOS


def test_raw_bytes_are_stored_as_given(tmp_path):
    # Even bytes that are not a valid message are stored unchanged (never re-serialised).
    path = tmp_path / 'raw.mcap'
    payloads = [bytes(range(k, k + 30)) for k in range(5)]
    with McapWriter(path, compression='lz4', chunk_bytes=64) as writer:
        channel = writer.add_channel('/x', 'geometry_msgs/msg/Vector3Stamped')
        for k, data in enumerate(payloads):
            writer.write(channel, data, 100 + k)
    with open(path, 'rb') as stream:
        assert [m.data for _, _, m in make_reader(stream).iter_messages()] == payloads


def test_service_event_round_trip(tmp_path):
    # Service introspection events are written with rosbag2's (Jazzy) schema for them; our
    # reader decodes them.
    path = tmp_path / 'service.mcap'
    event = ApplyImpact.Event()
    event.info.event_type = ServiceEventInfo.RESPONSE_SENT
    event.info.stamp.sec, event.info.sequence_number = 12, 3
    event.info.client_gid = list(range(16))
    request = ApplyImpact.Request()
    request.torque.y, request.duration, request.start_now = 1e6, 3e-7, True
    response = ApplyImpact.Response()
    response.accepted, response.message, response.id = True, 'scheduled', 4
    event.request, event.response = [request], [response]
    with McapWriter(path) as writer:
        channel = writer.add_channel(f'/{topics.APPLY_IMPACT}/_service_event',
                                     'tumble_ros_interfaces/srv/ApplyImpact_Event')
        writer.write(channel, serialize_message(event), 5)
    (message,) = list(read_messages(path))
    assert message.type_name == 'tumble_ros_interfaces/srv/ApplyImpact_Event'
    assert plain(message.message) == plain(event)
    assert message.message.request[0].torque.y == 1e6
    assert message.message.response[0].message == 'scheduled'
    # Raw access by a third party still works (rosbags' low-level reader does not parse schemas).
    from rosbags.rosbag2 import Reader
    with Reader(Path(path)) as reader:
        assert [c.msgtype for c in reader.connections] == [
            'tumble_ros_interfaces/srv/ApplyImpact_Event']
        assert len(list(reader.messages())) == 1

"""
The attitude on TF (issue 50) and the shape sent once (issue 48), in live and offline files.

Every file is decoded with mcap's own ROS 2 decoder (not this project's reader), the transforms
composed by hand (tf2 is not on PyPI: tf2_ros, tf2_py have no wheel): the rotation of
``orbital`` -> ``body`` must be the recorded ``attitude`` bit for bit, at every sample; the
channels' QoS metadata must say what a replay needs (``/tf_static`` and ``body_markers``
transient local); two asteroids' transforms on the one ``/tf`` must keep apart by their frames;
a ``markers`` message must not grow with the body's facets.
"""
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import pytest
from rclpy.parameter import Parameter
from tumble_ros import topics
from tumble_ros.core import Impact, Scenario, TimeBase
from tumble_ros.core.model.body import BodySpec
from tumble_ros.io.msgdefs import type_hash
from tumble_ros.runs.offline import record_offline
import yaml

TF, TF_STATIC = topics.TF, topics.TF_STATIC
ATTITUDE, MARKERS, BODY_MARKERS = (
    '/' + t for t in (topics.ATTITUDE, topics.MARKERS, topics.BODY_MARKERS))
#: tf2_msgs/msg/TFMessage's RIHS01 hash in ROS 2 Jazzy (ros2/geometry2's generated
#: TFMessage.json, as `ros2 topic info -v /tf` prints it): typed out, not computed here.
UPSTREAM_HASH = 'RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087'
SHORT = {'duration': 0.2, 'output_interval': 0.002, 'real_time_factor': 0.0}


def _decoded(path, wanted):
    """Return {topic: [(log time ns, message)]} of ``wanted``, decoded by mcap_ros2."""
    out = {t: [] for t in wanted}
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, msg in reader.iter_decoded_messages(topics=list(wanted)):
            out[channel.topic].append((message.log_time, msg))
    return out


def _channels(path):
    """Return {topic: (schema name, channel metadata)} of a file."""
    with open(path, 'rb') as stream:
        summary = make_reader(stream).get_summary()
    return {c.topic: (summary.schemas[c.schema_id].name, dict(c.metadata))
            for c in summary.channels.values()}


def _stamp(header):
    return TimeBase.stamp_ns(header.stamp.sec, header.stamp.nanosec)


def _bits(values):
    return np.asarray(values, dtype=np.float64).view(np.uint64).tolist()


def _attitudes(decoded, topic=ATTITUDE):
    """Return {stamp ns: (w, x, y, z)} of the recorded attitude."""
    return {_stamp(m.header): (m.quaternion.w, m.quaternion.x, m.quaternion.y, m.quaternion.z)
            for _, m in decoded[topic]}


def _transforms(decoded, parent, child):
    """Return {stamp ns: (w, x, y, z)} of /tf's transforms ``parent`` -> ``child``."""
    out = {}
    for log_time, msg in decoded[TF]:
        for t in msg.transforms:
            if (t.header.frame_id, t.child_frame_id) == (parent, child):
                r, v = t.transform.rotation, t.transform.translation
                assert (v.x, v.y, v.z) == (0.0, 0.0, 0.0)
                assert log_time == _stamp(t.header)          # logged at its sample's time
                out[_stamp(t.header)] = (r.w, r.x, r.y, r.z)
    return out


def _assert_tf_is_the_attitude(path, namespace='', samples=None):
    attitude_topic = topics.in_namespace(namespace, topics.ATTITUDE)
    decoded = _decoded(path, [TF, attitude_topic])
    q = _attitudes(decoded, attitude_topic)
    tf = _transforms(decoded, topics.frame_id(namespace, 'orbital'),
                     topics.frame_id(namespace, 'body'))
    assert sorted(tf) == sorted(q) and len(q) == (samples or len(q)) > 1
    for stamp, quaternion in q.items():
        assert _bits(tf[stamp]) == _bits(quaternion), stamp           # bit for bit
    return decoded


def _qos(metadata):
    return yaml.safe_load(metadata['offered_qos_profiles'])


def _assert_replay_metadata(path, namespace=''):
    channels = _channels(path)
    for topic in (TF, TF_STATIC):
        schema, metadata = channels[topic]
        assert schema == 'tf2_msgs/msg/TFMessage'
        assert metadata['topic_type_hash'] == UPSTREAM_HASH
        assert {p['reliability'] for p in _qos(metadata)} == {'reliable'}
    # what is sent once reaches a late subscriber, and a player that replays the file
    for topic in (TF_STATIC, topics.in_namespace(namespace, topics.BODY_MARKERS)):
        assert {p['durability'] for p in _qos(channels[topic][1])} == {'transient_local'}


def test_the_vendored_tf2_msgs_is_the_upstream_type():
    from tf2_msgs.msg import TFMessage
    assert type_hash('tf2_msgs/msg/TFMessage') == UPSTREAM_HASH
    assert list(TFMessage.get_fields_and_field_types().items()) == [
        ('transforms', 'sequence<geometry_msgs/TransformStamped>')]


@pytest.fixture(scope='module')
def offline(tmp_path_factory):
    sc = Scenario(duration=0.1, output_interval=0.001,
                  impacts=(Impact(0.05, 3e-7, (0.0, 1e6, 0.0)),))
    return record_offline(sc, tmp_path_factory.mktemp('tf') / 'run.mcap')


def test_the_offline_files_tf_is_the_recorded_attitude_bit_for_bit(offline):
    decoded = _assert_tf_is_the_attitude(offline.output, samples=101)
    _assert_replay_metadata(offline.output)
    static = _decoded(offline.output, [TF_STATIC])[TF_STATIC]
    (log_time, msg), = static                                  # once, at the run's start
    (t,) = msg.transforms
    assert log_time == 0 and (t.header.frame_id, t.child_frame_id) == ('body', 'body_as_given')
    r = t.transform.rotation
    assert (r.w, r.x, r.y, r.z) == (1.0, 0.0, 0.0, 0.0)        # an ellipsoid: given as it is
    assert len(decoded[TF]) == 101


def _icosphere(levels):
    """Return (vertices, facets) of a unit icosphere: 20 * 4**levels facets, outward."""
    t = (1 + 5 ** 0.5) / 2
    v = [np.array(p, float) / np.linalg.norm(p) for p in (
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
        (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1))]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        middle, finer = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                middle[key] = len(v) - 1
            return middle[key]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = finer
    return np.array(v), np.array(f)


def _shape_file(path, levels, rotation=np.eye(3), shift=(0.0, 0.0, 0.0)):
    """Write an ellipsoid mesh (semi-axes 1, 0.8, 0.6 km), turned and shifted, as an OBJ."""
    v, f = _icosphere(levels)
    v = (v * [1.0, 0.8, 0.6]) @ np.asarray(rotation).T + shift
    path.write_text(''.join(f'v {float(a)!r} {float(b)!r} {float(c)!r}\n' for a, b, c in v)
                    + ''.join(f'f {a + 1} {b + 1} {c + 1}\n' for a, b, c in f))
    return v, f


def _rotate(q, v):
    """Rotate v by the unit quaternion q = (w, x, y, z): q v q* (the textbook formula)."""
    u, s = np.array(q[1:]), q[0]
    return 2 * np.dot(u, v) * u + (s * s - np.dot(u, u)) * v + 2 * s * np.cross(u, v)


def test_the_static_frame_is_where_the_shape_file_put_the_body(tmp_path):
    """The transform body -> body_as_given takes the file's vertices onto the drawn body."""
    angle = 0.7
    turn = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0],
                     [0.0, 0.0, 1.0]])
    given, facets = _shape_file(tmp_path / 'turned.obj', 2, turn, (3.0, -2.0, 1.0))
    body = BodySpec(model='polyhedron', density=2600.0, shape_file=str(tmp_path / 'turned.obj'))
    result = record_offline(Scenario(body=body, duration=0.01, output_interval=0.01),
                            tmp_path / 'turned.mcap')
    decoded = _decoded(result.output, [TF_STATIC, BODY_MARKERS])
    ((_, static),), ((_, scene),) = decoded[TF_STATIC], decoded[BODY_MARKERS]
    (t,) = static.transforms
    assert (t.header.frame_id, t.child_frame_id) == ('body', 'body_as_given')
    r, d = t.transform.rotation, t.transform.translation
    q, shift = (r.w, r.x, r.y, r.z), np.array([d.x, d.y, d.z])
    drawn = np.array([[p.x, p.y, p.z] for p in scene.markers[0].points])   # the body's facets
    in_body = np.array([_rotate(q, p) for p in given[facets].reshape(-1, 3)])
    # drawn = s * (the given vertices turned by the transform) + its translation, s the
    # display scale: 1 / the farthest vertex, which is within 1 % of the 1-km semi-axis
    s = np.sum((drawn - shift) * in_body) / np.sum(in_body * in_body)
    assert 1.0 - 1e-12 <= s < 1.01
    np.testing.assert_allclose(s * in_body + shift, drawn, atol=1e-9)
    assert np.linalg.norm(shift) > 0.5            # the file's centre was 3.7 km off


def test_markers_do_not_grow_with_the_facets_and_the_shape_is_sent_once(tmp_path):
    sizes, shapes = {}, {}
    for levels in (2, 5):                          # 320 and 20,480 facets
        _, facets = _shape_file(tmp_path / f'ico{levels}.obj', levels)
        body = BodySpec(model='polyhedron', density=2600.0,
                        shape_file=str(tmp_path / f'ico{levels}.obj'))
        result = record_offline(Scenario(body=body, duration=0.02, output_interval=0.001),
                                tmp_path / f'ico{levels}.mcap')
        with open(result.output, 'rb') as stream:
            reader = make_reader(stream)
            sizes[levels] = {len(m.data) for _, c, m in reader.iter_messages(topics=[MARKERS])}
        decoded = _decoded(result.output, [BODY_MARKERS, MARKERS])
        (log_time, scene), = decoded[BODY_MARKERS]             # once, at the run's start
        assert log_time == 0 and len(decoded[MARKERS]) == result.samples == 21
        assert all(m.frame_locked and m.header.frame_id == 'body' for m in scene.markers)
        shapes[levels] = len(scene.markers[0].points)
        assert shapes[levels] == 3 * len(facets)
        assert not any(m.ns == 'body' for _, msg in decoded[MARKERS] for m in msg.markers)
    assert shapes == {2: 3 * 320, 5: 3 * 20480}
    (small,), (large,) = sizes[2], sizes[5]          # one size a run, the same for both
    assert small == large < 1000


def test_a_player_seeking_anywhere_finds_the_shape_and_the_attitude(offline):
    """
    What a seek shows: each topic's last message at or before the time (Foxglove's backfill).

    The shape, on its own topic, is that message wherever the seek goes; per-sample topics give
    the attitude of the time.
    """
    decoded = _decoded(offline.output, [TF, BODY_MARKERS, ATTITUDE])
    for seek in (0, 50_000_000, 73_500_000, 100_000_000):
        last = {topic: [m for t, m in messages if t <= seek][-1]
                for topic, messages in decoded.items()}
        assert [m.ns for m in last[BODY_MARKERS].markers] == ['body', 'axes', 'axes', 'axes']
        (t,) = last[TF].transforms
        assert _stamp(t.header) == _stamp(last[ATTITUDE].header) == seek - seek % 1_000_000


# -- live -----------------------------------------------------------------------------------------
def test_the_live_recorders_tf_is_the_recorded_attitude_bit_for_bit(ros, tmp_path):
    from tumble_ros.nodes.recorder import RecorderNode
    from tumble_ros.nodes.sim import SimNode
    from tumble_ros_interfaces.msg import SimStatus

    sim = ros.start(SimNode, min_consumers=1, markers=True, **SHORT)
    recorder = ros.start(RecorderNode, output=str(tmp_path / 'live.mcap'))
    assert ros.spin_until(lambda: sim.state == SimStatus.FINISHED, 60.0)
    assert ros.spin_until(lambda: recorder.counts.get(TF, 0) == 101, 20.0), recorder.counts
    recorder.close()
    _assert_tf_is_the_attitude(recorder.path, samples=101)
    _assert_replay_metadata(recorder.path)
    decoded = _decoded(recorder.path, [TF_STATIC, BODY_MARKERS])
    assert len(decoded[TF_STATIC]) == len(decoded[BODY_MARKERS]) == 1


def test_two_asteroids_share_tf_with_their_own_frames(ros, tmp_path):
    """/ast1 and /ast2 on one /tf: each file's transforms of each are that asteroid's attitude."""
    from tumble_ros.nodes.recorder import RecorderNode
    from tumble_ros.nodes.sim import SimNode
    from tumble_ros_interfaces.msg import SimStatus

    nodes = {}
    for ns, duration in (('ast1', 0.2), ('ast2', 0.1)):
        sim = ros.add(SimNode(context=ros.context, namespace=ns, parameter_overrides=[
            Parameter('duration', value=duration), Parameter('real_time_factor', value=0.0),
            Parameter('min_consumers', value=1), Parameter('publish_clock', value=False),
            Parameter('markers', value=True)]))
        recorder = ros.add(RecorderNode(context=ros.context, namespace=ns, parameter_overrides=[
            Parameter('output', value=str(tmp_path / f'{ns}.mcap'))]))
        nodes[ns] = (sim, recorder)
    expected = {'ast1': 101, 'ast2': 51}
    assert ros.spin_until(lambda: all(s.state == SimStatus.FINISHED for s, _ in nodes.values()),
                          60.0)
    attitude = {ns: topics.in_namespace(ns, topics.ATTITUDE) for ns in nodes}
    assert ros.spin_until(lambda: all(r.counts.get(attitude[ns], 0) == expected[ns]
                                      for ns, (_, r) in nodes.items()), 20.0)
    # each recorder takes both asteroids' transforms from the one /tf
    assert ros.spin_until(lambda: all(r.counts.get(TF, 0) == sum(expected.values())
                                      for _, r in nodes.values()), 20.0)
    for ns, (sim, recorder) in nodes.items():
        assert 'second source' not in sim.status_message       # /tf is shared by design
        assert not recorder.warnings
        recorder.close()
        _assert_tf_is_the_attitude(recorder.path, ns, samples=expected[ns])
        _assert_replay_metadata(recorder.path, ns)
        frames = {(t.header.frame_id, t.child_frame_id)
                  for _, m in _decoded(recorder.path, [TF])[TF] for t in m.transforms}
        # the other asteroid's transforms, on the same /tf, under its own frames
        assert frames <= {('ast1/orbital', 'ast1/body'), ('ast2/orbital', 'ast2/body')}
        assert (f'{ns}/orbital', f'{ns}/body') in frames
        statics = {(t.header.frame_id, t.child_frame_id)
                   for _, m in _decoded(recorder.path, [TF_STATIC])[TF_STATIC]
                   for t in m.transforms}
        assert (f'{ns}/body', f'{ns}/body_as_given') in statics
    # each file's transforms of the other asteroid are that one's attitude too
    for ns, other in (('ast1', 'ast2'), ('ast2', 'ast1')):
        decoded = _decoded(nodes[ns][1].path, [TF])
        theirs = _transforms(decoded, f'{other}/orbital', f'{other}/body')
        mine = _attitudes(_decoded(nodes[other][1].path, [attitude[other]]), attitude[other])
        assert theirs and all(_bits(q) == _bits(mine[s]) for s, q in theirs.items())


def test_the_layouts_show_the_body_frame_through_tf():
    config = Path(__file__).resolve().parents[1] / 'config'
    for name in ('foxglove_layout.json', 'foxglove_layout_flyby.json'):
        import json
        panel = json.loads((config / name).read_text())['configById']['3D!tumble']
        assert panel['followTf'] == topics.FRAME_ORBITAL
        assert panel['topics'][BODY_MARKERS]['visible'] is True
        assert panel['scene']['transforms']['enablePreloading'] is True

"""
The 3D scene (runs.messages.markers): decoded by the standard readers, equal to the samples.

The shape and the axes are sent once in the frame body (body_markers) and posed by /tf; the
scenes of the samples (markers) hold what moves in the orbital frame (L, the Sun).

The expected values are computed here from the recorded attitude and angular velocity and from
textbook formulas (an ellipsoid's moments from its semi-axes), never taken from the code under
test.
"""
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.core import Impact, load_scenario, Scenario, TimeBase
from tumble_ros.core.model.shape import body_shape, BOX, ELLIPSOID, MIN_THICKNESS
from tumble_ros.io import message_definition, MessageTemplate, read_messages
from tumble_ros.runs.messages.markers import marker_every, MARKER_FRAMES
from tumble_ros.runs.offline import record_offline

CONFIG = Path(__file__).resolve().parents[1] / 'config'
MARKERS = '/' + topics.MARKERS
BODY_MARKERS = '/' + topics.BODY_MARKERS
SPHERE, CUBE, ARROW = 2, 1, 0          # visualization_msgs/Marker types, typed out


def _ellipsoid_moments(a, b, c):
    """Principal moments of a uniform solid ellipsoid of unit mass (textbook)."""
    return np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 5.0


@pytest.mark.parametrize('inertia', [(1.0, 1.0, 1.5), (1.0, 1.6, 2.2), (2.0, 3.0, 4.5),
                                     (1.0, 1.0, 2.0)])
def test_the_ellipsoid_has_the_scenarios_principal_moments(inertia):
    shape = body_shape(inertia)
    assert shape.kind == ELLIPSOID and shape.physical
    assert max(shape.semi_axes) == 1.0
    moments = _ellipsoid_moments(*shape.semi_axes)
    if min(shape.semi_axes) > MIN_THICKNESS:          # not clamped for display
        np.testing.assert_allclose(moments / moments[0], np.array(inertia) / inertia[0],
                                   rtol=1e-12)


@pytest.mark.parametrize('inertia', [(1.0, 1.0, 4.0), (1.0, 1.0, 2.5), (3.0, 1.0, 1.0)])
def test_moments_that_no_body_has_are_drawn_as_a_box(inertia):
    shape = body_shape(inertia)
    assert shape.kind == BOX and not shape.physical
    assert min(shape.semi_axes) == MIN_THICKNESS and max(shape.semi_axes) == 1.0
    assert 'triangle inequality' in shape.note


def _scenes(path, topic=MARKERS):
    """Decode /markers with mcap's own ROS 2 decoder: [MarkerArray]."""
    out = []
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages(topics=[topic]):
            out.append(msg)
    return out


def _body(path):
    """Decode the one /body_markers message: the shape and its axes, in the frame body."""
    (body,) = _scenes(path, BODY_MARKERS)
    assert all(m.frame_locked and m.header.frame_id == topics.FRAME_BODY for m in body.markers)
    return body


def _tf(path):
    """Return {stamp ns: (w, x, y, z)} of /tf's orbital -> body (test_tf.py: the attitude)."""
    out = {}
    for msg in _scenes(path, topics.TF):
        (t,) = msg.transforms
        assert (t.header.frame_id, t.child_frame_id) == ('orbital', 'body')
        r = t.transform.rotation
        out[TimeBase.stamp_ns(t.header.stamp.sec, t.header.stamp.nanosec)] = np.array(
            [r.w, r.x, r.y, r.z])
    return out


def _samples(path):
    q = {}
    w = {}
    for m in read_messages(path, topics=['/' + topics.ATTITUDE, '/' + topics.ANGULAR_VELOCITY]):
        stamp = TimeBase.stamp_ns(m.message.header.stamp.sec, m.message.header.stamp.nanosec)
        if m.topic.endswith(topics.ATTITUDE):
            o = m.message.quaternion
            q[stamp] = np.array([o.w, o.x, o.y, o.z])
        else:
            v = m.message.vector
            w[stamp] = np.array([v.x, v.y, v.z])
    return q, w


def _rotate(q, v):
    """Rotate v by the unit quaternion q = (w, x, y, z): q v q* (the textbook formula)."""
    u, s = np.array(q[1:]), q[0]
    return 2 * np.dot(u, v) * u + (s * s - np.dot(u, u)) * v + 2 * s * np.cross(u, v)


def _direction(points):
    (p0, p1) = points
    tip = np.array([p1.x - p0.x, p1.y - p0.y, p1.z - p0.z])
    return tip / np.linalg.norm(tip)


@pytest.fixture(scope='module')
def recorded(tmp_path_factory):
    sc = load_scenario(CONFIG / 'fig10.yaml').replace(duration=0.1, output_interval=0.001,
                                                      impacts=(Impact(0.05, 3e-7,
                                                                      (0.0, 1e6, 0.0)),))
    path = tmp_path_factory.mktemp('markers') / 'run.mcap'
    result = record_offline(sc, path)
    return sc, result


def test_every_sample_has_a_scene_whose_poses_are_its_attitude(recorded):
    """The shape, sent once in body, posed by each sample's /tf; L and the Sun per sample."""
    sc, result = recorded
    scenes = _scenes(result.output)
    q, w = _samples(result.output)
    tf = _tf(result.output)
    assert len(scenes) == result.samples == len(q) == len(tf) == 101
    body = _body(result.output)
    shape = {(m.ns, m.id): m for m in body.markers}
    o = shape['body', 0].pose.orientation
    assert [o.w, o.x, o.y, o.z] == [1.0, 0.0, 0.0, 0.0]          # the body's own frame
    for scene in scenes:
        stamps = {TimeBase.stamp_ns(m.header.stamp.sec, m.header.stamp.nanosec)
                  for m in scene.markers}
        assert len(stamps) == 1
        stamp = stamps.pop()
        by_ns = {(m.ns, m.id): m for m in scene.markers}
        assert all(m.header.frame_id == topics.FRAME_ORBITAL for m in scene.markers)
        assert tf[stamp].tolist() == q[stamp].tolist()          # the attitude, bit for bit
        # each axis arrow points along the body axis, rotated into the orbital frame by TF
        for i in range(3):
            arrow = shape['axes', i]
            assert arrow.type == ARROW
            p = arrow.pose.orientation
            along = _rotate(tf[stamp], _rotate(np.array([p.w, p.x, p.y, p.z]),
                                               np.array([1.0, 0.0, 0.0])))
            np.testing.assert_allclose(along, _rotate(q[stamp], np.eye(3)[i]), atol=1e-12)
        # L = C(q) I w, in the orbital frame
        momentum = _rotate(q[stamp], np.array(sc.inertia) * w[stamp])
        np.testing.assert_allclose(_direction(by_ns['angular_momentum', 0].points),
                                   momentum / np.linalg.norm(momentum), atol=1e-12)
        # the Sun: R0(t) / R0 = (sin ws t, cos ws t, 0), the paper's orbit
        t = stamp / 1e9
        np.testing.assert_allclose(_direction(by_ns['sun', 0].points),
                                   [np.sin(sc.orbit_rate * t), np.cos(sc.orbit_rate * t), 0.0],
                                   atol=1e-12)
    # fig10's body (1, 1, 1.5): the ellipsoid of these moments, scale = its diameters
    solid = shape['body', 0]
    assert solid.type == SPHERE
    moments = _ellipsoid_moments(solid.scale.x / 2, solid.scale.y / 2, solid.scale.z / 2)
    np.testing.assert_allclose(moments / moments[0], sc.inertia, rtol=1e-12)


def test_an_unphysical_body_is_a_box_and_a_flyby_body_is_drawn(tmp_path):
    sc = load_scenario(CONFIG / 'fig9.yaml').replace(duration=0.05, output_interval=0.01)
    body = _body(record_offline(sc, tmp_path / 'box.mcap').output).markers[0]
    assert body.type == CUBE and body.scale.z == 2 * MIN_THICKNESS   # a plate: Iz > Ix + Iy
    from tumble_ros.core.torques.orbits import KeplerOrbit
    sun = 1.3271244e11                                  # GM [km^3/s^2], the orbit's unit
    flyby = Scenario(orbit_rate=0.0, orbit=KeplerOrbit(gm=sun, a=1.5e8, e=1.5, t_p=0.05),
                     duration=0.1, output_interval=0.01)
    scenes = _scenes(record_offline(flyby, tmp_path / 'flyby.mcap').output)
    position = flyby.perturber_position(np.arange(11) * 0.01)
    assert np.ptp(position[:, 0]) > 0.1 * np.linalg.norm(position, axis=1).max()   # it moves
    for scene, r in zip(scenes, position):
        by_ns = {m.ns: m for m in scene.markers}
        np.testing.assert_allclose(_direction(by_ns['perturber'].points),
                                   r / np.linalg.norm(r), atol=1e-12)
    no_torque = Scenario(orbit_rate=0.0, duration=0.01, output_interval=0.01)
    free = record_offline(no_torque, tmp_path / 'free.mcap').output
    (scene, *_) = _scenes(free)
    assert [m.ns for m in scene.markers] == ['angular_momentum']
    assert [m.ns for m in _body(free).markers] == ['body', 'axes', 'axes', 'axes']


def test_each_perturber_is_drawn(tmp_path):
    from tumble_ros.core.torques.orbits import KeplerOrbit
    from tumble_ros.core.torques.perturbers import Perturber
    sun = Perturber('sun', KeplerOrbit(gm=1.3271244e11, a=1.5e8, e=1.5, t_p=0.05))
    moon = Perturber('moon', KeplerOrbit(gm=4902.800066, a=4e5, e=0.3, node=1.0))
    sc = Scenario(orbit_rate=0.0, perturbers=(sun, moon), duration=0.1, output_interval=0.01)
    result = record_offline(sc, tmp_path / 'two.mcap')
    scenes = _scenes(result.output)
    t = np.arange(11) * 0.01
    for k, scene in enumerate(scenes):
        arrows = {m.id: m for m in scene.markers if m.ns == 'perturber'}
        assert sorted(arrows) == [0, 1]
        for j, body in enumerate((sun, moon)):
            r = body.position([t[k]])[0]
            np.testing.assert_allclose(_direction(arrows[j].points), r / np.linalg.norm(r),
                                       atol=1e-12)


def test_rosbags_decodes_the_scene_too(recorded):
    _, result = recorded
    from rosbags.highlevel import AnyReader
    decoded = {}
    with AnyReader([result.output]) as reader:
        for topic in (MARKERS, BODY_MARKERS, topics.TF):
            (connection,) = [c for c in reader.connections if c.topic == topic]
            assert connection.msgtype == {MARKERS: topics.TYPES[topics.MARKERS],
                                          BODY_MARKERS: topics.TYPES[topics.BODY_MARKERS],
                                          topics.TF: 'tf2_msgs/msg/TFMessage'}[topic]
            decoded[topic] = [reader.deserialize(raw, connection.msgtype)
                              for _, _, raw in reader.messages(connections=[connection])]
    assert len(decoded[MARKERS]) == len(decoded[topics.TF]) == result.samples
    q, _ = _samples(result.output)
    for scene, tf in zip(decoded[MARKERS], decoded[topics.TF]):
        (t,) = tf.transforms
        stamp = TimeBase.stamp_ns(t.header.stamp.sec, t.header.stamp.nanosec)
        o = t.transform.rotation
        assert [o.w, o.x, o.y, o.z] == q[stamp].tolist()
        assert [m.ns for m in scene.markers] == ['angular_momentum', 'sun']
    (body,) = decoded[BODY_MARKERS]
    assert [m.ns for m in body.markers] == ['body', 'axes', 'axes', 'axes']


def test_long_runs_are_decimated_and_end_on_the_last_sample(tmp_path):
    every = marker_every(0, 3 * MARKER_FRAMES + 1)
    assert every == 4 and marker_every(7, 10) == 7 and marker_every(0, MARKER_FRAMES) == 1
    sc = Scenario(duration=0.1, output_interval=0.001)
    result = record_offline(sc, tmp_path / 'd.mcap', marker_decimation=30)
    stamps = [s.markers[0].header.stamp.nanosec for s in _scenes(result.output)]
    interval = TimeBase().grid(0.001, 0.1).interval_ns
    assert stamps == [k * interval for k in (0, 30, 60, 90, 100)]
    off = record_offline(sc, tmp_path / 'off.mcap', markers=False)
    assert MARKERS not in off.counts and off.samples == 101


def test_a_template_encodes_what_rclpy_decodes():
    from geometry_msgs.msg import Point
    from rclpy.serialization import deserialize_message, serialize_message
    from visualization_msgs.msg import Marker, MarkerArray
    msg = MarkerArray(markers=[Marker(ns='a', points=[Point(), Point()]), Marker(ns='bb')])
    name = topics.TYPES[topics.MARKERS]
    template = MessageTemplate(name, message_definition(name), serialize_message(msg))
    rows = template.encode(3, {'markers[0].points[1].y': np.array([1.0, 2.0, 3.0]),
                               'markers[1].id': 7})
    back = [deserialize_message(row.tobytes(), MarkerArray) for row in rows]
    assert [b.markers[0].points[1].y for b in back] == [1.0, 2.0, 3.0]
    assert {b.markers[1].id for b in back} == {7} and back[2].markers[1].ns == 'bb'
    with pytest.raises(KeyError):
        template.encode(1, {'markers[2].id': 1})


def test_a_polyhedron_body_is_drawn_once_as_its_facets_turning_with_tf(tmp_path):
    from tumble_ros.core.model.body import BodySpec
    from tumble_ros.core.model.shape_files import load_shape, resolve_shape_path
    body = BodySpec(model='polyhedron', density=2600.0, shape_file='config/shapes/apophis.obj')
    sc = Scenario(body=body, duration=0.02, output_interval=0.01)
    result = record_offline(sc, tmp_path / 'shape.mcap')
    shape = load_shape(resolve_shape_path('config/shapes/apophis.obj'), 2600.0)
    v, f = shape.vertices, shape.facets                 # (shipped in principal axes)
    q, _ = _samples(tmp_path / 'shape.mcap')
    tf = _tf(tmp_path / 'shape.mcap')
    marker = _body(result.output).markers[0]             # sent once
    assert marker.type == 11 and marker.ns == 'body'          # TRIANGLE_LIST
    assert (marker.scale.x, marker.scale.y, marker.scale.z) == (1.0, 1.0, 1.0)
    points = np.array([[p.x, p.y, p.z] for p in marker.points])
    assert points.shape == (3 * len(f), 3)
    scale = np.linalg.norm(v, axis=1).max()          # the farthest vertex drawn at 1
    np.testing.assert_allclose(points, v[f].reshape(-1, 3) / scale, rtol=1e-12)
    normals = np.cross(points[1::3] - points[0::3], points[2::3] - points[0::3])
    assert np.all(np.einsum('ij,ij->i', normals, points[0::3]) > 0)   # outward, as read
    o = marker.pose.orientation
    assert [o.w, o.x, o.y, o.z] == [1.0, 0.0, 0.0, 0.0]      # the attitude comes from TF
    assert sorted(tf) == sorted(q) and all(tf[s].tolist() == q[s].tolist() for s in q)
    assert len(_scenes(result.output)) == 3


def test_the_still_poses_the_shape_sent_once_with_the_attitude(recorded):
    """The still (analyze --still): the body and axes of body_markers, turned by the attitude."""
    from tumble_ros.analysis.animation import Arrow, marker_scene, Solid
    _, result = recorded
    q, _ = _samples(result.output)
    for stamp in sorted(q)[::25]:
        scene = marker_scene(_body(result.output), q[stamp])
        (solid,) = [p for p in scene if isinstance(p, Solid)]
        np.testing.assert_allclose(solid.quaternion, q[stamp], atol=1e-15)
        arrows = {p.label: p for p in scene if isinstance(p, Arrow)}
        for i, axis in enumerate('xyz'):
            along = np.array(arrows[axis].end) - np.array(arrows[axis].start)
            np.testing.assert_allclose(along / np.linalg.norm(along),
                                       _rotate(q[stamp], np.eye(3)[i]), atol=1e-12)

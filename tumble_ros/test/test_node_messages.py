"""
The per-sample messages encoded as numpy rows (SampleEncoder) against rclpy's own messages.

The live simulator publishes these bytes and the offline recording writes them, so the check
must not come from the encoder: each row is deserialised by rclpy and compared with the message
built field by field as objects, and its length with rclpy's serialisation of that message.
"""
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Quaternion, QuaternionStamped, Vector3, Vector3Stamped
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Header

from tumble_ros import topics
from tumble_ros.runs.messages.builders import SampleEncoder, Vector3StampedReader
from tumble_ros_interfaces.msg import ErrorNorm

#: Awkward values: signed zero, a subnormal, extremes, infinities.
AWKWARD = [0.0, -0.0, 5e-324, -1.7976931348623157e308, np.inf, -np.inf, 1.0 / 3.0]


def _stamps(n: int) -> np.ndarray:
    rng = np.random.default_rng(3)
    ns = rng.integers(0, 2**31 - 1, n, dtype=np.int64) * 1_000_000_000 + rng.integers(
        0, 1_000_000_000, n)
    edges = [0, 999_999_999, (2**31 - 1) * 1_000_000_000 + 999_999_999]
    ns[:3] = edges[:n]
    return ns


def _columns(n: int, width: int, seed: int) -> np.ndarray:
    values = np.random.default_rng(seed).normal(scale=1e3, size=(n, width))
    values.flat[:len(AWKWARD)] = AWKWARD
    return values


def _header(ns: int, frame: str) -> Header:
    return Header(stamp=Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9)), frame_id=frame)


def _vector(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _same(row: np.ndarray, expected) -> None:
    data = row.tobytes()
    assert len(data) == len(serialize_message(expected))
    decoded = deserialize_message(data, type(expected))
    assert decoded == expected, (decoded, expected)
    assert _reprs(decoded) == _reprs(expected)  # (== takes -0.0 for 0.0)


def _reprs(msg) -> list[str]:
    """Return repr() of every leaf field of a message, depth first."""
    if not hasattr(msg, 'get_fields_and_field_types'):
        return [repr(msg)]
    return [r for name in msg.get_fields_and_field_types() for r in _reprs(getattr(msg, name))]


@pytest.mark.parametrize('clock', [True, False])
def test_simulator_rows_are_the_messages_rclpy_builds(clock):
    n = 40
    ns = _stamps(n)
    omega, quaternion, euler, position = (_columns(n, 3, 1), _columns(n, 4, 2),
                                          _columns(n, 3, 3), _columns(n, 3, 4))
    blocks = SampleEncoder().simulator(ns, omega, quaternion, euler, clock=clock,
                                       perturber=position)
    order = ([topics.CLOCK] if clock else []) + [topics.ANGULAR_VELOCITY, topics.ATTITUDE,
                                                 topics.EULER_ANGLES, topics.PERTURBER]
    assert [topic for topic, _ in blocks] == order
    rows = dict(blocks)
    for j in range(n):
        if clock:
            _same(rows[topics.CLOCK][j], Clock(clock=_header(ns[j], '').stamp))
        _same(rows[topics.ANGULAR_VELOCITY][j], Vector3Stamped(
            header=_header(ns[j], topics.FRAME_BODY), vector=_vector(omega[j])))
        w, x, y, z = quaternion[j].tolist()
        _same(rows[topics.ATTITUDE][j], QuaternionStamped(
            header=_header(ns[j], topics.FRAME_ORBITAL), quaternion=Quaternion(w=w, x=x, y=y,
                                                                               z=z)))
        _same(rows[topics.EULER_ANGLES][j], Vector3Stamped(
            header=_header(ns[j], topics.FRAME_EULER), vector=_vector(euler[j])))
        _same(rows[topics.PERTURBER][j], Vector3Stamped(
            header=_header(ns[j], topics.FRAME_BODY), vector=_vector(position[j])))


def test_without_a_perturber_there_is_no_perturber_row():
    ns = _stamps(2)
    blocks = SampleEncoder().simulator(ns, _columns(2, 3, 1), _columns(2, 4, 2),
                                       _columns(2, 3, 3))
    assert topics.PERTURBER not in dict(blocks)


@pytest.mark.parametrize('model_name', ['paper', 'torque_free_exact', ''])
def test_comparator_rows_are_the_messages_rclpy_builds(model_name):
    n = 25
    ns = _stamps(n)
    model, error, norms = _columns(n, 3, 5), _columns(n, 3, 6), _columns(n, 2, 7)
    blocks = SampleEncoder().comparator(ns, model, error, norms[:, 0], norms[:, 1], model_name)
    assert [topic for topic, _ in blocks] == [topics.MODEL_ANGULAR_VELOCITY, topics.ERROR,
                                              topics.ERROR_NORM]
    rows = dict(blocks)
    for j in range(n):
        header = _header(ns[j], topics.FRAME_BODY)
        _same(rows[topics.MODEL_ANGULAR_VELOCITY][j], Vector3Stamped(header=header,
                                                                     vector=_vector(model[j])))
        _same(rows[topics.ERROR][j], Vector3Stamped(header=header, vector=_vector(error[j])))
        _same(rows[topics.ERROR_NORM][j], ErrorNorm(header=header, model=model_name,
                                                    norm=float(norms[j, 0]),
                                                    relative=float(norms[j, 1])))


def test_one_sample_of_the_comparator_is_its_row():
    """SampleEncoder.comparison (one sample, struct) gives the bytes of comparator() (numpy)."""
    n = 12
    ns = _stamps(n)
    model, error, norms = _columns(n, 3, 8), _columns(n, 3, 9), _columns(n, 2, 10)
    encoder = SampleEncoder()
    rows = [block for _, block in encoder.comparator(ns, model, error, norms[:, 0],
                                                     norms[:, 1], 'paper')]
    for j in range(n):
        one = encoder.comparison(int(ns[j]), model[j].tolist(), error[j].tolist(),
                                 float(norms[j, 0]), float(norms[j, 1]), 'paper')
        assert list(one) == [block[j].tobytes() for block in rows]
    # another model name: another string in the message
    other = encoder.comparison(int(ns[0]), model[0].tolist(), error[0].tolist(), 1.0, 2.0,
                               'torque_free_exact')[2]
    assert deserialize_message(other, ErrorNorm).model == 'torque_free_exact'


def test_the_reader_reads_what_rclpy_writes_in_both_byte_orders():
    read = Vector3StampedReader()
    ns = _stamps(20)
    values = _columns(20, 3, 11)
    for j in range(20):
        msg = Vector3Stamped(header=_header(ns[j], 'any frame ' * (j % 4)),
                             vector=_vector(values[j]))
        stamp, vector = read(serialize_message(msg))
        assert stamp == ns[j]
        assert [repr(v) for v in vector] == [repr(v) for v in values[j].tolist()]
    # big-endian CDR (another DDS may send it): through rclpy's deserialisation
    big = (b'\x00\x00\x00\x00' + (7).to_bytes(4, 'big') + (9).to_bytes(4, 'big')
           + (1).to_bytes(4, 'big') + b'\x00' + b'\x00' * 3
           + np.array([1.5, -2.0, 3.25], dtype='>f8').tobytes())
    assert read(big) == (7_000_000_009, (1.5, -2.0, 3.25))


@pytest.mark.parametrize('data', [b'', b'\x00\x01\x00\x00\x05', b'garbage',
                                  b'\x00\x01\x00\x00' + b'\x00' * 8 + b'\xff\xff\xff\x7f'])
def test_the_reader_refuses_what_is_not_a_vector3_stamped(data):
    with pytest.raises(ValueError, match='not a geometry_msgs/Vector3Stamped'):
        Vector3StampedReader()(data)

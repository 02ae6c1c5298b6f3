"""
A per-sample topic added in one place: its description (tumble_ros.topics.SAMPLE_TOPICS).

The test registers a topic the package does not have, the angular momentum L = I w [I rad/yr]
in body axes, as one description whose columns come from the simulator's sample block, and
nothing else: the live simulator publishes it, the offline writer records it, the columnar
reader decodes it, and the three agree with each other and with I w computed here from the
published angular velocity.
"""
from geometry_msgs.msg import Vector3Stamped
import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.core import Scenario
from tumble_ros.io import read_columns, sample_values
from tumble_ros.nodes.sim import SimNode
from tumble_ros.runs.messages.builders import SampleEncoder
from tumble_ros.runs.offline import record_offline
from tumble_ros_interfaces.msg import SimStatus

INERTIA = (1.0, 1.6, 2.2)
SHORT = {'duration': 0.2, 'output_interval': 0.002}
COUNT = 101                       # 0, 0.002, ..., 0.2 yr
MOMENTUM = 'angular_momentum'
MOMENTUM_TOPIC = topics.SampleTopic(
    MOMENTUM, 'geometry_msgs/msg/Vector3Stamped', ('vector.x', 'vector.y', 'vector.z'),
    topics.FRAME_BODY, topics.SIM,
    lambda block: (np.asarray(INERTIA) * block['omega']).T)


@pytest.fixture
def momentum(monkeypatch):
    """Register the new topic: the one place."""
    monkeypatch.setattr(topics, 'SAMPLE_TOPICS', topics.SAMPLE_TOPICS + (MOMENTUM_TOPIC,))
    return MOMENTUM_TOPIC


def _values(msgs) -> np.ndarray:
    return np.array([[m.vector.x, m.vector.y, m.vector.z] for m in msgs])


def _stamps(msgs) -> np.ndarray:
    return np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
                     for m in msgs], dtype=np.int64)


def test_a_described_topic_is_published_live_written_offline_and_decoded_alike(
        momentum, ros, tmp_path):
    # live: the simulator node, as it runs
    live = ros.collect(Vector3Stamped, MOMENTUM)
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = ros.start(SimNode, real_time_factor=0.0, inertia=list(INERTIA), **SHORT)
    assert MOMENTUM in sim.per_sample_topics
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)
    assert ros.spin_until(lambda: len(live) == COUNT and len(omega) == COUNT, 5.0), (
        len(live), len(omega))
    assert {m.header.frame_id for m in live} == {topics.FRAME_BODY}
    # offline: the writer of bringup --offline, then the columnar reader
    path = tmp_path / 'offline.mcap'
    result = record_offline(Scenario(inertia=INERTIA, **SHORT), path, markers=False)
    assert result.state == SimStatus.FINISHED and result.counts[f'/{MOMENTUM}'] == COUNT
    columns, _ = read_columns(path, [f'/{MOMENTUM}', f'/{topics.ANGULAR_VELOCITY}'])
    table = columns[f'/{MOMENTUM}']
    assert table.type_name == momentum.type_name and table.columnar == COUNT
    assert table.strings['header.frame_id'] == [topics.FRAME_BODY]
    stamps, decoded = sample_values(table, momentum)
    # equal across the three, and what I w is (from the recorded w, computed here)
    np.testing.assert_array_equal(_stamps(live), stamps)
    np.testing.assert_array_equal(_values(live), decoded)
    _, recorded_omega = sample_values(columns[f'/{topics.ANGULAR_VELOCITY}'],
                                      topics.sample_topic(topics.ANGULAR_VELOCITY))
    np.testing.assert_array_equal(recorded_omega, _values(omega))
    np.testing.assert_array_equal(decoded, recorded_omega * np.array(INERTIA))
    assert np.ptp(decoded, axis=0).max() > 0      # (not a constant: the body tumbles)


def test_the_encoder_encodes_any_described_topic_and_leaves_out_an_absent_one(momentum):
    encoder = SampleEncoder()
    ns = np.array([0, 2_000_000, 4_000_000], dtype=np.int64)
    omega = np.arange(9.0).reshape(3, 3)
    quaternion = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    blocks = dict(encoder.simulator(ns, omega, quaternion, omega, clock=False))
    assert list(blocks) == [*topics.SIM_PER_SAMPLE, MOMENTUM]      # no perturber: no orbit
    built = encoder.encode(momentum, ns, (omega * np.array(INERTIA)).T)
    assert blocks[MOMENTUM].tobytes() == built.tobytes()
    assert blocks[MOMENTUM].tobytes() != blocks[topics.ANGULAR_VELOCITY].tobytes()

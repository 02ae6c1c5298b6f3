"""The comparator node: one error sample per (k-th) w sample, anchoring, refusals, late join."""
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
import numpy as np
import pytest
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger

from tumble_ros import topics
from tumble_ros.core import make_model, Scenario, TimeBase
from tumble_ros.nodes.comparator import ComparatorNode
from tumble_ros.nodes.sim import SimNode
from tumble_ros.runs.messages.qos import DESCRIPTION_QOS, STATE_QOS
from tumble_ros_interfaces.msg import ErrorNorm, ScenarioDescription

RUN = {'duration': 0.2, 'output_interval': 0.002, 'real_time_factor': 0.0, 'min_consumers': 1}


def stamp_ns(msg):
    return TimeBase.stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec)


def vec(msgs):
    return np.array([[m.vector.x, m.vector.y, m.vector.z] for m in msgs])


def test_an_error_sample_for_every_omega_sample(ros):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    error = ros.collect(Vector3Stamped, topics.ERROR)
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    ros.start(ComparatorNode)
    ros.start(SimNode, **RUN)
    assert ros.spin_until(lambda: len(norm) == 101 and len(error) == 101 and len(model) == 101,
                          20.0), len(norm)
    assert [stamp_ns(m) for m in norm] == [stamp_ns(m) for m in omega]
    np.testing.assert_allclose(vec(error), vec(omega) - vec(model), rtol=0, atol=1e-12)
    np.testing.assert_allclose([m.norm for m in norm], np.linalg.norm(vec(error), axis=1),
                               rtol=1e-12)
    assert norm[0].norm < 1e-12  # anchored on the initial state
    assert norm[-1].norm > 1e-4 and norm[0].model == 'paper'
    # the published model is the core's model at the stamped times
    t = np.array([stamp_ns(m) * 1e-9 for m in omega])
    np.testing.assert_allclose(vec(model), make_model('paper', Scenario()).omega(t), rtol=0,
                               atol=1e-12)


def test_a_sample_off_the_simulators_grid_is_compared_at_its_own_time(ros):
    """
    A sample off the simulator's grid gets the model at exactly its own time.

    The comparator evaluates the model ahead on the simulator's sample grid; any other stamp
    (another publisher, a changed grid) still gets the model at exactly its time.
    """
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    ros.start(ComparatorNode)
    ros.start(SimNode, start_paused=True, **RUN)
    pub = ros.probe.create_publisher(Vector3Stamped, topics.ANGULAR_VELOCITY, STATE_QOS)
    assert ros.spin_until(lambda: pub.get_subscription_count() > 0, 5.0)
    ros.spin_for(0.3)  # the latched scenario description reaches the comparator
    # ns: on the grid (0.002 yr), 0.0123 s, 0.0543 s (in time order: see the next test)
    off_grid = [2_000_000, 12_345_678, 54_321_987]
    for ns in off_grid:
        msg = Vector3Stamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 1_000_000_000)
        pub.publish(msg)
    assert ros.spin_until(lambda: len(model) == 3, 5.0), len(model)
    expected = make_model('paper', Scenario()).omega(np.array(off_grid) * 1e-9)
    np.testing.assert_allclose(vec(model), expected, rtol=0, atol=1e-12)


def test_samples_that_are_not_the_runs_never_reach_the_comparison(ros):
    """
    NaN, out-of-order and after-the-end samples of another publisher: dropped, counted, said.

    A foreign publisher on ``angular_velocity`` (here the test's probe, the simulator paused):
    its NaN sample, a sample older than the last one taken and one after the run's end (0.2 s
    of ROS time) are dropped; the comparison topics carry only the two samples that can be the
    run's, and ``comparison/status`` says how many were dropped and why.
    """
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    status = ros.collect(DiagnosticStatus, topics.COMPARISON_STATUS, latched=True)
    node = ros.start(ComparatorNode)
    ros.start(SimNode, start_paused=True, **RUN)
    pub = ros.probe.create_publisher(Vector3Stamped, topics.ANGULAR_VELOCITY, STATE_QOS)
    assert ros.spin_until(lambda: pub.get_subscription_count() > 0, 5.0)
    assert ros.spin_until(lambda: status and status[-1].level == DiagnosticStatus.OK, 10.0)
    for ns, x in [(4_000_000, 0.0), (6_000_000, float('nan')), (2_000_000, 0.0),
                  (10_000_000_000, 0.0), (8_000_000, 0.0)]:
        msg = Vector3Stamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 1_000_000_000)
        msg.vector.x, msg.vector.z = x, 30.0
        pub.publish(msg)
    assert ros.spin_until(lambda: node.dropped_samples == 3 and len(norm) == 2, 5.0), (
        node.dropped_samples, len(norm))
    ros.spin_for(0.2)
    assert [stamp_ns(m) for m in model] == [4_000_000, 8_000_000]
    assert all(np.isfinite(m.norm) for m in norm)
    # (the probe is also a second publisher: the second-source ERROR may follow)
    said = [m for m in status if 'dropped 3 samples' in m.message]
    assert said and said[0].level == DiagnosticStatus.WARN, [m.message for m in status]
    for why in ('1 not finite', '1 not after the last sample', "1 after the run's end"):
        assert why in said[0].message


def test_an_unreadable_sample_is_skipped_and_the_next_one_compared(ros):
    """Bytes on angular_velocity that are no Vector3Stamped: skipped, the node goes on."""
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    node = ros.start(ComparatorNode)
    ros.start(SimNode, start_paused=True, **RUN)
    pub = ros.probe.create_publisher(Vector3Stamped, topics.ANGULAR_VELOCITY, STATE_QOS)
    assert ros.spin_until(lambda: pub.get_subscription_count() > 0, 5.0)
    ros.spin_for(0.3)  # the latched scenario description reaches the comparator
    pub.publish(b'\x00\x01\x00\x00\x05')      # little-endian CDR, ends inside the stamp
    pub.publish(b'garbage')
    msg = Vector3Stamped()
    msg.header.stamp.nanosec = 2_000_000
    pub.publish(msg)
    assert ros.spin_until(lambda: len(model) == 1, 5.0), len(model)
    assert stamp_ns(model[0]) == 2_000_000 and node.consumed == 1


def test_decimation_compares_every_kth_sample(ros):
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    ros.start(ComparatorNode, decimation=3)
    ros.start(SimNode, **RUN)
    assert ros.spin_until(lambda: len(omega) == 101, 20.0)
    ros.spin_until(lambda: len(norm) == 34, 5.0)
    assert [stamp_ns(m) for m in norm] == [stamp_ns(m) for m in omega[::3]]


def test_a_model_that_does_not_apply_says_so_and_publishes_nothing(ros):
    status = ros.collect(DiagnosticStatus, topics.COMPARISON_STATUS, latched=True)
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    ros.start(ComparatorNode)
    ros.start(SimNode, inertia=[1.0, 1.2, 1.5], **RUN)
    assert ros.spin_until(lambda: len(omega) == 101, 20.0)
    ros.spin_for(0.2)
    assert norm == []
    assert status[-1].level == DiagnosticStatus.WARN and 'inertia' in status[-1].message
    assert 'symmetric' in status[-1].message


def test_late_join_recovers_from_the_latched_scenario(ros):
    sim = ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002,
                    real_time_factor=0.0)
    for _ in range(5):
        assert ros.call(Trigger, topics.STEP, Trigger.Request()).success
    status = ros.collect(DiagnosticStatus, topics.COMPARISON_STATUS, latched=True)
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    ros.start(ComparatorNode, model='fast_spin')
    assert ros.spin_until(lambda: status and status[-1].level == DiagnosticStatus.OK, 10.0)
    assert ros.call(Trigger, topics.RESUME, Trigger.Request()).success
    assert ros.spin_until(lambda: sim.published_samples == 101, 20.0)
    # the 5 samples published before it started come from the topics' transient-local history
    assert ros.spin_until(lambda: len(model) == 101, 10.0), len(model)
    t = np.array([stamp_ns(m) * 1e-9 for m in model])
    expected = make_model('fast_spin', Scenario(duration=0.2, output_interval=0.002)).omega(t)
    np.testing.assert_allclose(vec(model), expected, rtol=0, atol=1e-12)


def test_an_impact_re_anchors_the_model(ros):
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    status = ros.collect(DiagnosticStatus, topics.COMPARISON_STATUS, latched=True)
    ros.start(ComparatorNode)
    # an axial kick of 0.2 rad/yr at t = 0.1: without re-anchoring the model would be off by 0.2
    ros.start(SimNode, impacts__start=[0.1], impacts__duration=[3e-7],
              impacts__torque=[0.0, 0.0, 1e6], **RUN)
    assert ros.spin_until(lambda: len(norm) == 101, 20.0), len(norm)
    t = np.array([stamp_ns(m) * 1e-9 for m in norm])
    err = np.array([m.norm for m in norm])
    after = t > 0.1 + 3e-7
    assert err[after].max() < 0.05  # the same size as before the kick, not 0.2
    assert err[~after].max() > 0
    assert any('segment 1' in s.message and '0.1000003' in s.message for s in status)


def test_invalid_model_is_refused_at_start_up_and_at_run_time(ros):
    with pytest.raises(Exception, match='unknown model'):
        ros.start(ComparatorNode, model='nonsense')
    ros.start(ComparatorNode)
    req = SetParameters.Request(
        parameters=[Parameter('model', value='nonsense').to_parameter_msg()])
    result = ros.call(SetParameters, '/comparator/set_parameters', req).results[0]
    assert not result.successful and 'unknown model' in result.reason
    req = SetParameters.Request(parameters=[Parameter('decimation', value=0).to_parameter_msg()])
    assert not ros.call(SetParameters, '/comparator/set_parameters', req).results[0].successful


def test_samples_before_an_impact_keep_the_pre_impact_model(ros):
    """With the simulator far ahead, pre-impact samples are still compared with their anchor."""
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    ros.start(ComparatorNode)
    ros.start(SimNode, impacts__start=[0.1], impacts__duration=[3e-7],
              impacts__torque=[0.0, 0.0, 1e6], **RUN)
    assert ros.spin_until(lambda: len(model) == 101, 20.0), len(model)
    t = np.array([stamp_ns(m) * 1e-9 for m in model])
    before = t <= 0.1
    expected = make_model('paper', Scenario(duration=0.2, output_interval=0.002)).omega(t[before])
    np.testing.assert_allclose(vec(model)[before], expected, rtol=0, atol=1e-12)


def test_a_comparator_started_after_an_impact_compares_every_segment(ros):
    """Late join after an impact: the description history gives both anchors."""
    sim = ros.start(SimNode, start_paused=True, impacts__start=[0.1], impacts__duration=[3e-7],
                    impacts__torque=[0.0, 0.0, 1e6],
                    **{k: v for k, v in RUN.items() if k != 'min_consumers'})
    for _ in range(60):  # to t = 0.118 yr, past the impact
        assert ros.call(Trigger, topics.STEP, Trigger.Request()).success
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    norm = ros.collect(ErrorNorm, topics.ERROR_NORM)
    ros.start(ComparatorNode)
    ros.spin_for(0.5)
    assert ros.call(Trigger, topics.RESUME, Trigger.Request()).success
    assert ros.spin_until(lambda: sim.published_samples == 101 and len(model) == 101,
                          20.0), len(model)
    t = np.array([stamp_ns(m) * 1e-9 for m in model])
    before = t <= 0.1
    expected = make_model('paper', Scenario(duration=0.2, output_interval=0.002)).omega(t[before])
    np.testing.assert_allclose(vec(model)[before], expected, rtol=0, atol=1e-12)
    assert max(m.norm for m in norm) < 0.05  # after the kick: the post-impact anchor


def test_held_samples_wait_for_the_whole_description_history(ros):
    """
    Held samples wait for the whole description history.

    A late join in which DDS replays the sample history before the description history: the
    held samples are compared only after the post-impact description is in, not with the first
    (pre-impact) anchor. Replayed by the probe in that order to a comparator in /replay.
    """
    descriptions, omega = [], ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    ros.probe.create_subscription(ScenarioDescription, topics.SCENARIO, descriptions.append,
                                  DESCRIPTION_QOS)
    ros.start(SimNode, start_paused=True, impacts__start=[0.1], impacts__duration=[3e-7],
              impacts__torque=[0.0, 0.0, 1e6],
              **{k: v for k, v in RUN.items() if k != 'min_consumers'})
    for _ in range(60):  # to t = 0.118 yr, past the impact at 0.1
        assert ros.call(Trigger, topics.STEP, Trigger.Request()).success
    assert ros.spin_until(lambda: len(omega) == 60 and len(descriptions) == 2, 5.0)

    replay = '/replay'
    comparator = ros.add(ComparatorNode(context=ros.context, namespace=replay))
    norm = ros.collect(ErrorNorm, topics.in_namespace(replay, topics.ERROR_NORM))
    pub_omega = ros.probe.create_publisher(
        Vector3Stamped, topics.in_namespace(replay, topics.ANGULAR_VELOCITY), STATE_QOS)
    pub_description = ros.probe.create_publisher(
        ScenarioDescription, topics.in_namespace(replay, topics.SCENARIO), DESCRIPTION_QOS)
    assert ros.spin_until(lambda: pub_omega.get_subscription_count()
                          and pub_description.get_subscription_count(), 5.0)
    for msg in omega:
        pub_omega.publish(msg)
    ros.spin_for(0.5)
    assert norm == []  # held: no description yet
    pub_description.publish(descriptions[0])
    # the first anchor is in
    assert ros.spin_until(lambda: comparator.described, 5.0)
    pub_description.publish(descriptions[1])
    assert ros.spin_until(lambda: len(norm) == 60, 5.0), len(norm)
    t = np.array([stamp_ns(m) * 1e-9 for m in norm])
    assert t.max() > 0.1 + 3e-7
    assert max(m.norm for m in norm) < 0.05  # each sample against its own segment's anchor


def test_a_foreign_scenario_is_ignored_and_the_own_run_compared(ros):
    """
    A second simulator's ``scenario`` on the same topics: the comparator keeps its own run.

    The comparator anchors on its simulator's description, then another simulator (another
    scenario, paused: it publishes only its latched description) appears on the same topics.
    The comparator ignores that description (once warned, counted) and every sample of its own
    run is compared with its own scenario's model, not the foreign one's.
    """
    model = ros.collect(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY)
    status = ros.collect(DiagnosticStatus, topics.COMPARISON_STATUS, latched=True)
    descriptions = ros.collect(ScenarioDescription, topics.SCENARIO, qos=DESCRIPTION_QOS)
    own = ros.start(SimNode, start_paused=True, **RUN)
    comparator = ros.start(ComparatorNode)
    assert ros.spin_until(lambda: status and status[-1].level == DiagnosticStatus.OK, 10.0)
    foreign = ros.start(SimNode, start_paused=True, omega0=[0.5, 0.0, 20.0], **RUN)
    assert foreign.run_id != own.run_id
    assert ros.spin_until(lambda: len(descriptions) == 2, 5.0)
    ros.spin_for(0.3)   # the foreign description reaches the comparator too
    assert own._on_resume(Trigger.Request(), Trigger.Response()).success
    assert ros.spin_until(lambda: len(model) == 101, 20.0), len(model)
    t = np.array([stamp_ns(m) * 1e-9 for m in model])
    expected = make_model('paper', Scenario(duration=0.2, output_interval=0.002)).omega(t)
    np.testing.assert_allclose(vec(model), expected, rtol=0, atol=1e-12)
    assert comparator.run_id == own.run_id and comparator.foreign_descriptions == 1

"""The simulator node in-process: topics, values, impacts, parameters, pacing, failures."""
import math
import time

from geometry_msgs.msg import QuaternionStamped, Vector3, Vector3Stamped
import numpy as np
import pytest
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger

from tumble_ros import topics
from tumble_ros.core import Impact, Scenario, ScenarioError, simulate, TimeBase
from tumble_ros.nodes.sim import SimNode
from tumble_ros.runs.messages.qos import STATE_QOS
from tumble_ros_interfaces.msg import ImpactEvent, ScenarioDescription, SimStatus
from tumble_ros_interfaces.srv import ApplyImpact

SHORT = {'duration': 0.2, 'output_interval': 0.002, 'real_time_factor': 0.0}
#: /clock is best effort (rclpy's clock QoS); a deep reader queue keeps every sample in-process.
CLOCK_READER_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)


def omega_array(msgs):
    return np.array([[m.vector.x, m.vector.y, m.vector.z] for m in msgs])


def times(msgs, spy=1.0):
    tb = TimeBase(spy)
    return np.array([tb.to_years(tb.stamp_ns(m.header.stamp.sec, m.header.stamp.nanosec))
                     for m in msgs])


def test_topics_have_their_documented_types(ros):
    ros.start(SimNode, **SHORT, markers=True)     # the scene is off for a bare node
    expected = {
        '/' + topics.ANGULAR_VELOCITY: 'geometry_msgs/msg/Vector3Stamped',
        '/' + topics.ATTITUDE: 'geometry_msgs/msg/QuaternionStamped',
        '/' + topics.EULER_ANGLES: 'geometry_msgs/msg/Vector3Stamped',
        topics.CLOCK: 'rosgraph_msgs/msg/Clock',
        '/' + topics.IMPACT_EVENTS: 'tumble_ros_interfaces/msg/ImpactEvent',
        '/' + topics.STATUS: 'tumble_ros_interfaces/msg/SimStatus',
        '/' + topics.SCENARIO: 'tumble_ros_interfaces/msg/ScenarioDescription',
        '/' + topics.MARKERS: 'visualization_msgs/msg/MarkerArray',
    }

    def listed():
        return {n: t[0] for n, t in ros.probe.get_topic_names_and_types()}

    assert ros.spin_until(lambda: expected.items() <= listed().items(), 10.0), listed()
    services = dict(ros.probe.get_service_names_and_types())
    assert services['/' + topics.APPLY_IMPACT] == ['tumble_ros_interfaces/srv/ApplyImpact']
    for name in (topics.PAUSE, topics.RESUME, topics.STEP):
        assert services['/' + name] == ['std_srvs/srv/Trigger']
    # service introspection: calls can be recorded
    assert ros.spin_until(lambda: f'/{topics.APPLY_IMPACT}/_service_event' in listed(), 5.0)


def test_a_bare_node_publishes_no_scene(ros):
    """The 3D scene costs ~30 % of the standalone throughput: off unless asked (bringup asks)."""
    sim = ros.start(SimNode, **SHORT)
    assert sim.get_parameter('markers').value is False
    assert ros.spin_until(lambda: sim.published_samples > 0, 10.0)
    names = [n for n, _ in ros.probe.get_topic_names_and_types()]
    assert '/' + topics.ANGULAR_VELOCITY in names and '/' + topics.MARKERS not in names


def test_published_state_equals_simulate_at_the_stamped_times(ros):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    attitude = ros.collect(QuaternionStamped, topics.ATTITUDE)
    euler = ros.collect(Vector3Stamped, topics.EULER_ANGLES)
    clock = ros.collect(Clock, topics.CLOCK, qos=CLOCK_READER_QOS)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    ros.start(SimNode, seconds_per_year=3.0, **SHORT)
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)
    ros.spin_until(lambda: len(omega) == 101 and len(attitude) == 101 and len(clock) == 101, 5.0)
    assert len(omega) == len(attitude) == len(clock) == 101  # 0, 0.002, ..., 0.2 yr: none lost
    t = times(omega, spy=3.0)
    np.testing.assert_allclose(t, np.arange(101) * 0.002, rtol=0, atol=1e-15)
    # the stamps are the one output grid (core.model.timebase.SampleGrid) at 3 s per year
    assert t.tolist() == TimeBase(3.0).grid(0.002, 0.2).times().tolist()
    ref = simulate(Scenario(duration=0.2, output_interval=0.002), t_eval=t)
    np.testing.assert_array_equal(omega_array(omega), ref.omega)  # same times, same numbers
    q = np.array([[m.quaternion.w, m.quaternion.x, m.quaternion.y, m.quaternion.z]
                  for m in attitude])
    np.testing.assert_array_equal(q, ref.quaternion)
    ros.spin_until(lambda: len(euler) == 101, 5.0)
    np.testing.assert_array_equal(omega_array(euler), ref.euler)   # (phi, psi, theta) as x, y, z
    assert [m.header.frame_id for m in (omega[0], attitude[0], euler[0])] == [
        topics.FRAME_BODY, topics.FRAME_ORBITAL, topics.FRAME_EULER]
    assert [c.clock for c in clock] == [m.header.stamp for m in omega]


def impact_request(**fields):
    req = ApplyImpact.Request()
    req.torque = Vector3(x=0.0, y=0.0, z=1.0e6)
    req.frame, req.duration, req.start, req.start_now = (ApplyImpact.Request.FRAME_BODY, 3e-7, 0.1,
                                                         False)
    for k, v in fields.items():
        setattr(req, k, v)
    return req


def test_accepted_impact_changes_omega_by_its_impulse(ros):
    events = ros.collect(ImpactEvent, topics.IMPACT_EVENTS)
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    scenario_msgs = ros.collect(ScenarioDescription, topics.SCENARIO, latched=True)
    ros.start(SimNode, start_paused=True, **SHORT)
    reply = ros.call(ApplyImpact, topics.APPLY_IMPACT, impact_request())
    assert reply.accepted, reply.message
    assert (reply.scheduled_start, reply.scheduled_end, reply.id) == (0.1, 0.1 + 3e-7, 1)
    ros.call(Trigger, topics.RESUME, Trigger.Request())
    assert ros.spin_until(lambda: events and len(omega) == 101, 20.0)
    (event,) = events
    dwz = 1.0e6 * 3e-7 / 1.5  # Mz dt / Iz (exact for Ix = Iy)
    assert event.id == 1 and event.delta_omega.z == pytest.approx(dwz, rel=1e-9)
    # The transverse part is the free motion during the pulse (w_perp turning at 15 rad/yr).
    ref = simulate(Scenario(duration=0.2, impacts=(Impact(0.1, 3e-7, (0.0, 0.0, 1.0e6)),)),
                   t_eval=[0.1, 0.1 + 3e-7])
    dw = [event.delta_omega.x, event.delta_omega.y, event.delta_omega.z]
    np.testing.assert_allclose(dw, ref.omega[1] - ref.omega[0], rtol=0, atol=1e-12)
    w = omega_array(omega)
    assert w[-1, 2] - w[0, 2] == pytest.approx(dwz, rel=1e-9)
    # The latched description now starts a new segment at the end of the pulse.
    assert ros.spin_until(lambda: scenario_msgs and scenario_msgs[-1].segment_start == 0.1 + 3e-7,
                          5.0)
    assert scenario_msgs[-1].omega.z == pytest.approx(30.0 + dwz, rel=1e-12)
    assert 'impacts.start' in scenario_msgs[-1].parameters_yaml


BAD_REQUESTS = [
    ({'torque': Vector3(x=math.nan, y=0.0, z=0.0)}, 'torque'),
    ({'torque': Vector3(x=0.0, y=math.inf, z=0.0)}, 'torque'),
    ({'duration': 0.0}, 'duration'),
    ({'duration': -1e-7}, 'duration'),
    ({'duration': 0.01}, 'max_impact_duration'),
    ({'torque': Vector3(x=1e12, y=0.0, z=0.0)}, 'max_impact_impulse'),
    ({'start': -0.5}, 'start'),
    ({'start': 0.19999999}, 'after the end'),
    ({'frame': 7}, 'frame'),
    ({'start': math.nan}, 'start'),
]


def test_bad_impact_requests_are_rejected_with_a_reason_and_the_node_goes_on(ros):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002,
              real_time_factor=0.1)
    for fields, reason in BAD_REQUESTS:
        reply = ros.call(ApplyImpact, topics.APPLY_IMPACT, impact_request(**fields))
        assert not reply.accepted, fields
        assert reason in reply.message, (fields, reply.message)
        assert reply.id == 0
    ros.call(Trigger, topics.RESUME, Trigger.Request())
    assert ros.spin_until(lambda: len(omega) >= 20, 10.0)  # still publishing after all that
    reply = ros.call(ApplyImpact, topics.APPLY_IMPACT, impact_request(start=0.01))
    assert not reply.accepted and 'past' in reply.message, reply.message
    assert ros.spin_until(lambda: len(omega) == 101, 10.0)


def test_invalid_parameters_are_refused_at_start_up(ros):
    with pytest.raises(ScenarioError, match='^inertia'):
        ros.start(SimNode, inertia=[1.0, 1.0, 4.0])
    with pytest.raises(ScenarioError, match=r'^integrator\.method'):
        ros.start(SimNode, integrator__method='euler')
    with pytest.raises(Exception, match='real_time_factor'):
        ros.start(SimNode, real_time_factor=-1.0)
    with pytest.raises(ValueError, match='int32'):
        ros.start(SimNode, duration=10_000.0, seconds_per_year=1e6)


def test_invalid_parameters_are_refused_at_run_time(ros):
    node = ros.start(SimNode, start_paused=True, **SHORT)

    def set_param(name, value):
        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        return ros.call(SetParameters, '/sim/set_parameters', req).results[0]

    result = set_param('real_time_factor', -2.0)
    assert not result.successful and result.reason
    result = set_param('max_impact_duration', math.nan)
    assert not result.successful and 'max_impact_duration' in result.reason
    result = set_param('inertia', [1.0, 1.0, 1.2])
    assert not result.successful and 'read-only' in result.reason
    result = set_param('max_impact_duration', 0.5)
    assert result.successful
    assert node.get_parameter('max_impact_duration').value == 0.5
    reply = ros.call(ApplyImpact, topics.APPLY_IMPACT,
                     impact_request(duration=0.01, torque=Vector3(x=0.0, y=0.0, z=1e3)))
    assert reply.accepted, reply.message  # the new cap is in force


def test_pause_step_resume(ros):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    sim = ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002,
                    real_time_factor=0.1)
    assert ros.spin_ticks(sim._timer, 50)
    assert omega == [] and sim.published_samples == 0  # paused from the start
    reply = ros.call(Trigger, topics.STEP, Trigger.Request())
    assert reply.success, reply.message
    assert ros.spin_until(lambda: len(omega) == 1, 5.0)
    assert ros.spin_ticks(sim._timer, 50)
    assert len(omega) == 1 and sim.published_samples == 1  # one sample, no more
    assert ros.call(Trigger, topics.RESUME, Trigger.Request()).success
    assert ros.spin_until(lambda: len(omega) >= 5, 5.0)
    assert ros.call(Trigger, topics.PAUSE, Trigger.Request()).success
    n = sim.published_samples
    assert ros.spin_until(lambda: len(omega) == n, 5.0)  # what was published before the pause
    assert ros.spin_ticks(sim._timer, 50)
    assert len(omega) == sim.published_samples == n < 101  # paused: nothing more
    # already paused: says so
    assert not ros.call(Trigger, topics.PAUSE, Trigger.Request()).success
    assert ros.call(Trigger, topics.STEP, Trigger.Request()).success
    assert ros.spin_until(lambda: len(omega) == n + 1, 5.0)
    assert ros.call(Trigger, topics.RESUME, Trigger.Request()).success
    assert ros.spin_until(lambda: len(omega) == 101, 10.0)
    assert not ros.call(Trigger, topics.STEP, Trigger.Request()).success  # finished: says so


def test_real_time_factor_paces_the_run(ros):
    """0.2 yr at 0.2 yr/s take at least a second; a slow machine only makes it longer."""
    arrivals = []
    ros.probe.create_subscription(Vector3Stamped, topics.ANGULAR_VELOCITY,
                                  lambda msg: arrivals.append(time.monotonic()), STATE_QOS)
    ros.start(SimNode, duration=0.2, output_interval=0.002, real_time_factor=0.2)
    assert ros.spin_until(lambda: len(arrivals) == 101, 20.0), len(arrivals)
    assert arrivals[-1] - arrivals[0] >= 0.9  # paced (unpaced: ~0.05 s), a lower bound only


def test_divergence_stops_publishing_and_reports(ros):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    # A valid scenario whose state overflows: a 1e300 torque pulse (torques need only be finite).
    ros.start(SimNode, inertia=[1.0, 1.6, 2.2], impacts__start=[0.0], impacts__duration=[0.5],
              impacts__torque=[1e300, 1e300, 1e300], integrator__method='rk4',
              integrator__step=0.1, duration=1.0, output_interval=0.1, real_time_factor=0.0)
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.DIVERGED, 10.0)
    assert 'non-finite' in status[-1].message
    ros.spin_for(0.2)
    assert len(omega) < 11
    assert np.all(np.isfinite(omega_array(omega)))


def test_ten_thousand_year_run_keeps_exact_times(ros):
    """A cheap free spinner over 10,000 yr: stamps stay valid int32 and t is recovered exactly."""
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    ros.start(SimNode, orbit_rate=0.0, omega0=[0.0, 0.001, 0.01], duration=10_000.0,
              output_interval=100.0,
              real_time_factor=0.0, integrator__rtol=1e-8)
    assert ros.spin_until(lambda: len(omega) == 101, 30.0), len(omega)
    t = times(omega)
    assert t[-1] == 10_000.0 and omega[-1].header.stamp.sec == 10_000
    np.testing.assert_array_equal(t, np.arange(101) * 100.0)


def test_as_fast_as_the_consumers_take_it_loses_nothing(ros):
    """With rtf = 0 and a slow consumer reporting progress, every sample arrives, in order."""
    import time

    from tumble_ros.nodes.progress import ProgressReporter
    from tumble_ros.runs.messages.qos import STATE_QOS

    reporter = ProgressReporter(ros.probe)
    got = []

    def slow(msg):
        got.append(msg)
        time.sleep(2e-4)
        reporter.mark(TimeBase.stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec))

    ros.probe.create_subscription(Vector3Stamped, topics.ANGULAR_VELOCITY, slow, STATE_QOS)
    # twice the depth of the topic's history (1000): without the flow control (sim.WINDOW
    # unbounded) 1240 of the 2001 arrived (2026-12-05)
    ros.start(SimNode, duration=0.2, output_interval=1e-4, real_time_factor=0.0, min_consumers=1)
    assert ros.spin_until(lambda: len(got) == 2001, 60.0), len(got)
    ns = [TimeBase.stamp_ns(m.header.stamp.sec, m.header.stamp.nanosec) for m in got]
    assert ns == [k * 100_000 for k in range(2001)]


def test_min_consumers_counts_only_the_consumers_present(ros):
    """
    A consumer that registered and died before the first sample is not counted.

    With min_consumers 2: a ghost registers (one report, then silence, as a consumer killed
    before the first sample), and once it has been silent for longer than CONSUMER_TIMEOUT a
    live consumer registers. One consumer is present: nothing is published, however many ticks
    the simulator gets. Before, the ghost still counted and the simulator started with one.
    """
    from builtin_interfaces.msg import Time
    import rclpy

    from tumble_ros.nodes.progress import (CONSUMER_TIMEOUT, PROGRESS_QOS, PROGRESS_TOPIC,
                                           ProgressReporter)
    from tumble_ros_interfaces.msg import ConsumerProgress

    sim = ros.start(SimNode, real_time_factor=0.0, min_consumers=2,
                    **{k: v for k, v in SHORT.items() if k != 'real_time_factor'})
    ghost = ros.probe.create_publisher(ConsumerProgress, PROGRESS_TOPIC, PROGRESS_QOS)
    assert ros.spin_until(lambda: ghost.get_subscription_count() >= 1, 10.0)
    ghost.publish(ConsumerProgress(consumer='/ghost', active=True, last_stamp=Time(sec=-1)))
    assert ros.spin_until(lambda: sim._consumers.count == 1, 10.0)
    ros.spin_for(CONSUMER_TIMEOUT + 0.5)   # the ghost is silent past the timeout
    live = [ProgressReporter(ros.probe)]   # reports (heartbeats), has processed nothing
    assert ros.spin_until(lambda: sim._consumers.count >= 1, 10.0)
    assert ros.spin_ticks(sim._timer, 100)
    assert sim.published_samples == 0, 'started with one consumer present of the two expected'
    assert sim._consumers.count == 1
    # a second live consumer: the two expected are present, publication starts
    second = ros.add(rclpy.create_node('second', context=ros.context))
    live.append(ProgressReporter(second))
    assert ros.spin_until(lambda: sim.published_samples > 0, 10.0)


def test_nothing_more_is_published_while_a_recorder_has_not_heard_a_comparator(ros):
    """
    A recorder reports the producing consumers it has heard (``ConsumerProgress.heard``).

    Beside two CPU hogs a recorder discovered a new comparator 1.7 s after the simulator did,
    and the simulator, paced on progress the recorder could not yet hold back, ran about 2,600
    samples ahead: 1,630 comparator samples beyond their history were lost. Now, while a
    recorder has not heard a present producer, the simulator publishes nothing more; once it
    has, publication goes on.
    """
    from builtin_interfaces.msg import Time

    from tumble_ros.nodes.progress import PROGRESS_QOS, PROGRESS_TOPIC
    from tumble_ros_interfaces.msg import ConsumerProgress

    sim = ros.start(SimNode, real_time_factor=0.0, min_consumers=2,
                    **{k: v for k, v in SHORT.items() if k != 'real_time_factor'})
    report = ros.probe.create_publisher(ConsumerProgress, PROGRESS_TOPIC, PROGRESS_QOS)
    assert ros.spin_until(lambda: report.get_subscription_count() >= 1, 10.0)

    def both(recorder_heard):
        far = Time(sec=10**6)     # both far ahead: only the gate can hold the simulator
        report.publish(ConsumerProgress(consumer='/recorder', active=True, last_stamp=far,
                                        records=True, heard=recorder_heard))
        report.publish(ConsumerProgress(consumer='/comparator', active=True, last_stamp=far,
                                        produces=['/comparison/error']))

    for _ in range(20):
        both([])
        ros.spin_for(0.05)
    assert sim._consumers.count == 2
    assert sim.published_samples == 0, 'published while the recorder had not heard the comparator'
    assert sim._consumers.recorders_behind() == [('/recorder', '/comparator')]
    for _ in range(20):
        both(['/comparator'])
        ros.spin_for(0.05)
    assert sim._consumers.recorders_behind() == []
    assert ros.spin_until(lambda: sim.published_samples > 0, 10.0)


def test_min_consumers_holds_publication_until_they_report(ros):
    from tumble_ros.nodes.progress import ProgressReporter
    from tumble_ros.nodes.sim import WINDOW

    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    sim = ros.start(SimNode, real_time_factor=0.0, min_consumers=1,
                    **{k: v for k, v in SHORT.items() if k != 'real_time_factor'})
    assert ros.spin_ticks(sim._timer, 50)
    assert omega == [] and sim.published_samples == 0  # nobody has reported yet
    reporter = ProgressReporter(ros.probe)  # reports, but has processed nothing
    assert ros.spin_until(lambda: len(omega) == WINDOW, 10.0), len(omega)
    assert ros.spin_ticks(sim._timer, 50)
    assert len(omega) == sim.published_samples == WINDOW  # never more than the window ahead
    reporter.mark(TimeBase.stamp_ns(omega[-1].header.stamp.sec, omega[-1].header.stamp.nanosec))
    assert ros.spin_until(lambda: len(omega) == 2 * WINDOW, 10.0), len(omega)


def test_nothing_is_published_before_the_command_line_is_accepted(ros):
    """
    A node refused for an unknown parameter has published nothing a consumer could anchor on.

    ``run_node`` refuses unknown parameters after the node is built (rclpy drops them
    silently): the run's description and its 'started' status go out at the first tick, not at
    construction, so a comparator or recorder never hears of a run that is then refused.
    """
    from rclpy.parameter import Parameter as P

    from tumble_ros.errors import NodeError
    from tumble_ros.nodes.parameters import refuse_unknown_parameters
    from tumble_ros.runs.messages.qos import DESCRIPTION_QOS
    descriptions = ros.collect(ScenarioDescription, topics.SCENARIO, qos=DESCRIPTION_QOS)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = SimNode(context=ros.context, parameter_overrides=[P('durration', value=3.0)])
    try:
        with pytest.raises(NodeError, match="unknown parameter 'durration'"):
            refuse_unknown_parameters([sim])
        ros.spin_for(0.5)      # the probe only: the refused node is never spun
        assert descriptions == [] and status == []
    finally:
        sim.destroy_node()
    accepted = ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002)
    assert ros.spin_until(lambda: len(descriptions) == 1 and status, 5.0)
    assert descriptions[0].run_id == accepted.run_id


def test_a_node_in_hours_runs_the_defaults_it_was_not_given_in_years(ros):
    """
    time_unit h with no integrator.step, duration or max_step: the Scenario's own defaults.

    The node declared every scenario parameter with its default in years and read them all
    back as given, so with time_unit h it ran integrator.step 1e-4 h (not 1e-4 yr) and a
    duration of 2 h. What it lists (``ros2 param get``) is now the default in its unit.
    """
    sim = ros.start(SimNode, time_unit='h', output_interval=1.0, real_time_factor=0.0,
                    integrator__method='rk4')
    default = Scenario()
    assert sim.scenario.integrator.step == default.integrator.step            # 1e-4 yr
    assert sim.scenario.duration == default.duration                          # 2 yr
    assert sim.scenario.output_interval == pytest.approx(1.0 / 8766.0, rel=1e-15)
    assert sim.get_parameter('integrator.step').value == pytest.approx(0.8766, rel=1e-12)
    assert sim.get_parameter('duration').value == pytest.approx(2.0 * 8766.0, rel=1e-12)
    assert list(sim.get_parameter('omega0').value) == pytest.approx(
        [v / 8766.0 for v in default.omega0], rel=1e-12)                       # rad/h


def test_a_node_in_hours_takes_a_spin_block_beside_its_listed_defaults(ros):
    """The omega0 it lists (the default in rad/h) is no second spin state beside spin.*."""
    from tumble_ros.core import load_scenario, shipped_scenario
    expected = load_scenario(shipped_scenario('tumbling_from_observables'))
    spin = {'spin__mode': 'SAM', 'spin__precession_period': 27.38,
            'spin__rotation_period': 263.0, 'spin__inertia_ratios': [0.61, 0.965],
            'spin__pole': [4.363323129985824, -1.3089969389957472], 'spin__phases': [0.0, 0.0]}
    sim = ros.start(SimNode, time_unit='h', duration=1.0, output_interval=0.5,
                    real_time_factor=0.0, **spin)
    assert sim.scenario.omega0 == expected.omega0 and sim.scenario.inertia == expected.inertia


def test_the_impact_service_takes_and_answers_the_scenarios_time_unit(ros):
    """
    time_unit h: start and duration [h], torque [I rad/h^2], the schedule answered in hours.

    The service read them in years whatever the scenario said: start 12 was refused as past
    the end of a 24-h run (12 yr).
    """
    events = ros.collect(ImpactEvent, topics.IMPACT_EVENTS)
    sim = ros.start(SimNode, time_unit='h', duration=24.0, output_interval=0.5,
                    real_time_factor=0.0, start_paused=True)
    reply = ros.call(ApplyImpact, topics.APPLY_IMPACT, impact_request(
        start=12.0, duration=0.01, torque=Vector3(x=0.0, y=0.0, z=3.0)))
    assert reply.accepted, reply.message
    assert (reply.scheduled_start, reply.scheduled_end) == pytest.approx(
        (12.0, 12.01), rel=1e-12)
    assert reply.message == 'impact 1 scheduled on [12, 12.01] h'
    ros.call(Trigger, topics.RESUME, Trigger.Request())
    assert ros.spin_until(lambda: events, 20.0)
    # (the event is recorded in years: 3 I rad/h^2 for 0.01 h is 0.03 / Iz rad/h)
    assert events[0].delta_omega.z == pytest.approx(3.0 * 0.01 / 1.5 * 8766.0, rel=1e-9)
    assert events[0].start == pytest.approx(12.0 / 8766.0, rel=1e-12)
    assert sim.scenario.time_unit == 'h'


def test_real_time_factor_is_in_the_scenarios_time_unit(ros, monkeypatch):
    """real_time_factor 1 with time_unit h: an hour a wall-clock second (it was a year)."""
    import tumble_ros.nodes.sim as sim_module

    sim = ros.start(SimNode, time_unit='h', duration=24.0, output_interval=0.5,
                    real_time_factor=1.0, start_paused=True)
    sim._pace_origin = (100.0, 0)          # (wall time, sample index) when pacing began
    monkeypatch.setattr(sim_module.time, 'monotonic', lambda: 103.0)
    assert sim._paced_index() == 6         # 3 s later: 3 h, the sample at 3 h (every 0.5 h)

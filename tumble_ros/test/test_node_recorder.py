"""Recording to MCAP: round trip, latched and late topics, SIGTERM and SIGKILL, bringup."""
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from std_msgs.msg import String

from tumble_ros import topics
from tumble_ros.core import load_scenario, simulate, TimeBase
from tumble_ros.io import McapError, read_messages, summarize
from tumble_ros.nodes.bringup import run_bringup
from tumble_ros.nodes.recorder import RecorderNode
from tumble_ros.nodes.sim import SimNode
from viewer_checks import check_timeline

PER_SAMPLE = [topics.in_namespace('/', name) for name in (
    topics.ANGULAR_VELOCITY, topics.ATTITUDE, topics.EULER_ANGLES, topics.CLOCK,
    topics.MODEL_ANGULAR_VELOCITY, topics.ERROR, topics.ERROR_NORM)]
OMEGA_TOPIC = '/' + topics.ANGULAR_VELOCITY


def write_params(tmp_path, extra=''):
    path = tmp_path / 'short.yaml'
    path.write_text('sim:\n  ros__parameters:\n    duration: 0.3\n    output_interval: 0.001\n'
                    '    impacts:\n      start: [0.1]\n      duration: [3.0e-7]\n'
                    '      torque: [0.0, 1.0e6, 0.0]\n'
                    + extra)
    return path


def stamp_ns(msg):
    return TimeBase.stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec)


@pytest.mark.parametrize('executor', ['events', 'single'])
def test_bringup_round_trip_counts_and_values(tmp_path, executor):
    started = time.time_ns()
    params = write_params(tmp_path)
    result = run_bringup(params, output=tmp_path / 'run.mcap', progress=None,
                         executor_name=executor)
    assert result.ok and result.samples == 301
    for topic in PER_SAMPLE:
        assert result.counts[topic] == 301, topic  # nothing lost
    summary = summarize(result.output)
    assert summary.finalised and not summary.truncated and summary.profile == 'ros2'
    assert {t: s.message_count for t, s in summary.topics.items()} == result.counts

    omega = [m.message for m in read_messages(result.output, topics=[OMEGA_TOPIC])]
    t = np.array([TimeBase().to_years(stamp_ns(m)) for m in omega])
    ref = simulate(load_scenario(params), t_eval=t)
    np.testing.assert_array_equal([[m.vector.x, m.vector.y, m.vector.z] for m in omega], ref.omega)
    (event,) = [m.message
                for m in read_messages(result.output, topics=['/' + topics.IMPACT_EVENTS])]
    assert event.delta_omega.y == pytest.approx(0.3, rel=1e-4)

    from rosbags.highlevel import AnyReader

    with AnyReader([result.output]) as reader:
        counts = {}
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
    assert counts == {t: n for t, n in result.counts.items() if n}

    # log time: the sample's stamp (simulated time on the ROS clock); publish time: the wall
    # clock, the publisher's source timestamp ('single') or the receive time ('events' cannot
    # pass MessageInfo), within the run
    records = list(read_messages(result.output, topics=[OMEGA_TOPIC]))
    assert [m.log_time_ns for m in records] == [stamp_ns(m.message) for m in records]
    sent = np.array([m.publish_time_ns for m in records])
    assert np.all((sent >= started) & (sent <= time.time_ns())) and np.all(np.diff(sent) >= 0)


def test_a_live_run_plays_in_simulated_time_at_its_seconds_per_year(tmp_path):
    """10 ROS seconds a year: the 0.3-yr run is a 3-s timeline, whatever the wall clock says."""
    result = run_bringup(write_params(tmp_path, '    seconds_per_year: 10.0\n'),
                         output=tmp_path / 'run.mcap', progress=None)
    assert result.ok and result.samples == 301
    t = check_timeline(result.output, 0.3, 0.001, 10.0)
    assert t.end - t.start == 3_000_000_000
    assert t.rate(OMEGA_TOPIC) == pytest.approx(301 / 3.0)
    (impact,) = t.log_times['/' + topics.IMPACT_EVENTS]
    assert impact == 1_000_003_000          # its end, 0.1 + 3e-7 yr, at 10 s a year


def test_log_time_receive_logs_the_wall_clock(tmp_path):
    started = time.time_ns()
    params = write_params(tmp_path, 'recorder:\n  ros__parameters:\n    log_time: receive\n')
    result = run_bringup(params, output=tmp_path / 'run.mcap', progress=None)
    assert result.ok
    records = list(read_messages(result.output, topics=[OMEGA_TOPIC]))
    logged = np.array([m.log_time_ns for m in records])
    assert np.all((logged >= started) & (logged <= time.time_ns()))
    assert np.all(np.diff(logged) >= 0)


def test_an_unknown_log_time_is_refused_in_one_line(spawn, tmp_path):
    recorder = spawn('recorder', '--ros-args', '-p', 'log_time:=wall', '-p',
                     f'output:={tmp_path / "x.mcap"}')
    assert recorder.wait(60) == 1, recorder.output
    assert "log_time: must be one of sim, receive, got 'wall'" in recorder.output
    assert 'Traceback' not in recorder.output and not (tmp_path / 'x.mcap').exists()


def test_bringup_refuses_an_unknown_executor(tmp_path):
    with pytest.raises(ValueError, match='executor: must be one of events, single'):
        run_bringup(write_params(tmp_path), output=tmp_path / 'x.mcap', progress=None,
                    executor_name='multi')
    assert not (tmp_path / 'x.mcap').exists()


def test_latched_and_late_topics_are_recorded(ros, tmp_path):
    sim = ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002,
                    real_time_factor=0.0)
    ros.spin_for(0.2)
    recorder = ros.start(RecorderNode, output=str(tmp_path / 'late.mcap'),
                         topics=[topics.SCENARIO, topics.STATUS],
                         topic_pattern='^/late', discovery_period=0.05)
    late = ros.probe.create_publisher(String, '/late/news', 10)
    assert ros.spin_until(lambda: recorder.counts.get('/late/news') is not None, 5.0)
    late.publish(String(data='hello'))
    assert ros.spin_until(lambda: recorder.counts.get('/late/news') == 1, 5.0)
    assert ros.spin_until(lambda: recorder.counts.get('/' + topics.SCENARIO) == 1
                          and recorder.counts.get('/' + topics.STATUS) == 1, 5.0)
    assert OMEGA_TOPIC not in recorder.counts  # not asked for
    recorder.close()
    got = {m.topic: m.message for m in read_messages(tmp_path / 'late.mcap')}
    assert got['/late/news'].data == 'hello' and got['/' + topics.SCENARIO].revision == 0
    assert sim.state == 1  # still paused: the latched messages came from before the recorder


def test_a_topic_pattern_adds_to_the_default_topics(ros, tmp_path):
    """
    `-p topic_pattern:=...` records the tumble topics too (it replaced them).

    analyze refused such a file: it held only the matched topics.
    """
    ros.start(SimNode, start_paused=True, duration=0.2, output_interval=0.002,
              real_time_factor=0.0)
    recorder = ros.start(RecorderNode, output=str(tmp_path / 'pattern.mcap'),
                         topic_pattern='^/late', discovery_period=0.05)
    late = ros.probe.create_publisher(String, '/late/news', 10)
    assert ros.spin_until(lambda: recorder.counts.get('/late/news') is not None
                          and recorder.counts.get('/' + topics.SCENARIO) == 1,
                          5.0), recorder.counts
    assert OMEGA_TOPIC in recorder.counts and '/clock' in recorder.counts, recorder.counts
    late.publish(String(data='hello'))
    assert ros.spin_until(lambda: recorder.counts.get('/late/news') == 1, 5.0)
    recorder.close()


def recorder_process(path, *extra):
    exe = (Path(os.environ.get('AMENT_PREFIX_PATH', '').split(':')[0]) / 'lib' / 'tumble_ros'
           / 'recorder')
    from ament_index_python.packages import get_package_prefix

    exe = Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / 'recorder'
    return subprocess.Popen([str(exe), '--ros-args', '-p', f'output:={path}', *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def run_sim_until_recorded(ros, path, n_samples):
    """Publish n samples from an in-process sim, paced on the recorder in the other process."""
    sim = ros.start(SimNode, duration=(n_samples - 1) * 1e-3, output_interval=1e-3,
                    real_time_factor=0.0,
                    min_consumers=1)
    assert ros.spin_until(lambda: sim.published_samples == n_samples, 60.0), sim.published_samples
    return sim


def test_sigterm_finalises_the_file(ros, tmp_path):
    path = tmp_path / 'term.mcap'
    proc = recorder_process(path)
    try:
        run_sim_until_recorded(ros, path, 500)
        ros.spin_for(0.5)
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, out
    summary = summarize(path)
    assert summary.finalised
    assert summary.topics[OMEGA_TOPIC].message_count == 500


def test_sigkill_loses_at_most_the_last_chunk(ros, tmp_path):
    """
    Survive a SIGKILL with what the recorder flushed (by chunk_seconds, unasked).

    Event-based: the test waits until the file on disk holds every sample, then kills; the
    writer's time bound itself is proven in test_io_durability.py.
    """
    path = tmp_path / 'kill.mcap'
    proc = recorder_process(path, '-p', 'chunk_seconds:=0.2', '-p', 'chunk_bytes:=20000')

    def on_disk():
        try:
            return len(list(read_messages(path, topics=[OMEGA_TOPIC])))
        except McapError:  # nothing flushed yet
            return 0

    try:
        sim = run_sim_until_recorded(ros, path, 2000)
        assert ros.spin_until(lambda: on_disk() == sim.published_samples, 30.0), on_disk()
        proc.kill()
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    summary = summarize(path)
    assert not summary.finalised
    stamps = [stamp_ns(m.message) for m in read_messages(path, topics=[OMEGA_TOPIC])]
    assert stamps == [k * 1_000_000 for k in range(sim.published_samples)]


def test_a_stopped_comparator_no_longer_holds_the_recorders_progress(ros, tmp_path, monkeypatch):
    """
    A comparator that stops mid-run does not stall the simulator through the recorder.

    The recorder's progress is the oldest latest stamp of its per-sample topics, the
    comparator's included: once the comparator's publishers are gone its topics no longer
    count. STALE_TOPIC (the rescue for a topic that just goes silent) is made endless here, so
    the simulator goes on only if the recorder saw that they left. Before: it stalled until
    STALE_TOPIC (2.0 s on a loaded machine, /clock paused as long), here for good.
    """
    from tumble_ros.nodes import recorder as recorder_module
    from tumble_ros.nodes.comparator import ComparatorNode
    from tumble_ros.nodes.runner import close_node
    from tumble_ros.nodes.sim import WINDOW

    monkeypatch.setattr(recorder_module, 'STALE_TOPIC', 1e9)
    sim = ros.start(SimNode, duration=20.0, output_interval=1e-3, real_time_factor=0.0,
                    min_consumers=2)
    comparator = ros.start(ComparatorNode)
    recorder = ros.start(RecorderNode, output=str(tmp_path / 'left.mcap'))
    error_topic = '/' + topics.ERROR
    assert ros.spin_until(lambda: recorder.counts.get(error_topic, 0) > 300, 60.0), \
        (sim.published_samples, recorder.counts)
    ros.executor.remove_node(comparator)
    ros.nodes.remove(comparator)
    close_node(comparator)              # goodbye, then its publishers go (nodes.runner)
    at_stop = sim.published_samples
    # stalled, it would publish at most sim.WINDOW (40) samples beyond the recorder's progress
    assert ros.spin_until(lambda: sim.published_samples > at_stop + 10 * WINDOW, 60.0), \
        f'the simulator stalled at {sim.published_samples} samples ({at_stop} at the stop)'
    recorder.close()


@pytest.mark.parametrize('kind', ['msg', 'srv'])
def test_an_advertised_type_of_a_module_that_is_no_interface_package_is_not_imported(
        tmp_path, monkeypatch, kind):
    """
    A foreign participant's type name cannot make the recorder import an arbitrary module.

    ``probe_pkg`` is an importable top-level package (its import leaves a mark) with a
    ``msg``/``srv`` submodule, but no interface package of the ament index: it is refused
    before any import. Before, ``_import_type`` imported ``probe_pkg.msg`` (and so
    ``probe_pkg``) for any advertised type ``probe_pkg/msg/X`` on a recorded topic.
    """
    from tumble_ros.nodes import recorder

    package = tmp_path / 'probe_pkg'
    (package / kind).mkdir(parents=True)
    (package / '__init__.py').write_text("import os\nos.environ['PROBE_PKG_IMPORTED'] = '1'\n")
    (package / kind / '__init__.py').write_text('X = object\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv('PROBE_PKG_IMPORTED', raising=False)
    with pytest.raises(recorder.NotAnInterface, match='probe_pkg'):
        recorder._import_type(f'probe_pkg/{kind}/X')
    assert 'probe_pkg' not in sys.modules
    assert 'PROBE_PKG_IMPORTED' not in os.environ
    for bad in ('os/msg/path', 'probe_pkg/__init__/X', 'a/b/c/d', '../x/msg/Y'):
        with pytest.raises(recorder.NotAnInterface):
            recorder._import_type(bad)
    # interface packages still import: messages, service events
    assert recorder._import_type('geometry_msgs/msg/Vector3Stamped').__name__ == 'Vector3Stamped'
    assert recorder._import_type('std_srvs/srv/Trigger_Event').__name__ == 'Trigger_Event'
    with pytest.raises(recorder.NotAnInterface):
        recorder._import_type('geometry_msgs/msg/NoSuchType')


@pytest.mark.parametrize('ghost', [None, 'goes-silent', 'never-appears'],
                         ids=['appears', 'consumer-goes-silent', 'never-appears'])
def test_a_consumers_announced_topics_hold_the_recorders_progress_until_subscribed(
        ros, tmp_path, ghost):
    """
    A comparator announces its per-sample outputs (``ConsumerProgress.produces``).

    Until the recorder has subscribed them its progress does not advance, so the simulator
    cannot run past their history while the recorder's graph does not show them yet (under CPU
    contention the comparator's 3 outputs lost 1179 of 10,000 samples that way). The hold
    ends when the announcing consumer goes silent (CONSUMER_TIMEOUT), or, while it lives, once
    the announced topic has not appeared for ``wait`` (30 s by default; 4 s here).
    """
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import Vector3Stamped
    from tumble_ros.nodes.progress import PROGRESS_QOS, PROGRESS_TOPIC
    from tumble_ros.runs.messages.qos import STATE_QOS
    from tumble_ros_interfaces.msg import ConsumerProgress

    recorder = ros.start(RecorderNode, output=str(tmp_path / 'announced.mcap'),
                         topics=[topics.ANGULAR_VELOCITY], topic_pattern='^/late',
                         discovery_period=15.0)
    recorder._produced.wait = 4.0
    reports = ros.collect(ConsumerProgress, PROGRESS_TOPIC, qos=PROGRESS_QOS)
    omega = ros.probe.create_publisher(Vector3Stamped, OMEGA_TOPIC, STATE_QOS)
    announce = ros.probe.create_publisher(ConsumerProgress, PROGRESS_TOPIC, PROGRESS_QOS)

    def recorder_ns():
        mine = [r for r in reports if r.consumer == '/recorder' and r.last_stamp.sec >= 0]
        return mine[-1].last_stamp.sec * 10**9 + mine[-1].last_stamp.nanosec if mine else None

    def publish_sample(k):
        msg = Vector3Stamped()
        msg.header.stamp = Time(sec=0, nanosec=k * 1_000_000)
        omega.publish(msg)

    for k in range(5):
        publish_sample(k)
    assert ros.spin_until(lambda: recorder_ns() == 4_000_000, 5.0), recorder.counts

    def announce_once():
        announce.publish(ConsumerProgress(consumer='/comparator', active=True,
                                          last_stamp=Time(sec=0), produces=['/late/error']))

    for _ in range(3):     # a comparator announces its output, not on the graph yet
        announce_once()
        ros.spin_for(0.1)
    for k in range(5, 10):
        publish_sample(k)
    ros.spin_for(1.0)
    assert recorder_ns() == 4_000_000      # held: /late/error is announced, not subscribed
    assert recorder.counts.get(OMEGA_TOPIC) == 10
    if ghost:    # never published: the wait is bounded
        for k in range(10, 40):        # the samples go on meanwhile (up to 6 s)
            publish_sample(k)
            if ghost == 'never-appears':   # the consumer lives on, announcing
                announce_once()
            ros.spin_for(0.2)
            if k == 11:                # 1.4 s after the last announcement: still held
                assert recorder_ns() == 4_000_000
            elif k > 11 and (recorder_ns() or 0) > 9_000_000:
                break                  # released (before the 6 s are up)
        assert recorder_ns() is not None and recorder_ns() > 9_000_000, recorder_ns()
    else:
        ros.probe.create_publisher(Vector3Stamped, '/late/error', STATE_QOS)
        assert ros.spin_until(lambda: recorder.counts.get('/late/error') is not None, 5.0)
        assert ros.spin_until(lambda: recorder_ns() == 9_000_000, 5.0), recorder_ns()
    recorder.close()

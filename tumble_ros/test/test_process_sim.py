"""The `sim` executable as its own process: params file, messages across processes, SIGINT."""
import os
from pathlib import Path
import signal
import subprocess

from geometry_msgs.msg import Vector3Stamped
import pytest

from tumble_ros import topics
from tumble_ros_interfaces.msg import SimStatus

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def sim_executable() -> str:
    """Where `ros2 run tumble_ros sim` finds it: <prefix>/lib/tumble_ros/sim."""
    from ament_index_python.packages import get_package_prefix

    path = Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / 'sim'
    assert path.is_file() and os.access(path, os.X_OK), f'{path} is not installed (make setup)'
    return str(path)


@pytest.fixture
def process():
    started = []

    def start(*args, env=None):
        p = subprocess.Popen([sim_executable(), *args], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, env=env)
        started.append(p)
        return p

    yield start
    for p in started:
        if p.poll() is None:
            p.kill()
        p.wait(timeout=10)


def test_sim_process_publishes_and_exits_cleanly_on_sigint(ros, process):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = process('--ros-args', '--params-file', str(CONFIG / 'fig4.yaml'), '-p',
                  'real_time_factor:=0.05')
    # status and angular_velocity are matched separately across processes: wait for both
    assert ros.spin_until(lambda: len(omega) >= 20 and status, 30.0), (sim.poll(), len(omega))
    assert status[0].state == SimStatus.RUNNING
    assert omega[0].header.frame_id == topics.FRAME_BODY
    sim.send_signal(signal.SIGINT)
    out, _ = sim.communicate(timeout=20)
    assert sim.returncode == 0, out
    assert 'simulating 2 yr with dop853' in out


def test_sim_process_refuses_invalid_parameters_with_a_reason(process):
    sim = process('--ros-args', '-p', 'inertia:=[1.0, 1.0, 4.0]')
    out, _ = sim.communicate(timeout=30)
    assert sim.returncode == 1
    assert 'inertia' in out and 'not physically realisable' in out
    assert 'Traceback' not in out


@pytest.mark.parametrize('executor', ['single', 'events'])
def test_sim_process_runs_in_the_chosen_executor(ros, process, executor):
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    sim = process('--ros-args', '-p', 'real_time_factor:=0.05',
                  env=dict(os.environ, TUMBLE_ROS_EXECUTOR=executor))
    assert ros.spin_until(lambda: len(omega) >= 5, 30.0), sim.poll()
    sim.send_signal(signal.SIGINT)
    out, _ = sim.communicate(timeout=20)
    assert sim.returncode == 0, out


def test_an_unknown_executor_is_refused_with_a_reason(process):
    sim = process(env=dict(os.environ, TUMBLE_ROS_EXECUTOR='multi'))
    out, _ = sim.communicate(timeout=30)
    assert sim.returncode == 1
    assert "TUMBLE_ROS_EXECUTOR='multi': must be one of ['events', 'single']" in out
    assert 'Traceback' not in out


def test_sim_process_paces_on_a_consumer_in_another_process(ros, process):
    from tumble_ros.core import TimeBase
    from tumble_ros.nodes.progress import ProgressReporter
    from tumble_ros.runs.messages.qos import STATE_QOS

    reporter = ProgressReporter(ros.probe)
    got = []

    def on_omega(msg):
        got.append(TimeBase.stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec))
        reporter.mark(got[-1])

    ros.probe.create_subscription(Vector3Stamped, topics.ANGULAR_VELOCITY, on_omega, STATE_QOS)
    sim = process('--ros-args', '-p', 'duration:=0.5', '-p', 'output_interval:=0.0001',
                  '-p', 'real_time_factor:=0.0', '-p', 'min_consumers:=1')
    assert ros.spin_until(lambda: len(got) == 5001, 60.0), (len(got), sim.poll())
    assert got == [k * 100_000 for k in range(5001)]
    sim.send_signal(signal.SIGINT)
    sim.communicate(timeout=20)
    assert sim.returncode == 0

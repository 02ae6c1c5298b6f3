"""
Real use, process by process: concurrent runs, signals, consumers that leave, disk errors.

Every process runs in the test's DDS domain (conftest.py) and its process group is killed when
the test ends (the ``spawn`` fixture).
"""
import os
from pathlib import Path
import resource
import signal
import time

from builtin_interfaces.msg import Time
import pytest
from rosgraph_msgs.msg import Clock

from tumble_ros import topics
from tumble_ros.core import TimeBase
from tumble_ros.io import McapWriter, read_messages, summarize
from tumble_ros_interfaces.msg import SimStatus

CONFIG = Path(__file__).resolve().parents[1] / 'config'
#: Generous bound for a process to do a short job on a loaded 2-core machine [s].
SLOW = 120.0


def stamps(path, topic='/' + topics.ANGULAR_VELOCITY):
    return [TimeBase.stamp_ns(m.message.header.stamp.sec, m.message.header.stamp.nanosec)
            for m in read_messages(path, topics=[topic])]


def test_two_bringups_at_once_each_record_only_their_own_samples(ros, spawn, tmp_path):
    """
    Two bringups at once each record only their own samples.

    Same domain, same topics: each run is isolated (discovery off), and a foreign /clock
    published meanwhile by a third party reaches neither file.
    """
    runs = {name: spawn('bringup', CONFIG / f'{name}.yaml', '--output', tmp_path / f'{name}.mcap',
                        '--quiet')
            for name in ('fig5', 'fig10')}
    foreign = ros.probe.create_publisher(Clock, topics.CLOCK, 10)
    deadline = time.monotonic() + SLOW
    while any(p.popen.poll() is None for p in runs.values()) and time.monotonic() < deadline:
        foreign.publish(Clock(clock=Time(sec=999_999)))
        ros.spin_for(0.01)
    for name, process in runs.items():
        assert process.wait(10) == 0, process.output
        path = tmp_path / f'{name}.mcap'
        # 1001 samples, each once
        assert stamps(path) == [k * 2_000_000 for k in range(1001)], name
        clock = [m.message.clock.sec for m in read_messages(path, topics=[topics.CLOCK])]
        assert clock and max(clock) <= 2, name  # its own /clock only, none of the foreign one
    events_topic = '/' + topics.IMPACT_EVENTS
    events = [m.message for m in read_messages(tmp_path / 'fig10.mcap', topics=[events_topic])]
    assert len(events) == 1
    assert list(read_messages(tmp_path / 'fig5.mcap', topics=[events_topic])) == []


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_stops_bringup_with_a_finalised_file_and_a_summary(spawn, tmp_path, signum):
    output = tmp_path / 'long.mcap'
    run = spawn('bringup', '--output', output, '--ros-args', '-p', 'duration:=400.0')
    assert run.wait_for('samples/s', SLOW), run.output  # running, progress shown
    run.signal(signum)
    assert run.wait(30) == 128 + signum, run.output
    assert f'stopped by {signal.Signals(signum).name}' in run.output
    assert 'Traceback' not in run.output
    summary = summarize(output)
    assert summary.finalised
    omega_topic = '/' + topics.ANGULAR_VELOCITY
    n = summary.topics[omega_topic].message_count
    assert 0 < n < 200_001  # stopped early, what was received is in
    # the summary's count
    assert f'{omega_topic} {n:>{40 - len(omega_topic) + 8}d}' in run.output


def test_a_second_signal_during_shutdown_is_absorbed(spawn, tmp_path):
    """
    A second signal during shutdown is absorbed.

    ros2 launch sends Ctrl-C twice (the process group's and its own): no traceback, exit 0,
    the recording finalised.
    """
    output = tmp_path / 'rec.mcap'
    sim = spawn('sim', '--ros-args', '-p', 'duration:=100.0', '-p', 'real_time_factor:=1.0')
    recorder = spawn('recorder', '--ros-args', '-p', f'output:={output}')
    comparator = spawn('comparator')
    assert recorder.wait_for(f'recording /{topics.ANGULAR_VELOCITY}', SLOW), recorder.output
    assert comparator.wait_for('anchored', SLOW), comparator.output
    for process in (sim, recorder, comparator):
        process.signal(signal.SIGINT)
        time.sleep(0.005)
        process.signal(signal.SIGINT)
    for process in (sim, recorder, comparator):
        assert process.wait(30) == 0, process.output
        for noise in ('Traceback', 'KeyboardInterrupt', 'Failed to publish log message',
                      'Future.__del__'):
            assert noise not in process.output, (process.name, process.output)
    assert summarize(output).finalised


def test_a_consumer_stopped_cleanly_says_goodbye(ros, spawn):
    """The simulator hears the goodbye (no 'silent for' timeout, no freeze)."""
    sim = spawn('sim', '--ros-args', '-p', 'duration:=50.0', '-p', 'real_time_factor:=1.0', '-p',
                'min_consumers:=1')
    comparator = spawn('comparator')
    assert sim.wait_for('consumer /comparator registered', SLOW), sim.output
    comparator.signal(signal.SIGINT)
    assert comparator.wait(30) == 0, comparator.output
    assert sim.wait_for('consumer /comparator left', 10.0), sim.output
    assert 'silent for' not in sim.output


def test_a_killed_consumer_is_dropped_even_with_min_consumers(ros, spawn):
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = spawn('sim', '--ros-args', '-p', 'duration:=8.0', '-p', 'real_time_factor:=2.0', '-p',
                'min_consumers:=1')
    comparator = spawn('comparator')
    assert sim.wait_for('consumer /comparator registered', SLOW), sim.output
    comparator.kill_group()
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED,
                          60.0), sim.output
    assert any('silent for' in s.message for s in status)  # said on status, not only in the log


def test_a_full_disk_stops_the_recording_and_keeps_what_was_flushed(spawn, tmp_path):
    """
    A full disk stops the recording and keeps what was flushed.

    A file size limit (EFBIG, like ENOSPC) during a bringup: one ERROR line, exit 1, and the
    chunks flushed before the failure read back.
    """
    output = tmp_path / 'full.mcap'
    limit = 200_000

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    scenario = tmp_path / 'long.yaml'
    scenario.write_text('sim:\n  ros__parameters:\n    duration: 100.0\n'
                        'recorder:\n  ros__parameters:\n    chunk_bytes: 20000\n')
    run = spawn('bringup', scenario, '--output', output, '--quiet', preexec_fn=small_files)
    assert run.wait(SLOW) == 1, run.output
    assert 'ERROR: recording stopped: cannot write' in run.output
    assert 'Traceback' not in run.output
    kept = stamps(output)
    # a readable prefix, in order
    assert kept and kept == [k * 2_000_000 for k in range(len(kept))]


def test_sim_with_use_sim_time_still_runs(ros, spawn):
    """The simulator is the clock source: use_sim_time must not freeze it."""
    from geometry_msgs.msg import Vector3Stamped

    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    spawn('sim', '--ros-args', '-p', 'use_sim_time:=true', '-p', 'duration:=0.2', '-p',
          'real_time_factor:=0.0')
    assert ros.spin_until(lambda: len(omega) == 101, SLOW), len(omega)


@pytest.mark.parametrize('args, expected', [
    (['-p', 'durration:=3.0'], "unknown parameter 'durration' (did you mean 'duration'?)"),
    (['-p', 'integrator.methd:=rk4'], "did you mean 'integrator.method'?"),
])
def test_sim_refuses_a_misspelt_parameter(spawn, args, expected):
    sim = spawn('sim', '--ros-args', *args)
    assert sim.wait(SLOW) == 1, sim.output
    assert expected in sim.output and 'Traceback' not in sim.output


def test_sim_refuses_a_binary_params_file_in_one_line(spawn, tmp_path):
    path = tmp_path / 'binary.yaml'
    path.write_bytes(bytes(range(256)) * 4)
    sim = spawn('sim', '--ros-args', '--params-file', path)
    assert sim.wait(SLOW) == 1, sim.output
    (line,) = sim.output.strip().splitlines()
    assert line.startswith(f'sim: params file {path}: cannot read it as text: it holds binary '
                           'data')


# -- edges: help, signals at start-up, closed pipes, misplaced options, rcl's refusals ----------
def test_sighup_stops_the_nodes_like_sigterm(spawn, tmp_path):
    """A closed terminal (SIGHUP): exit 0, the recording finalised, no traceback."""
    output = tmp_path / 'rec.mcap'
    sim = spawn('sim', '--ros-args', '-p', 'duration:=100.0', '-p', 'real_time_factor:=1.0',
                module=True)
    recorder = spawn('recorder', '--ros-args', '-p', f'output:={output}', module=True)
    assert recorder.wait_for(f'recording /{topics.ANGULAR_VELOCITY}', SLOW), recorder.output
    for process in (sim, recorder):
        process.signal(signal.SIGHUP)
    for process in (sim, recorder):
        assert process.wait(30) == 0, process.output
        assert 'Traceback' not in process.output, process.output
    assert summarize(output).finalised


@pytest.mark.parametrize('module', [True, False], ids=['python -m tumble_ros', 'ros2 run'])
@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_the_node_is_still_importing_exits_quietly(spawn, module, signum):
    """Importing the simulator takes seconds (rclpy, numba): a signal then ends it with 0."""
    sim = spawn('sim', module=module)
    time.sleep(0.3)   # the interpreter is up, the import of rclpy/numba far from done
    sim.signal(signum)
    assert sim.wait(SLOW) == 0, sim.output
    assert 'Traceback' not in sim.output and 'KeyboardInterrupt' not in sim.output, sim.output


def test_help_on_every_executable_prints_its_usage_and_exits_0(spawn):
    from tumble_ros.__main__ import EXECUTABLES

    runs = {name: spawn(name, '--help', module=True) for name in EXECUTABLES}
    main = spawn('', '--help', module=True)
    for name, process in runs.items():
        assert process.wait(SLOW) == 0, (name, process.output)
        assert process.output.lower().startswith('usage:'), (name, process.output)
        assert 'simulating' not in process.output, name     # nothing was started
    assert main.wait(SLOW) == 0, main.output
    assert all(name in main.output for name in EXECUTABLES), main.output


def test_help_without_docstrings_prints_the_usage_line_and_exits_0():
    """``python -OO`` strips the modules' docstrings: ``--help`` still prints its usage."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, '-OO', '-m', 'tumble_ros', 'recorder', '--help'],
                          capture_output=True, text=True, timeout=SLOW)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith('usage: recorder'), done.stdout
    assert 'Traceback' not in done.stderr, done.stderr


def test_every_installed_executable_is_one_of_the_module_entry():
    """setup.py's console scripts and ``python -m tumble_ros``'s executables are the same."""
    from importlib.metadata import distribution

    from tumble_ros.__main__ import EXECUTABLES

    scripts = {ep.name: ep.value for ep in distribution('tumble_ros').entry_points
               if ep.group == 'console_scripts'}
    assert sorted(scripts) == sorted(EXECUTABLES)
    assert set(scripts.values()) == {'tumble_ros.__main__:entry'}


def test_a_closed_pipe_ends_bringup_quietly_with_the_recording_finalised(tmp_path):
    """``bringup | head -1``: stdout's reader is gone; exit 141 (SIGPIPE), no traceback."""
    import os
    import subprocess
    import sys

    output = tmp_path / 'piped.mcap'
    read, write = os.pipe()
    os.close(read)          # the reader has gone before anything is written
    with open(tmp_path / 'stderr.log', 'w') as err:
        run = subprocess.run(
            [sys.executable, '-m', 'tumble_ros', 'bringup', '--output', output, '--quiet',
             '--ros-args', '-p', 'duration:=0.2'], stdout=write, stderr=err,
            stdin=subprocess.DEVNULL, timeout=SLOW, start_new_session=True)
    os.close(write)
    stderr = (tmp_path / 'stderr.log').read_text()
    assert run.returncode == 141, stderr
    assert 'Traceback' not in stderr and 'BrokenPipeError' not in stderr, stderr
    assert summarize(output).finalised


@pytest.mark.parametrize('module, args', [
    ('tumble_ros.cli.ensemble', ['fig9.yaml', '--bodies', '30', '--duration', '0.01']),
    ('tumble_ros.cli.encounter', ['apophis_2029.yaml', '--bodies', '4', '--inertia-draws', '1']),
    ('tumble_ros.analysis', [Path(__file__).resolve().parent / 'data' / 'golden.mcap']),
], ids=['ensemble', 'encounter', 'analysis'])
def test_a_closed_pipe_ends_each_commands_module_entry_quietly(tmp_path, module, args):
    """
    ``python -m tumble_ros.cli.ensemble ... | head -1``: exit 141, no traceback.

    The documented module entries called ``main`` directly and printed a BrokenPipeError
    traceback (exit 1); the installed executables (``python -m tumble_ros ensemble``) did not.
    """
    import subprocess
    import sys

    args = [CONFIG / a if str(a).endswith('.yaml') else a for a in args]
    read, write = os.pipe()
    os.close(read)          # the reader has gone before anything is written
    with open(tmp_path / 'stderr.log', 'w') as err:
        run = subprocess.run([sys.executable, '-m', module, *map(str, args), '--quiet'],
                             stdout=write, stderr=err, stdin=subprocess.DEVNULL, timeout=SLOW,
                             start_new_session=True, cwd=tmp_path)
    os.close(write)
    stderr = (tmp_path / 'stderr.log').read_text()
    assert run.returncode == 141, stderr
    assert 'Traceback' not in stderr and 'BrokenPipeError' not in stderr, stderr


@pytest.mark.parametrize('name', ['sim', 'bringup'])
def test_an_option_after_ros_args_is_one_line_naming_it(spawn, name):
    run = spawn(name, '--ros-args', '-p', 'duration:=0.1', '--output', 'x.mcap', module=True)
    assert run.wait(SLOW) == 1, run.output
    (line,) = run.output.strip().splitlines()
    assert 'unknown option after --ros-args: --output x.mcap' in line, line


@pytest.mark.parametrize('name', ['sim', 'bringup'])
@pytest.mark.parametrize('content, reason', [
    ('/**/sim:\n  ros__parameters: &p\n    duration: 1.0\nsim:\n  ros__parameters: *p\n',
     'Will not support aliasing at line'),
])
def test_a_params_file_rcl_cannot_parse_is_one_line_with_its_reason(spawn, tmp_path, name,
                                                                    content, reason):
    """Valid YAML that rcl's parser refuses (an alias): rcl's reason, no RCLError traceback."""
    path = tmp_path / 'aliased.yaml'
    path.write_text(content)
    run = spawn(name, '--ros-args', '--params-file', path, module=True)
    assert run.wait(SLOW) == 1, run.output
    (line,) = run.output.strip().splitlines()
    assert f'params file {path}: rcl cannot parse it: {reason}' in line, line


def test_a_shipped_scenario_runs_by_its_name_and_an_unknown_name_lists_them(spawn, tmp_path):
    output = tmp_path / 'fig10.mcap'
    known = spawn('bringup', 'fig10', '--offline', '--quiet', '--output', output, module=True)
    unknown = spawn('bringup', 'fig11', module=True)
    assert unknown.wait(SLOW) == 1, unknown.output
    (line,) = unknown.output.strip().splitlines()
    assert line.startswith('ERROR: no scenario file fig11 (shipped scenarios: ')
    assert 'fig10' in line
    assert known.wait(SLOW) == 0, known.output
    events = list(read_messages(output, topics=['/' + topics.IMPACT_EVENTS]))
    assert len(events) == 1   # fig10's impact: the shipped file was run


@pytest.mark.parametrize('delay', [0.0, 0.5, 1.5])
def test_a_signal_stops_an_offline_run_at_any_moment(spawn, tmp_path, delay):
    """
    SIGTERM at several moments of an offline Fig 9 run: served, the file finalised.

    The Fig 9 scenario over 20,000 yr (2,000,001 samples): the 2000-yr run itself ends ~1.6 s
    after its first progress line on an idle machine, before the latest signal here arrived.
    """
    output = tmp_path / 'fig9.mcap'
    scenario = tmp_path / 'fig9_long.yaml'
    text = (CONFIG / 'fig9.yaml').read_text()
    assert 'duration: 2000.0' in text
    scenario.write_text(text.replace('duration: 2000.0', 'duration: 20000.0'))
    run = spawn('bringup', scenario, '--offline', '--output', output, module=True)
    assert run.wait_for('samples/s', SLOW), run.output
    time.sleep(delay)
    run.signal(signal.SIGTERM)
    assert run.wait(30) == 128 + signal.SIGTERM, run.output
    assert 'stopped by SIGTERM' in run.output and 'Traceback' not in run.output
    assert summarize(output).finalised


def test_a_refused_parameter_is_not_announced_as_a_simulation(spawn):
    """Validate first, then announce: no 'simulating 2 yr' line before the refusal."""
    sim = spawn('sim', '--ros-args', '-p', 'durration:=3.0', module=True)
    assert sim.wait(SLOW) == 1, sim.output
    assert 'unknown parameter' in sim.output and 'simulating' not in sim.output, sim.output


def test_the_bare_sim_says_when_it_finishes(spawn):
    """One line at FINISHED: samples and wall time."""
    sim = spawn('sim', '--ros-args', '-p', 'duration:=0.02', '-p', 'real_time_factor:=0.0',
                module=True)
    assert sim.wait_for('samples in', SLOW), sim.output
    sim.signal(signal.SIGINT)
    assert sim.wait(30) == 0, sim.output
    assert 'finished at t = 0.02 yr: 11 samples in ' in sim.output, sim.output
    assert sim.output.index('simulating 0.02 yr') < sim.output.index('finished at t')


def test_only_the_dds_memory_of_dead_processes_of_this_session_is_removed():
    """processes.remove_dead_dds_segments, on fake Fast DDS segments in /dev/shm."""
    import fcntl
    import os
    import uuid

    from processes import remove_dead_dds_segments, SHM, SHM_MIN_AGE

    tag = uuid.uuid4().hex[:12]
    now = time.time()
    since = now - 100.0
    made = {}
    for name, age in (('dead', 10.0), ('alive', 10.0), ('young', 0.0), ('before', 200.0)):
        segment = SHM / f'fastrtps_{tag}{name}'
        lock = SHM / f'fastrtps_{tag}{name}_el'
        for path in (segment, lock):
            path.write_bytes(b'')
            os.utime(path, (now - age, now - age))
        made[name] = (segment, lock)
    port = (SHM / f'fastrtps_port{tag}', SHM / f'fastrtps_port{tag}_el')
    for path in port:
        path.write_bytes(b'')
        os.utime(path, (now - 10.0, now - 10.0))
    held = os.open(made['alive'][1], os.O_RDWR)
    fcntl.flock(held, fcntl.LOCK_SH)     # what a live participant holds
    try:
        assert SHM_MIN_AGE < 10.0
        remove_dead_dds_segments(since)
        left = {name for name, (segment, lock) in made.items() if segment.exists()}
        assert left == {'alive', 'young', 'before'}
        assert not made['dead'][1].exists() and all(p.exists() for p in port)
    finally:
        os.close(held)
        for path in [*[p for pair in made.values() for p in pair], *port]:
            path.unlink(missing_ok=True)


def test_the_three_nodes_beside_a_cpu_hog_lose_nothing_on_the_reliable_topics(ros, spawn,
                                                                              tmp_path):
    """
    sim, recorder and comparator as processes, two CPU hogs beside them: nothing lost.

    Every reliable per-sample topic (the simulator's and the comparator's) holds each of the
    N samples once; ``/clock`` (best effort) may miss some, and the recorder says how many
    (what the file shows). The comparator starts after the recorder has subscribed to the
    simulator's topics, and the recorder looks for new topics only every 15 s
    (``discovery_period``): before, the comparator's topics were subscribed up to 15 s into
    the run and their first samples, beyond the 1000 their history replays, were lost.
    """
    import subprocess
    import sys

    from tumble_ros.io import read_columns

    n = 4_000    # four times the 1000 samples a late subscriber's history would replay
    interval = 1e-3
    output = tmp_path / 'loaded.mcap'
    hogs = [subprocess.Popen([sys.executable, '-c', 'while True: pass'],
                             start_new_session=True) for _ in range(2)]
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    try:
        sim = spawn('sim', '--ros-args', '-p', f'duration:={(n - 1) * interval!r}', '-p',
                    f'output_interval:={interval!r}', '-p', 'real_time_factor:=0.0',
                    '-p', 'min_consumers:=2')
        recorder = spawn('recorder', '--ros-args', '-p', f'output:={output}',
                         '-p', 'discovery_period:=15.0')
        assert recorder.wait_for(f'recording /{topics.EULER_ANGLES}', SLOW), recorder.output
        spawn('comparator')
        assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED,
                              SLOW), sim.output
        ros.spin_for(2.0)   # the last samples reach the recorder (it is paced: few are left)
        recorder.signal(signal.SIGINT)
        assert recorder.wait(30) == 0, recorder.output
    finally:
        for hog in hogs:
            os.killpg(hog.pid, signal.SIGKILL)
            hog.wait()
    reliable = ['/' + t for t in topics.PER_SAMPLE]
    columns, _ = read_columns(output, reliable + [topics.CLOCK])
    expected = [k * 1_000_000 for k in range(n)]
    lost = {}
    for topic in reliable:
        c = columns[topic].columns if topic in columns else None
        got = ([] if c is None else
               (c['header.stamp.sec'].astype('int64') * 1_000_000_000
                + c['header.stamp.nanosec'].astype('int64')).tolist())
        if got != expected:
            lost[topic] = len(set(expected) - set(got))
    assert not lost, (f'samples lost per reliable topic: {lost}\n'
                      + recorder.output + sim.output)
    clock = len(columns[topics.CLOCK]) if topics.CLOCK in columns else 0
    assert f'{topics.CLOCK}: {n - clock} of {n} samples missed' in recorder.output


# -- orbits: impossible geometry refused at start-up, a runaway stopped as DIVERGED -----------
def params_file(path, params: dict):
    """Write ``params`` (dotted names) as the ros__parameters of a sim params file."""
    import yaml

    nested: dict = {}
    for name, value in params.items():
        *parents, leaf = name.split('.')
        node = nested
        for parent in parents:
            node = node.setdefault(parent, {})
        node[leaf] = value
    path.write_text(yaml.safe_dump({'/**/sim': {'ros__parameters': nested}}))
    return path


SUN_KEPLER = {'orbit_rate': 0.0, 'orbit.kind': 'kepler', 'orbit.gm': 1.3271244e11,
              'orbit.a': 1.496e8}
EARTH_FLYBY = {'orbit_rate': 0.0, 'orbit.kind': 'flyby', 'orbit.gm': 398600.4418,
               'orbit.perigee': 38000.0, 'orbit.v_inf': 5.8}


@pytest.mark.parametrize('params, expected', [
    # a pericentre of 150 km from the Sun's centre: accepted, it ran for minutes
    ({**SUN_KEPLER, 'orbit.e': 1.000001}, ['orbit.e: the pericentre a |1 - e| = 149.6 km',
                                           'radius 695700.0 km', 'got 1.000001']),
    ({**EARTH_FLYBY, 'orbit.perigee': 1.0}, ['orbit.perigee: must lie outside the perturber, '
                                             'radius 6378.137 km', 'got 1.0 km']),
    # were tracebacks (ZeroDivisionError) or a derived field nobody wrote
    ({**EARTH_FLYBY, 'orbit.gm': 0.0}, ['orbit.gm: must be in (0, 1e+21]', 'got 0.0']),
    ({**EARTH_FLYBY, 'orbit.v_inf': 1e-300}, ['orbit.v_inf: ', 'got 1e-300']),
    ({**EARTH_FLYBY, 'orbit.gm': 1e300}, ['orbit.gm: must be in (0, 1e+21]', 'got 1e+300']),
    ({**EARTH_FLYBY, 'orbit.gm': 1.0, 'orbit.perigee': 1e-300},
     ['orbit.perigee, orbit.v_inf: e - 1 = perigee v_inf^2 / gm', 'got perigee = 1e-300 km']),
], ids=['e-1e-6-inside-the-sun', 'perigee-inside-the-earth', 'gm-0', 'v_inf-1e-300', 'gm-1e300',
        'perigee-1e-300'])
def test_sim_refuses_an_impossible_orbit_in_one_line(spawn, tmp_path, params, expected):
    sim = spawn('sim', '--ros-args', '--params-file', params_file(tmp_path / 'orbit.yaml', params))
    assert sim.wait(SLOW) == 1, sim.output
    (line,) = sim.output.strip().splitlines()
    assert all(text in line for text in expected), line


def test_sim_reports_a_runaway_spin_up_as_diverged_with_the_work_budget(ros, spawn, tmp_path):
    """A pericentre of 1 km from a point mass of GM 4.5e4: stopped, not running for ever."""
    from test_core_divergence import RUNAWAY

    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    params = {**RUNAWAY, 'real_time_factor': 0.0}
    sim = spawn('sim', '--ros-args', '--params-file', params_file(tmp_path / 'runaway.yaml',
                                                                  params))
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.DIVERGED, 2 * SLOW), (
        [(s.state, s.message) for s in status], sim.output[-3000:])
    message = status[-1].message
    assert message.startswith('work budget exceeded at t = 1.0'), message
    assert 'output_interval' in message and 1.0 - 0.002 <= status[-1].t <= 1.0
    assert 'Traceback' not in sim.output


def _merged_without_descriptions_of(paths: list[Path], run_id: str, out: Path) -> Path:
    """Write the messages of recordings ``paths`` to ``out``, less run ``run_id``'s /scenario."""
    from mcap.reader import make_reader

    with McapWriter(out) as writer:
        channels: dict[str, int] = {}
        for path in paths:
            with open(path, 'rb') as stream:
                for schema, channel, message in make_reader(stream).iter_messages():
                    if channel.topic == '/' + topics.SCENARIO and run_id.encode() in message.data:
                        continue
                    if channel.topic not in channels:
                        channels[channel.topic] = writer.add_channel(channel.topic, schema.name)
                    writer.write(channels[channel.topic], message.data, message.log_time,
                                 message.publish_time)
    return out


def test_two_visible_bringups_in_one_domain_exit_1_and_their_recordings_are_refused(
        spawn, tmp_path, capsys):
    """
    Two ``--visible`` runs of the same scenario in one domain: their messages mix.

    Each sees the other's simulator on its topics ("second source"): it says so, exits 1 (not
    0 with a mixed recording), and ``analyze`` refuses a recording that holds both runs'
    descriptions in one line naming them, unless ``--run`` chooses one; one that missed the
    other's description warns of the repeated stamps its samples have.
    """
    from tumble_ros.analysis.cli import command

    outputs = [tmp_path / f'run{k}.mcap' for k in range(2)]
    # paced over ~10 s each, so that each is alive when the other's recorder discovers it (its
    # latched description reaches a late subscriber only while its publisher lives): as fast as
    # possible, a run could end before the other's recorder had matched its /scenario, and
    # paced over 3 s one did, at load 5-6, the other process starting that much later
    runs = [spawn('bringup', '--visible', '--quiet', '--no-markers', '--output', output,
                  '--ros-args', '-p', 'duration:=6.0', '-p', 'real_time_factor:=0.6')
            for output in outputs]
    for run in runs:
        assert run.wait(SLOW) == 1, run.output
        assert 'second source' in run.output and 'bringup: ERROR: the recording holds a second ' \
            'source' in run.output, run.output
        # the other run's messages in the counts do not keep it waiting for its consumers
        assert 'had not taken every sample' not in run.output, run.output
    ids = [{m.message.run_id for m in read_messages(output, topics=['/' + topics.SCENARIO])}
           for output in outputs]
    assert len(ids[0] | ids[1]) == 2 and max(map(len, ids)) == 2, ids
    run_id = sorted(ids[0] | ids[1])[0]
    warning = f'repeated stamps on /{topics.ANGULAR_VELOCITY} (two runs in one file?)'
    for output, described in zip(outputs, ids):
        capsys.readouterr()
        if len(described) == 2:   # refused, unless --run chooses one
            assert command([str(output), '--quiet']) == 1
            assert command([str(output), '--quiet', '--run', run_id]) == 0
            continue
        # This recorder missed the other run's description (that run ended before it matched
        # the latched /scenario: seen at load 2.2-2.7): any of the other's samples it holds
        # repeat stamps, and say so.
        stamps = [m.message.header.stamp for m in read_messages(
            output, topics=['/' + topics.ANGULAR_VELOCITY])]
        repeated = len(stamps) - len({(s.sec, s.nanosec) for s in stamps})
        assert command([str(output), '--quiet']) == 0
        assert (warning in capsys.readouterr().out) == bool(repeated), (output, repeated)
    # Whatever each recorder caught of the other run, the two runs' samples in one file with
    # one run's descriptions (both recordings merged, one run's /scenario left out):
    one_described = _merged_without_descriptions_of(outputs, run_id, tmp_path / 'merged.mcap')
    capsys.readouterr()
    assert command([str(one_described), '--quiet']) == 0
    assert warning in capsys.readouterr().out

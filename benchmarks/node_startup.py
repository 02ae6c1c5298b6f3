"""Node start-up: seconds from a node process's start to the node on the ROS graph (issue 30).

Each of ``sim``, ``comparator`` and ``recorder`` is started as ``python -m tumble_ros <name>``
(what ``ros2 run tumble_ros <name>`` runs, without the ``ros2`` command's own start-up; the
simulator also through its installed console script, the file ``ros2 run`` executes) on a
DDS domain of its own (a fresh ROS_DOMAIN_ID per start, discovery limited to this host).

An observer process (this file with ``--observe``), started 1 s before on that domain (a
domain where it finds another run's nodes is left for the next one), polls
``get_node_names_and_namespaces()`` every 5 ms and prints the time (``time.monotonic``, one
clock for every process) at which the node's name appears: "visible" is that time minus the
moment just before ``Popen``. For the simulator it also waits for the first
``angular_velocity`` sample ("first sample"). Then SIGINT, and the node must exit 0. The
median of several starts is reported. numba's cache is warm: the first start of each
executable is not counted (it may load or compile the kernels for the first time).

DDS discovery: with Fast DDS (rmw_fastrtps, Jazzy) a participant that is already running
learns of a new one at its own next participant announcement (every 3 s by default), not when
the new one announces itself: a node is seen 0-3 s after it exists, whatever the node (a bare
rclpy node as well as ours), and ``ros2 node list`` through its daemon waits the same way. The
observer therefore announces itself every 0.1 s (a Fast DDS profile given to the observer
process only), so that "visible" measures the node process, not the observer's announcement
schedule; one row repeats the simulator with an observer of default settings.
Target (issue 30): visible <= 1 s once compiled.

Beside it, the import of each node module alone (``python -c 'import tumble_ros.nodes.X'``,
the interpreter's start-up included), the largest part of that second.

Run alone: ``scripts/env.sh python benchmarks/node_startup.py [--quick]``.
"""
from __future__ import annotations

import os
from pathlib import Path
import signal
import statistics
import subprocess
import sys
import tempfile
import time

TARGET_SECONDS = 1.0
#: Issue 30's figure before: a node in ``ros2 node list`` 3.3-4.6 s after ``ros2 run``.
BEFORE = '3.3-4.6 s (issue 30)'
NODES = ('sim', 'comparator', 'recorder')
#: Polling period of the graph [s].
POLL = 0.005
#: Age of the observer's participant when the node process starts [s].
OBSERVER_AGE = 1.0
#: The observer's Fast DDS participant: it announces itself every 0.1 s (default 3 s).
OBSERVER_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <participant profile_name="startup_observer" is_default_profile="true">
    <rtps><builtin><discovery_config>
      <leaseAnnouncement><sec>0</sec><nanosec>100000000</nanosec></leaseAnnouncement>
    </discovery_config></builtin></rtps>
  </participant>
</profiles>
"""


def _domain(k: int) -> int:
    """A ROS domain id for start ``k`` of this process (Fast DDS allows 0..232)."""
    return 1 + (os.getpid() * 7 + k) % 200


def _command(name: str, script: bool, tmp: Path) -> list[str]:
    args = ['--ros-args', '--log-level', 'warn']
    if name == 'recorder':
        args += ['-p', f'output:={tmp / "startup.mcap"}']
    if name == 'sim':
        args += ['-p', 'duration:=1000.0']
    if script:
        from ament_index_python.packages import get_package_prefix

        return [str(Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / name), *args]
    return [sys.executable, '-m', 'tumble_ros', name, *args]


def observe(name: str, timeout: float) -> None:
    """
    The observer process: print ``ready``, then ``visible T`` and (sim) ``sample T``.

    T is ``time.monotonic()`` when the node ``name`` appears in the graph / when its first
    ``angular_velocity`` arrives. The domain is ``ROS_DOMAIN_ID``.
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from geometry_msgs.msg import Vector3Stamped
    from tumble_ros.runs.messages.qos import STATE_QOS

    rclpy.init()
    node = rclpy.create_node('bench_startup_observer')
    first: list[float] = []
    node.create_subscription(Vector3Stamped, '/angular_velocity',
                             lambda _: first or first.append(time.monotonic()), STATE_QOS)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    time.sleep(OBSERVER_AGE)       # (discovers whatever already runs on this domain)
    others = [n for n, _ in node.get_node_names_and_namespaces() if n != node.get_name()]
    print(f'busy {others}' if others else 'ready', flush=True)
    if others:                     # another run uses this domain: the caller takes another
        return
    end = time.monotonic() + timeout
    seen = False
    while time.monotonic() < end:
        if not seen and any(n == name for n, _ in node.get_node_names_and_namespaces()):
            seen = True
            print(f'visible {time.monotonic()!r}', flush=True)
        if seen and (name != 'sim' or first):
            break
        executor.spin_once(timeout_sec=POLL)
    if first:
        print(f'sample {first[0]!r}', flush=True)
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()


def start_once(name: str, domain: int, script: bool = False, fast_observer: bool = True,
               timeout: float = 120.0) -> dict | None:
    """
    Start executable ``name`` once on ``domain``; return its start-up figures [s].

    None when another run's nodes are on ``domain`` (nothing was started).

    ``visible``: from just before the process was started to its node in the observer's view
    of the graph; ``first_sample`` (the simulator): to the first ``angular_velocity`` there.
    ``fast_observer``: the observer announces itself every 0.1 s (else Fast DDS's 3 s).
    """
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    env.pop('FASTRTPS_DEFAULT_PROFILES_FILE', None)
    with tempfile.TemporaryDirectory() as tmp:
        profile = Path(tmp) / 'observer.xml'
        profile.write_text(OBSERVER_PROFILE)
        observer_env = dict(env, **({'FASTRTPS_DEFAULT_PROFILES_FILE': str(profile)}
                                    if fast_observer else {}))
        observer = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), '--observe', name, str(timeout)],
            env=observer_env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True)
        log = Path(tmp) / 'log.txt'
        try:
            assert observer.stdout is not None
            answer = observer.stdout.readline().strip()
            if answer.startswith('busy'):
                return None
            if answer != 'ready':
                raise RuntimeError(f'the observer did not start: {answer!r}')
            with open(log, 'w') as err:
                started = time.monotonic()
                process = subprocess.Popen(_command(name, script, Path(tmp)), env=env,
                                           stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                           stderr=err, start_new_session=True)
                try:
                    output, _ = observer.communicate(timeout=timeout + 10)
                finally:
                    if process.poll() is None:
                        os.killpg(process.pid, signal.SIGINT)
                    try:
                        code = process.wait(timeout=30)
                    except subprocess.TimeoutExpired:
                        os.killpg(process.pid, signal.SIGKILL)
                        code = process.wait()
        finally:
            if observer.poll() is None:
                observer.kill()
                observer.wait()
        times = dict(line.split() for line in output.splitlines() if line.strip())
        if code != 0 or 'visible' not in times:
            raise RuntimeError(f'{name} (exit {code}) was not seen on the graph: '
                               f'{log.read_text()[-2000:]}')
    return {'visible': float(times['visible']) - started,
            'first_sample': float(times['sample']) - started if 'sample' in times else None}


def import_seconds(name: str) -> float:
    """Wall time of ``python -c 'import tumble_ros.nodes.<name>'`` (interpreter start included)."""
    started = time.monotonic()
    subprocess.run([sys.executable, '-c', f'import tumble_ros.nodes.{name}'], check=True)
    return time.monotonic() - started


def measure(starts: int = 3) -> dict:
    """Median start-up figures [s] of every node over ``starts`` starts (after one not counted)."""
    results: dict = {}
    k = 0

    def start(name: str, **options) -> dict:
        nonlocal k
        for _ in range(20):
            k += 1
            found = start_once(name, _domain(k), **options)
            if found is not None:
                return found
        raise RuntimeError('no free ROS domain found (20 tried)')

    def row(runs: list[dict], imports: float | None) -> dict:
        samples = [r['first_sample'] for r in runs if r['first_sample'] is not None]
        return {'visible_s': statistics.median(r['visible'] for r in runs),
                'visible_all_s': [r['visible'] for r in runs],
                'first_sample_s': statistics.median(samples) if samples else None,
                'import_s': imports}

    for name in NODES:
        start(name)   # the first start: numba's cache loaded once, not counted
        runs = [start(name) for _ in range(starts)]
        results[name] = row(runs, statistics.median(import_seconds(name) for _ in range(2)))
    few = 1 if starts < 3 else 2
    results['sim (installed script)'] = row(
        [start('sim', script=True) for _ in range(few)], None)
    results['sim, observer with Fast DDS defaults'] = row(
        [start('sim', fast_observer=False) for _ in range(few)], None)
    return results


def _rows(results: dict) -> list[list]:
    rows = []
    for name, f in results.items():
        rows.append([name, f'{f["visible_s"]:.2f}',
                     ' '.join(f'{v:.2f}' for v in f['visible_all_s']),
                     '-' if f['first_sample_s'] is None else f'{f["first_sample_s"]:.2f}',
                     '-' if f['import_s'] is None else f'{f["import_s"]:.2f}'])
    return rows


HEADERS = ['executable', 'visible [s] (median)', 'each start [s]', 'first sample [s]',
           'import of the node module [s]']


def _bench_section():
    from common import section

    @section('Node start-up: process start to the node on the ROS graph', order=32)
    def node_startup(ctx):
        load = os.getloadavg()[0]
        results = measure(2 if ctx.quick else 3)
        ctx.table(HEADERS, _rows(results))
        worst = max(results[name]['visible_s'] for name in NODES)
        verdict = ctx.verdict(worst <= TARGET_SECONDS, f'MISSED (slowest median {worst:.2f} s)')
        ctx.note(f'load average {load:.2f} at the start of the section; before: {BEFORE}')
        ctx.note(f'target (sim, comparator, recorder visible <= {TARGET_SECONDS:g} s after '
                 f'the process starts, numba cache warm): {verdict}')
        ctx.note('the observer announces its participant every 0.1 s; one with Fast DDS '
                 'defaults (3 s, as a ros2 daemon) sees a new node at its next announcement, '
                 'whatever the node: the last row')
        return results


if __name__ == '__main__':
    if sys.argv[1:2] == ['--observe']:
        observe(sys.argv[2], float(sys.argv[3]))
        sys.exit(0)
    load = os.getloadavg()
    found = measure(2 if '--quick' in sys.argv else 3)
    print(f'load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} at the start')
    print(' | '.join(HEADERS))
    for line in _rows(found):
        print(' | '.join(line))
    print(f'load average {os.getloadavg()[0]:.2f} at the end')
else:
    _bench_section()

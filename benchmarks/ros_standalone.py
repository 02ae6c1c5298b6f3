"""Standalone nodes: sim, comparator and recorder as three processes (the `ros2 run` way).

The installed executables (what `ros2 run tumble_ros <name>` starts), each in its own process,
on an isolated DDS domain (a free ROS_DOMAIN_ID, discovery limited to this host). The simulator
runs as fast as its consumers take it (real_time_factor 0, min_consumers 2: it waits for the
comparator and the recorder and paces on their progress); when it reports FINISHED the three
get SIGINT and the recorder finalises its file. From the recording: samples per second (first to
last recorded sample), samples lost per reliable per-sample topic (the simulator's three and the
comparator's three: stamps missing from the file), the /clock messages missed (best effort by
convention, CLOCK_QOS: counted apart, never in "lost"), and the comparator's latency (receipt
of its error_norm minus receipt of the angular_velocity sample it answers, both by the
recorder, which runs with ``log_time:=receive``: its default logs the simulated time). Target:
>= 2000 samples/s, 0 lost on the reliable topics. Run once per executor (TUMBLE_ROS_EXECUTOR:
events, the default, and single), and the events executor once more beside two busy processes.
"""
from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import tempfile
import time

import numpy as np

TARGET_RATE = 2000.0
#: Reliable, one message per sample: none may be lost.
RELIABLE = ('/angular_velocity', '/attitude', '/euler_angles',
            '/comparison/model_angular_velocity', '/comparison/error', '/comparison/error_norm')
#: Best effort (rclpy's clock QoS): may drop, counted apart.
CLOCK = '/clock'
PER_SAMPLE = RELIABLE + (CLOCK,)
#: The row of the events executor run again beside two busy processes (issue 30).
UNDER_LOAD = 'events, 2 busy processes'


def _executable(name: str) -> str:
    from ament_index_python.packages import get_package_prefix

    return str(Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / name)


def _finished(domain: int, timeout: float) -> bool:
    """Wait (in this process, on the same domain) for the simulator's latched FINISHED."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from tumble_ros_interfaces.msg import SimStatus

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    node = rclpy.create_node('bench_watch', context=context)
    done = []
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                     reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(SimStatus, '/status',
                             lambda m: done.append(m.state == SimStatus.FINISHED), qos)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    end = time.monotonic() + timeout
    try:
        while time.monotonic() < end and not any(done):
            executor.spin_once(timeout_sec=0.2)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return any(done)


def measure(samples: int = 20_000, executor: str = 'events') -> dict:
    """Run the three processes over ``samples`` samples; return the measured figures."""
    from tumble_ros.io import read_columns

    domain = 100 + os.getpid() % 100
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               TUMBLE_ROS_EXECUTOR=executor)
    interval = 2.0 / (samples - 1)
    with tempfile.TemporaryDirectory() as tmp:
        output = Path(tmp) / 'standalone.mcap'
        quiet = ['--log-level', 'warn']
        commands = {
            # receive times (wall clock): the default log time is the simulated one
            'recorder': ['--ros-args', '-p', f'output:={output}', '-p', 'log_time:=receive',
                         *quiet],
            'comparator': ['--ros-args', *quiet],
            'sim': ['--ros-args', '-p', 'duration:=2.0', '-p', f'output_interval:={interval!r}',
                    '-p', 'real_time_factor:=0.0', '-p', 'min_consumers:=2', *quiet],
        }
        processes = {}
        try:
            for name, args in commands.items():
                processes[name] = subprocess.Popen(
                    [_executable(name), *args], env=env, stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL, stderr=open(Path(tmp) / f'{name}.log', 'w'),
                    start_new_session=True)
            finished = _finished(domain, timeout=120.0 + samples / 200.0)
            time.sleep(1.0)  # the last samples reach the comparator and the recorder
        finally:
            for name in ('sim', 'comparator', 'recorder'):
                if name in processes and processes[name].poll() is None:
                    os.killpg(processes[name].pid, signal.SIGINT)
            for p in processes.values():
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
        if not finished:
            logs = {name: (Path(tmp) / f'{name}.log').read_text()[-2000:] for name in commands}
            raise RuntimeError(f'the simulator did not finish; logs: {logs}')
        columns, _ = read_columns(output, PER_SAMPLE)
    velocity = columns['/angular_velocity']
    received = dict(zip(_stamps(velocity).tolist(), velocity.log_time_ns.tolist()))
    norm = columns['/comparison/error_norm']
    latency = np.array([t - received[s] for s, t in zip(_stamps(norm).tolist(),
                                                          norm.log_time_ns.tolist())
                        if s in received]) / 1e6
    span = (velocity.log_time_ns.max() - velocity.log_time_ns.min()) / 1e9
    return {
        'executor': executor,
        'samples': samples,
        'samples_per_s': (len(velocity) - 1) / span if span > 0 else float('nan'),
        'lost': {t: _missing(columns.get(t), samples, interval) for t in RELIABLE},
        'clock_missed': samples - (len(columns[CLOCK]) if CLOCK in columns else 0),
        'latency_p50_ms': float(np.percentile(latency, 50)) if latency.size else float('nan'),
        'latency_p99_ms': float(np.percentile(latency, 99)) if latency.size else float('nan'),
    }


def _missing(table, samples: int, interval: float) -> int:
    """Count the grid samples 0 .. samples - 1 whose stamp is not in ``table`` (None: all)."""
    if table is None:
        return samples
    k = np.rint(_stamps(table) / (interval * 1e9)).astype(np.int64)
    return samples - np.unique(k[(k >= 0) & (k < samples)]).size


def _stamps(table) -> np.ndarray:
    c = table.columns
    return (c['header.stamp.sec'].astype(np.int64) * 1_000_000_000
            + c['header.stamp.nanosec'].astype(np.int64))


def _bench_section():
    from common import busy_processes, section

    @section('Standalone nodes: sim, comparator, recorder as three processes', order=31)
    def standalone(ctx):
        samples = 500 if ctx.quick else 20_000
        rows, results = [], {}
        for executor in ('events', 'single', UNDER_LOAD):
            if executor == UNDER_LOAD:
                with busy_processes(2):
                    f = measure(samples, 'events')
                f['executor'] = UNDER_LOAD
            else:
                f = measure(samples, executor)
            lost = sum(f['lost'].values())
            rows.append([executor, f['samples'], f'{f["samples_per_s"]:,.0f}',
                         f'{f["samples_per_s"] / TARGET_RATE:.2f}x', lost, f['clock_missed'],
                         f'{f["latency_p50_ms"]:.2f}', f'{f["latency_p99_ms"]:.2f}'])
            results[executor] = f
        ctx.table(['executor', 'samples', 'samples/s', 'vs 2000/s target', 'lost (reliable)',
                   '/clock missed (best effort)', 'latency p50 [ms]', 'p99 [ms]'], rows)
        for executor, f in results.items():
            if any(f['lost'].values()):
                ctx.note(f'{executor}: lost per topic: '
                         + ', '.join(f'{t} {n}' for t, n in f['lost'].items() if n))
        loaded = results[UNDER_LOAD]
        ctx.note(f'beside two busy processes (both cores taken): {loaded["samples_per_s"]:,.0f} '
                 f'samples/s, {sum(loaded["lost"].values())} lost on the reliable topics '
                 f'(must be 0: {ctx.verdict(not any(loaded["lost"].values()), "LOST SAMPLES")})')
        best = results['events']
        ok = best['samples_per_s'] >= TARGET_RATE and sum(best['lost'].values()) == 0
        verdict = ctx.verdict(ok, f'MISSED ({best["samples_per_s"]:,.0f}/s, '
                              f'{sum(best["lost"].values())} lost)')
        ctx.note(f'target (>= 2000 samples/s, 0 lost on the reliable topics, default executor '
                 f'events): {verdict}')
        return results


_bench_section()

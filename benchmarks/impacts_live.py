"""Impacts through the service: a live simulator's CPU with 0, 1,000 and 10,000 requested impacts.

The installed ``sim`` executable runs the paper's Fig 9 case (2000 yr, 200,001 samples) paced
at ``real_time_factor`` 2000 / RUN_SECONDS (so every run lasts the same wall time, whatever it
does), on an isolated DDS domain, without consumers. This process calls ``apply_impact`` n
times with ``start_now`` (3e-7-yr pulses), spread over the run, at most IN_FLIGHT requests
unanswered at once (the simulator holds at most MAX_PENDING_IMPACTS). The figure is the
simulator's CPU time (user + system, from its exit status) against the run without impacts:
issue 30's target is at most 2x at 10,000 impacts. Every request must be accepted and every
impact must end (``impact_events``) before the run finishes.
"""
from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import tempfile
import time

from common import section

CONFIG = Path(__file__).resolve().parents[1] / "tumble_ros" / "config" / "fig9.yaml"
TARGET_RATIO = 2.0
#: Wall time of every run [s]: the pacing, the same with and without impacts.
RUN_SECONDS = 40.0
IN_FLIGHT = 50


def _executable(name: str) -> str:
    from ament_index_python.packages import get_package_prefix

    return str(Path(get_package_prefix("tumble_ros")) / "lib" / "tumble_ros" / name)


def _drive(domain: int, n: int, duration: float, timeout: float) -> dict:
    """Request ``n`` impacts spread over the run; return when the simulator finished."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from tumble_ros.runs.messages.qos import SERVICE_QOS
    from tumble_ros_interfaces.msg import ImpactEvent, SimStatus
    from tumble_ros_interfaces.srv import ApplyImpact

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    node = rclpy.create_node("bench_impacts", context=context)
    status, ended, answers = [], [], {"accepted": 0, "refused": 0}
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                         reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(SimStatus, "/status", lambda m: status.append((m.state, m.t)), latched)
    node.create_subscription(ImpactEvent, "/impact_events", lambda m: ended.append(m.id),
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    # KEEP_ALL, as a client firing requests without waiting should (runs.messages.qos)
    client = node.create_client(ApplyImpact, "/apply_impact", qos_profile=SERVICE_QOS)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    futures: list = []
    end = time.monotonic() + timeout
    sent = 0
    try:
        if not client.wait_for_service(timeout_sec=60.0):
            raise RuntimeError("the simulator's apply_impact service did not appear")
        while time.monotonic() < end and not any(s == SimStatus.FINISHED for s, _ in status):
            executor.spin_once(timeout_sec=0.005)
            for f in [f for f in futures if f.done()]:
                futures.remove(f)
                answers["accepted" if f.result().accepted else "refused"] += 1
            t = status[-1][1] if status else 0.0
            # keep pace with the run: request k is due at k / n of it (the last ones by 90 %)
            due = min(n, int(n * t / (0.9 * duration)) + 1) if t > 0 else 0
            while sent < due and len(futures) < IN_FLIGHT:
                request = ApplyImpact.Request(frame=ApplyImpact.Request.FRAME_BODY,
                                              duration=3e-7, start_now=True)
                request.torque.y = 1e3
                futures.append(client.call_async(request))
                sent += 1
        settle = time.monotonic() + 10.0    # the last answers, the simulator still up
        while futures and time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.01)
            for f in [f for f in futures if f.done()]:
                futures.remove(f)
                answers["accepted" if f.result().accepted else "refused"] += 1
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return {"sent": sent, "ended": len(set(ended)), **answers,
            "finished": any(s == SimStatus.FINISHED for s, _ in status)}


def measure(n: int, duration: float = 2000.0, seconds: float = RUN_SECONDS) -> dict:
    """Run the simulator with ``n`` impacts through the service; its CPU time and the counts."""
    domain = 1 + (os.getpid() + 37) % 101
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "sim.log"
        sim = subprocess.Popen(
            [_executable("sim"), "--ros-args", "--params-file", str(CONFIG),
             "-p", f"duration:={duration!r}", "-p", "min_consumers:=0",
             "-p", f"real_time_factor:={duration / seconds!r}", "-p", "markers:=false",
             "--log-level", "warn"],
            env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=open(log, "w"),
            start_new_session=True)
        try:
            counts = _drive(domain, n, duration, timeout=seconds * 3 + 60.0)
        finally:
            if sim.poll() is None:
                os.killpg(sim.pid, signal.SIGINT)
        _, status, usage = os.wait4(sim.pid, 0)
        if not counts["finished"]:
            raise RuntimeError(f"the simulator did not finish: {log.read_text()[-2000:]}")
    return {"cpu_s": usage.ru_utime + usage.ru_stime, **counts}


@section("Impacts through the service: a live 2000-yr simulator with 0, 1,000 and 10,000 "
         "requested impacts", order=37)
def impacts_live_section(ctx):
    duration, seconds = (20.0, 10.0) if ctx.quick else (2000.0, RUN_SECONDS)
    counts = (0, 100) if ctx.quick else (0, 1000, 10_000)
    rows, out = [], {}
    for n in counts:
        f = measure(n, duration, seconds)
        out[n] = f
        rows.append([n, f["accepted"], f["refused"], f["ended"], f"{f['cpu_s']:.2f}",
                     f"{f['cpu_s'] / out[0]['cpu_s']:.2f}x"])
    ctx.table(["impacts", "accepted", "refused", "ended", "sim CPU [s]", "CPU / none"], rows)
    last = out[counts[-1]]
    ratio = last["cpu_s"] / out[0]["cpu_s"]
    complete = last["accepted"] == last["ended"] == counts[-1]
    ctx.note(f"{duration:g} yr paced over {seconds:g} s wall, {IN_FLIGHT} requests in flight at "
             f"most; target ({counts[-1]:,} impacts <= {TARGET_RATIO:g}x the simulator's CPU "
             f"without, every one accepted and ended): "
             f"{ctx.verdict(ratio <= TARGET_RATIO and complete, f'MISSED: {ratio:.2f}x')}: "
             f"{ratio:.2f}x")
    return out

"""End-to-end ROS throughput: sim -> comparator -> recorder in one process (bringup).

Runs ``bringup`` on the default scenario with many samples, once per executor, and reports from
the recording itself:

- samples/s: simulator samples (omega + attitude + Euler angles + /clock, and the comparator's
  three answers) recorded per wall second of the run;
- lost: samples published minus samples recorded, per per-sample topic;
- comparator latency per sample: publish time of its ``comparison/error_norm`` minus publish
  time of the ``angular_velocity`` sample it answers. With the ``single`` executor these are the
  publishers' source timestamps; the ``events`` executor cannot pass MessageInfo, so there they
  are the recorder's receive times (the same process clock; each includes the recorder's own
  queueing, which the difference mostly cancels).

    scripts/env.sh python benchmarks/ros_throughput.py [--samples N] [--executor events|single]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tumble_ros.io import read_messages
from tumble_ros.nodes.bringup import EXECUTORS, run_bringup

PER_SAMPLE = ("/angular_velocity", "/attitude", "/euler_angles", "/clock", "/comparison/error_norm")
TARGET_RATE, TARGET_P99_MS = 2000.0, 10.0
#: The events executor's row run again beside two busy processes (issue 30).
UNDER_LOAD = "events, 2 busy processes"


def measure(samples: int = 20_000, executor: str = "events") -> dict:
    """Run bringup over ``samples`` samples with ``executor``; return the measured figures."""
    with tempfile.TemporaryDirectory() as tmp:
        params = Path(tmp) / "bench.yaml"
        interval = 2.0 / (samples - 1)
        params.write_text(f"sim:\n  ros__parameters:\n    duration: 2.0\n    output_interval: {interval!r}\n")
        started = time.perf_counter()
        result = run_bringup(params, output=Path(tmp) / "bench.mcap", progress=None, executor_name=executor,
                             ros_args=["--log-level", "warn"])
        wall = time.perf_counter() - started
        sent: dict[int, int] = {}
        latency = []
        for m in read_messages(result.output, topics=["/angular_velocity", "/comparison/error_norm"]):
            stamp = m.message.header.stamp.sec * 1_000_000_000 + m.message.header.stamp.nanosec
            if m.topic == "/angular_velocity":
                sent[stamp] = m.publish_time_ns
            elif stamp in sent:
                latency.append(m.publish_time_ns - sent[stamp])
    latency_ms = np.array(latency) / 1e6
    return {
        "executor": executor,
        "samples": result.samples,
        "wall_s": wall,
        "samples_per_s": result.samples / result.wall_seconds,
        "lost": {t: result.samples - result.counts.get(t, 0) for t in PER_SAMPLE},
        "latency_p50_ms": float(np.percentile(latency_ms, 50)) if latency else float("nan"),
        "latency_p99_ms": float(np.percentile(latency_ms, 99)) if latency else float("nan"),
    }


def _row(f: dict) -> tuple:
    lost = sum(f["lost"].values())
    return (f["executor"], f["samples"], f["samples_per_s"], f"{f['samples_per_s'] / TARGET_RATE:.2f}x",
            lost, f["latency_p50_ms"], f["latency_p99_ms"])


HEADERS = ["executor", "samples", "samples/s", "vs 2000/s target", "lost", "latency p50 [ms]", "p99 [ms]"]


def _bench_section():
    try:
        from common import busy_processes, section
    except ImportError:  # run as a script, outside benchmarks/run.py
        return

    @section("End-to-end ROS throughput (bringup: sim + comparator + recorder)", order=30)
    def ros_throughput(ctx):
        samples = 500 if ctx.quick else 20_000
        figures = [measure(samples, name) for name in ("events", "single")]
        with busy_processes(2):
            loaded = measure(samples, "events")
        loaded["executor"] = UNDER_LOAD
        figures.append(loaded)
        ctx.table(HEADERS, [_row(f) for f in figures])
        ctx.note(f"""
One process, default scenario (dop853), {samples} samples over 2 yr, real_time_factor 0 (as fast
as the comparator and recorder take it); 7 messages per sample (sim: omega, attitude, Euler
angles, /clock; comparator: model omega, error, error norm). Targets: >= {TARGET_RATE:.0f}
samples/s, 0 lost, comparator p99 <= {TARGET_P99_MS:g} ms. 'events' latency uses receive
times (no MessageInfo), 'single' the publishers' source timestamps. The last row: the events
executor again beside two busy processes (both cores taken); it must lose nothing.""")
        return {f["executor"]: f for f in figures}


_bench_section()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=20_000)
    parser.add_argument("--executor", choices=sorted(EXECUTORS), action="append")
    args = parser.parse_args()
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from common import Context
    ctx = Context()
    ctx.table(HEADERS, [_row(measure(args.samples, name)) for name in (args.executor or ["events", "single"])])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

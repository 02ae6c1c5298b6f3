"""Reading recordings: messages per second, columnar (io.read_columns) vs the generic decoder.

A recording laid out as the main job's (per sample: /angular_velocity, /attitude,
/euler_angles, /clock, /comparison/model_angular_velocity, /comparison/error,
/comparison/error_norm; zstd chunks of 1 MB) is written, then read whole by
``read_columns`` (what ``analyze`` uses) and by ``read_messages`` (the generic decoder, the
reference; timed on the first part of the file and extrapolated, it takes ~45 us a message),
and by ``load_recording`` end to end. Target: >= 1e6 messages/s for the columnar read.
"""
from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

from common import Timer, section

TARGET = 1e6  # messages per second


def _write(path: Path, samples: int) -> int:
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import QuaternionStamped, Vector3Stamped
    from rclpy.serialization import serialize_message
    from rosgraph_msgs.msg import Clock
    from tumble_ros_interfaces.msg import ErrorNorm

    from tumble_ros import topics
    from tumble_ros.io import McapWriter

    def stamped(msg, ns, frame):
        msg.header.stamp = Time(sec=ns // 10**9, nanosec=ns % 10**9)
        msg.header.frame_id = frame
        return msg

    count = 0
    with McapWriter(path, chunk_seconds=math.inf) as writer:
        ids = {name: writer.add_channel('/' + name if not name.startswith('/') else name,
                                        topics.TYPES[name])
               for name in (topics.ANGULAR_VELOCITY, topics.ATTITUDE, topics.EULER_ANGLES,
                            topics.CLOCK, topics.MODEL_ANGULAR_VELOCITY, topics.ERROR,
                            topics.ERROR_NORM)}
        for k in range(samples):
            ns = k * 10_000_000
            w = (0.1 * math.sin(k * 1e-3), 0.1 * math.cos(k * 1e-3), 30.0 + 1e-6 * k)
            v = stamped(Vector3Stamped(), ns, topics.FRAME_BODY)
            v.vector.x, v.vector.y, v.vector.z = w
            data = serialize_message(v)
            q = stamped(QuaternionStamped(), ns, topics.FRAME_ORBITAL)
            q.quaternion.w, q.quaternion.x = math.cos(k * 1e-3), math.sin(k * 1e-3)
            e = stamped(ErrorNorm(), ns, topics.FRAME_BODY)
            e.model, e.norm, e.relative = 'paper', 1e-3 * k, 1e-5 * k
            for name, payload in ((topics.ANGULAR_VELOCITY, data), (topics.ATTITUDE,
                                                                      serialize_message(q)),
                                  (topics.EULER_ANGLES, data),
                                  (topics.CLOCK, serialize_message(Clock(clock=v.header.stamp))),
                                  (topics.MODEL_ANGULAR_VELOCITY, data), (topics.ERROR, data),
                                  (topics.ERROR_NORM, serialize_message(e))):
                writer.write(ids[name], payload, ns, ns)
                count += 1
    return count


@section("Reading recordings (analyze): columnar vs generic decoding", order=40)
def read_section(ctx):
    from tumble_ros.analysis import load_recording
    from tumble_ros.io import read_columns, read_messages, summarize

    samples = 2_000 if ctx.quick else 200_000
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / 'bench.mcap'
        with Timer() as tm:
            total = _write(path, samples)
        ctx.note(f'{total:,} messages ({samples:,} samples x 7 topics), '
                 f'{path.stat().st_size / 1e6:.0f} MB, written in {tm.seconds:.1f} s')
        names = sorted(summarize(path).topics)
        best = math.inf
        for _ in range(3):
            with Timer() as tm:
                columns, _ = read_columns(path, names)
            best = min(best, tm.seconds)
        assert sum(len(c) for c in columns.values()) == total
        columnar = total / best
        part = min(total, 70_000)
        start = time.perf_counter()
        for k, _ in enumerate(read_messages(path, names), start=1):
            if k >= part:
                break
        generic = part / (time.perf_counter() - start)
        with Timer() as tm:
            rec = load_recording(path)
        assert rec.n == samples
    ctx.table(['reader', 'messages', 'messages/s', 'vs generic', 'vs 1e6/s target'], [
        ['read_columns (columnar)', total, f'{columnar:,.0f}', f'{columnar / generic:.1f}x',
         f'{columnar / TARGET:.2f}x'],
        ['read_messages (generic)', part, f'{generic:,.0f}', '1.0x', f'{generic / TARGET:.2f}x'],
        ['load_recording (analyze)', total, f'{total / tm.seconds:,.0f}',
         f'{total / tm.seconds / generic:.1f}x', f'{total / tm.seconds / TARGET:.2f}x'],
    ])
    verdict = ctx.verdict(columnar >= TARGET, f'MISSED by {TARGET / columnar - 1:.0%}')
    ctx.note(f'target (>= 1e6 messages/s, columnar): {verdict}: {columnar:,.0f}/s '
             f'(generic decoder {generic:,.0f}/s)')
    return dict(messages=total, columnar_per_s=columnar, generic_per_s=generic,
                load_recording_s=tm.seconds)

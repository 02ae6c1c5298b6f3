#!/usr/bin/env python3
"""Write the golden MCAP file of the io tests and the JSON that states what it holds.

    scripts/env.sh python scripts/make_golden_mcap.py [--out-dir tumble_ros/test/data]

writes ``golden.mcap`` (with tumble_ros.io.McapWriter; messages serialised by rclpy from the real
message classes) and ``golden.json``. The JSON is written from this script's own literal inputs,
never by reading the MCAP file back, so a test can compare the reader's output with it. The
output is deterministic (fixed stamps and log times, no wall clock, zstd chunks of a fixed size):
``test_io_golden.py`` regenerates both files and checks they are byte-identical to the committed
ones.

Content (seconds_per_year = 1, so a stamp of t yr is t s of ROS time; stamp ns = t * 1e9):

- ``/angular_velocity`` geometry_msgs/msg/Vector3Stamped, frame 'body', 200 samples
  k = 0..199, t_k = k * 0.002 yr (stamp ns = k * 2_000_000),
  w = (cos(2 pi 15 t), sin(2 pi 15 t), 30) rad/yr;
- ``/attitude`` geometry_msgs/msg/QuaternionStamped, frame 'orbital', every 10th sample
  (k = 0, 10, ..., 190: 20 messages), a rotation about z by 30 t rad:
  q = (x, y, z, w) = (0, 0, sin(15 t), cos(15 t));
- ``/clock`` rosgraph_msgs/msg/Clock, every 10th sample (20 messages), clock = the stamp;
- ``/impact_events`` tumble_ros_interfaces/msg/ImpactEvent, one message: id 1, start 0.1 yr,
  end 0.1000003 yr (stamp = end: 100_000_300 ns), FRAME_BODY, torque (0, 1e6, 0),
  delta_omega (0, 0.3, 0);
- ``/scenario`` tumble_ros_interfaces/msg/ScenarioDescription, one latched message (stamp 0,
  transient-local QoS): revision 0, a small params YAML, seconds_per_year 1, segment_start 0,
  omega (1, 0, 30), attitude identity, run_id 0123456789ab;
- ``/status`` tumble_ros_interfaces/msg/SimStatus (latched): RUNNING at t = 0 and FINISHED at
  t = 0.398 yr.

Log time (receive time) = stamp ns + a fixed latency per topic; publish time = stamp ns. The
messages are written in log-time order, in zstd chunks of 2048 bytes of message data (several
chunks), chunk_seconds = inf (no wall-clock dependence).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'tumble_ros'))

from geometry_msgs.msg import QuaternionStamped, Vector3Stamped  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from tumble_ros_interfaces.msg import ImpactEvent, ScenarioDescription, SimStatus  # noqa: E402

from tumble_ros.io import McapWriter  # noqa: E402
from tumble_ros.io.msgdefs import message_spec  # noqa: E402

CHUNK_BYTES = 2048
COMPRESSION = 'zstd'

# offered_qos_profiles as rosbag2 (Jazzy, metadata version 9) serialises them.
_INFINITE = '    sec: 9223372036\n    nsec: 854775807\n'
QOS_RELIABLE_1000 = (
    '- history: keep_last\n  depth: 1000\n  reliability: reliable\n  durability: volatile\n'
    f'  deadline:\n{_INFINITE}  lifespan:\n{_INFINITE}  liveliness: automatic\n'
    f'  liveliness_lease_duration:\n{_INFINITE}  avoid_ros_namespace_conventions: false')
QOS_LATCHED = (
    '- history: keep_last\n  depth: 1\n  reliability: reliable\n  durability: transient_local\n'
    f'  deadline:\n{_INFINITE}  lifespan:\n{_INFINITE}  liveliness: automatic\n'
    f'  liveliness_lease_duration:\n{_INFINITE}  avoid_ros_namespace_conventions: false')

TOPICS = {  # topic: (type, message class, offered_qos_profiles)
    '/scenario': ('tumble_ros_interfaces/msg/ScenarioDescription', ScenarioDescription,
                  QOS_LATCHED),
    '/status': ('tumble_ros_interfaces/msg/SimStatus', SimStatus, QOS_LATCHED),
    '/clock': ('rosgraph_msgs/msg/Clock', Clock, QOS_RELIABLE_1000),
    '/angular_velocity': ('geometry_msgs/msg/Vector3Stamped', Vector3Stamped, QOS_RELIABLE_1000),
    '/attitude': ('geometry_msgs/msg/QuaternionStamped', QuaternionStamped, QOS_RELIABLE_1000),
    '/impact_events': ('tumble_ros_interfaces/msg/ImpactEvent', ImpactEvent, QOS_RELIABLE_1000),
}

# Receive latency per topic [ns] (log time = stamp + latency).
LATENCY = {'/scenario': 50_000, '/status': 60_000, '/clock': 100_000,
           '/angular_velocity': 250_000, '/attitude': 260_000, '/impact_events': 270_000}


def stamp(ns: int) -> dict:
    return {'sec': ns // 1_000_000_000, 'nanosec': ns % 1_000_000_000}


def events() -> list[tuple[str, int, dict]]:
    """(topic, stamp ns, message fields) of every message, from the literal inputs above."""
    out = []
    out.append(('/scenario', 0, {
        'header': {'stamp': stamp(0), 'frame_id': ''},
        'revision': 0,
        'parameters_yaml': 'sim:\n  ros__parameters:\n    duration: 0.4\n'
                           '    output_interval: 0.002\n    omega0: [1.0, 0.0, 30.0]\n',
        'seconds_per_year': 1.0,
        'segment_start': 0.0,
        'omega': {'x': 1.0, 'y': 0.0, 'z': 30.0},
        'attitude': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0},
        'run_id': '0123456789ab',
    }))
    out.append(('/status', 0, {
        'header': {'stamp': stamp(0), 'frame_id': ''},
        'state': SimStatus.RUNNING, 't': 0.0, 'message': '',
    }))
    for k in range(200):
        ns = k * 2_000_000
        t = k * 0.002
        if k % 10 == 0:
            out.append(('/clock', ns, {'clock': stamp(ns)}))
        out.append(('/angular_velocity', ns, {
            'header': {'stamp': stamp(ns), 'frame_id': 'body'},
            'vector': {'x': math.cos(2 * math.pi * 15 * t), 'y': math.sin(2 * math.pi * 15 * t),
                       'z': 30.0},
        }))
        if k % 10 == 0:
            out.append(('/attitude', ns, {
                'header': {'stamp': stamp(ns), 'frame_id': 'orbital'},
                'quaternion': {'x': 0.0, 'y': 0.0, 'z': math.sin(15 * t),
                               'w': math.cos(15 * t)},
            }))
    out.append(('/impact_events', 100_000_300, {
        'header': {'stamp': stamp(100_000_300), 'frame_id': 'body'},
        'id': 1, 'start': 0.1, 'end': 0.1000003, 'frame': ImpactEvent.FRAME_BODY,
        'torque': {'x': 0.0, 'y': 1.0e6, 'z': 0.0},
        'delta_omega': {'x': 0.0, 'y': 0.3, 'z': 0.0},
    }))
    out.append(('/status', 398_000_000, {
        'header': {'stamp': stamp(398_000_000), 'frame_id': ''},
        'state': SimStatus.FINISHED, 't': 0.398, 'message': 'reached duration',
    }))
    out.sort(key=lambda e: e[1] + LATENCY[e[0]])
    return out


def fill(message, fields: dict):
    """Set the fields of a ROS message object from a (nested) dict."""
    for name, value in fields.items():
        if isinstance(value, dict):
            fill(getattr(message, name), value)
        else:
            setattr(message, name, value)
    return message


_SIZES = {'bool': 1, 'byte': 1, 'char': 1, 'int8': 1, 'uint8': 1, 'int16': 2, 'uint16': 2,
          'int32': 4, 'uint32': 4, 'float32': 4, 'int64': 8, 'uint64': 8, 'float64': 8}


def zero_padding(data: bytes, type_name: str) -> bytes:
    """``data`` with its CDR alignment padding set to zero.

    rclpy (Fast-CDR) leaves the padding bytes uninitialised, so serialising the same message twice
    can give different bytes; zeroing them makes this script's output reproducible. Walks the
    XCDR1 layout (alignment relative to the byte after the 4-byte encapsulation header) using
    the parsed .msg files.
    """
    buf = bytearray(data)
    pos = 4

    def align(size):
        nonlocal pos
        new = 4 + -(-(pos - 4) // size) * size
        buf[pos:new] = bytes(new - pos)
        pos = new

    def u32():
        nonlocal pos
        align(4)
        value = int.from_bytes(buf[pos:pos + 4], 'little')
        pos += 4
        return value

    def value(base):
        nonlocal pos
        if base in _SIZES:
            align(_SIZES[base])
            pos += _SIZES[base]
        elif base == 'string':
            length = u32()
            pos += length
        else:
            struct_(base)

    def struct_(base):
        package, _, name = base.partition('/')
        for field in message_spec(f'{package}/msg/{name}').fields:
            if field.array is None:
                value(field.type)
                continue
            count = int(field.array) if field.array.isdigit() else u32()
            for _ in range(count):
                value(field.type)

    struct_(type_name.replace('/msg/', '/'))
    if pos > len(buf):
        raise RuntimeError(f'CDR walk of {type_name} overran the data')
    buf[pos:] = bytes(len(buf) - pos)
    return bytes(buf)


def serialize(cls, type_name: str, fields: dict) -> bytes:
    """rclpy's CDR bytes of a message built from ``fields``, padding zeroed (checked by rclpy)."""
    message = fill(cls(), fields)
    data = zero_padding(serialize_message(message), type_name)
    if deserialize_message(data, cls) != message:
        raise RuntimeError(f'zeroing the padding changed a {type_name} message')
    return data


def write(out_dir: Path) -> tuple[Path, Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    mcap_path = out_dir / 'golden.mcap'
    json_path = out_dir / 'golden.json'
    mcap_path.unlink(missing_ok=True)
    expected: dict = {
        'description': 'content of golden.mcap, written by scripts/make_golden_mcap.py from its '
                       'literal inputs (not read back from the file)',
        'profile': 'ros2',
        'compression': COMPRESSION,
        'topics': {},
    }
    all_events = events()
    with McapWriter(mcap_path, chunk_bytes=CHUNK_BYTES, chunk_seconds=math.inf,
                    compression=COMPRESSION) as writer:
        channels = {topic: writer.add_channel(topic, type_name, qos)
                    for topic, (type_name, _, qos) in TOPICS.items()}
        for topic, ns, fields in all_events:
            type_name, cls, _ = TOPICS[topic]
            data = serialize(cls, type_name, fields)
            log_time = ns + LATENCY[topic]
            writer.write(channels[topic], data, log_time, ns)
            entry = expected['topics'].setdefault(topic, {
                'type': TOPICS[topic][0], 'offered_qos_profiles': TOPICS[topic][2],
                'count': 0, 'first': None, 'last': None})
            record = {'log_time_ns': log_time, 'publish_time_ns': ns, 'message': fields}
            entry['count'] += 1
            entry['first'] = entry['first'] or record
            entry['last'] = record
    expected['message_count'] = len(all_events)
    log_times = [ns + LATENCY[topic] for topic, ns, _ in all_events]
    expected['start_time_ns'] = min(log_times)
    expected['end_time_ns'] = max(log_times)
    json_path.write_text(json.dumps(expected, indent=1, sort_keys=True) + '\n', encoding='utf-8')
    return mcap_path, json_path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--out-dir', type=Path, default=ROOT / 'tumble_ros' / 'test' / 'data',
                        help='directory for golden.mcap and golden.json (default: %(default)s)')
    args = parser.parse_args(argv)
    mcap_path, json_path = write(args.out_dir)
    print(f'wrote {mcap_path} ({mcap_path.stat().st_size} bytes) and {json_path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())

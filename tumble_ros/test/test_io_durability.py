"""
McapWriter's durability contract, argument checks and close semantics.

A writer killed with SIGKILL loses at most the chunk in progress (< chunk_bytes of message
data), what was flushed stays readable.
"""
import math
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import threading
import time

from geometry_msgs.msg import Vector3Stamped
import numpy
import pytest
from rclpy.serialization import serialize_message

from tumble_ros.io import (McapError, McapWriter, MessageDefinitionError, offered_qos_yaml,
                           read_messages, summarize)

CHILD = textwrap.dedent("""
    import math, pickle, sys, time
    from tumble_ros.io import McapWriter
    payloads = pickle.load(open(sys.argv[1], 'rb'))
    path, chunk_bytes, flushes, extra, mode = (
        sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), sys.argv[6])
    writer = McapWriter(path, chunk_bytes=chunk_bytes, chunk_seconds=math.inf)
    channel = writer.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
    i = 0
    def write_one():
        global i
        writer.write(channel, payloads[i % len(payloads)], 1_000 + i)
        i += 1
    if mode == 'still':
        # Write until the N-th flush, then `extra` more messages (kept in the chunk in
        # progress), report, and wait to be killed.
        while writer.chunks_written < flushes:
            write_one()
        for _ in range(extra):
            write_one()
        print(i, writer.messages_flushed, writer.chunks_written, flush=True)
        time.sleep(120)
    else:
        # Keep writing; report after every flush; killed while busy.
        reported = 0
        while True:
            write_one()
            if writer.chunks_written > reported:
                reported = writer.chunks_written
                print(i, writer.messages_flushed, reported, flush=True)
""")


def vector_payloads(count):
    """Return serialized Vector3Stamped messages; message k carries k in vector.x."""
    out = []
    for k in range(count):
        message = Vector3Stamped()
        message.header.frame_id = 'body'
        message.header.stamp.sec = k
        message.vector.x, message.vector.y, message.vector.z = float(k), 0.5, 30.0
        out.append(serialize_message(message))
    return out


@pytest.fixture
def child(tmp_path):
    payload_file = tmp_path / 'payloads.pickle'
    payloads = vector_payloads(400)
    payload_file.write_bytes(pickle.dumps(payloads))
    script = tmp_path / 'child.py'
    script.write_text(CHILD)
    processes = []

    def start(path, chunk_bytes, flushes, extra, mode):
        process = subprocess.Popen(
            [sys.executable, str(script), str(payload_file), str(path), str(chunk_bytes),
             str(flushes), str(extra), mode],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        processes.append(process)
        return process

    yield start, payloads
    for process in processes:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=10)
        process.stdout.close()
        process.stderr.close()


def read_line(process, timeout=30.0):
    lines = []
    reader = threading.Thread(target=lambda: lines.append(process.stdout.readline()), daemon=True)
    reader.start()
    reader.join(timeout)
    if reader.is_alive():
        process.kill()
        raise AssertionError(f'the child did not report within {timeout} s')
    if not lines[0]:
        raise AssertionError(f'child ended early: {process.stderr.read()}')
    return [int(x) for x in lines[0].split()]


def kill(process):
    os.kill(process.pid, signal.SIGKILL)
    assert process.wait(timeout=10) == -signal.SIGKILL


def test_sigkill_loses_at_most_the_chunk_in_progress(tmp_path, child):
    start, payloads = child
    path = tmp_path / 'killed.mcap'
    size = len(payloads[0])
    assert {len(p) for p in payloads} == {size}
    chunk_bytes = 1000
    per_chunk = math.ceil(chunk_bytes / size)   # a chunk is flushed once it holds >= chunk_bytes
    extra = per_chunk - 1                       # the most that can be pending without a flush
    process = start(path, chunk_bytes, 3, extra, 'still')
    written, flushed, chunks = read_line(process)
    kill(process)

    assert chunks == 3 and flushed == 3 * per_chunk and written == flushed + extra
    messages = list(read_messages(path))
    # Every flushed message is back, in order, with its value; nothing else.
    assert [m.message.vector.x for m in messages] == [float(k) for k in range(flushed)]
    assert [m.log_time_ns for m in messages] == [1_000 + k for k in range(flushed)]
    lost = [payloads[k] for k in range(flushed, written)]
    assert 0 < sum(len(p) for p in lost) < chunk_bytes      # the documented bound

    summary = summarize(path)
    assert not summary.finalised and summary.truncated and summary.problem
    assert summary.chunk_count == 3
    assert summary.message_count == flushed
    assert summary.topics['/w'].message_count == flushed
    assert summary.topics['/w'].type_name == 'geometry_msgs/msg/Vector3Stamped'


def test_sigkill_while_busy_writing(tmp_path, child):
    start, _ = child
    path = tmp_path / 'busy.mcap'
    process = start(path, 300, 0, 0, 'busy')
    for _ in range(5):
        written, flushed, chunks = read_line(process)
    kill(process)
    messages = list(read_messages(path))
    # At least what was flushed when the child last reported; a consecutive prefix, no gaps.
    assert len(messages) >= flushed
    assert [m.message.vector.x for m in messages] == [
        float(k % 400) for k in range(len(messages))]
    assert summarize(path).truncated


def test_flush_on_chunk_bytes(tmp_path):
    path = tmp_path / 'bytes.mcap'
    data = vector_payloads(1)[0]
    with McapWriter(path, chunk_bytes=5 * len(data), chunk_seconds=math.inf) as writer:
        channel = writer.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
        with pytest.raises(McapError, match='no messages recoverable'):
            list(read_messages(path))                       # header only, so far
        for k in range(4):
            writer.write(channel, data, k)
            assert writer.messages_flushed == 0 and writer.chunks_written == 0
        writer.write(channel, data, 4)
        assert writer.messages_flushed == 5 and writer.chunks_written == 1
        assert len(list(read_messages(path))) == 5         # readable while still open
        writer.write(channel, data, 5)
        assert summarize(path).message_count == 5 and summarize(path).truncated
    assert summarize(path).message_count == 6 and summarize(path).finalised


def test_flush_on_chunk_seconds_by_write_and_by_poll(tmp_path):
    path = tmp_path / 'seconds.mcap'
    data = vector_payloads(1)[0]
    writer = McapWriter(path, chunk_bytes=10**9, chunk_seconds=0.15)
    channel = writer.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
    writer.write(channel, data, 1)
    writer.write(channel, data, 2)
    assert writer.poll() is False and writer.messages_flushed == 0
    time.sleep(0.2)
    assert writer.poll() is True                           # a timer's poll flushes
    assert writer.messages_flushed == 2 and len(list(read_messages(path))) == 2
    assert writer.poll() is False                          # nothing pending
    writer.write(channel, data, 3)
    time.sleep(0.2)
    writer.write(channel, data, 4)                         # the write itself sees the age
    assert writer.messages_flushed == 4 and len(list(read_messages(path))) == 4
    writer.write(channel, data, 5)
    writer.flush()                                         # on demand
    assert writer.messages_flushed == 5 and writer.chunks_written == 3
    assert writer.counts == {'/w': 5}
    writer.close()
    writer.close()                                         # idempotent
    assert writer.closed and writer.poll() is False
    summary = summarize(path)
    assert summary.finalised and summary.message_count == 5 and summary.chunk_count == 3
    with pytest.raises(ValueError, match='closed'):
        writer.write(channel, data, 6)
    with pytest.raises(ValueError, match='closed'):
        writer.add_channel('/x', 'rosgraph_msgs/msg/Clock')


def test_clean_close_is_finalised_even_on_exception(tmp_path):
    path = tmp_path / 'exc.mcap'
    data = vector_payloads(3)
    with pytest.raises(RuntimeError, match='boom'):
        with McapWriter(path) as writer:
            channel = writer.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
            for k, payload in enumerate(data):
                writer.write(channel, payload, k)
            raise RuntimeError('boom')
    summary = summarize(path)
    assert summary.finalised and summary.message_count == 3
    assert writer.path == path


@pytest.mark.parametrize('kwargs, name', [
    ({'chunk_bytes': 0}, 'chunk_bytes'), ({'chunk_bytes': -5}, 'chunk_bytes'),
    ({'chunk_bytes': 1.5}, 'chunk_bytes'), ({'chunk_bytes': True}, 'chunk_bytes'),
    ({'chunk_seconds': 0}, 'chunk_seconds'), ({'chunk_seconds': -1.0}, 'chunk_seconds'),
    ({'chunk_seconds': math.nan}, 'chunk_seconds'), ({'chunk_seconds': '1'}, 'chunk_seconds'),
    ({'compression': 'gzip'}, 'compression'), ({'compression': None}, 'compression'),
])
def test_constructor_arguments_are_checked(tmp_path, kwargs, name):
    with pytest.raises(ValueError, match=name):
        McapWriter(tmp_path / 'x.mcap', **kwargs)
    assert not (tmp_path / 'x.mcap').exists()


def test_existing_file_is_not_overwritten(tmp_path):
    path = tmp_path / 'keep.mcap'
    path.write_bytes(b'precious')
    with pytest.raises(FileExistsError):
        McapWriter(path)
    assert path.read_bytes() == b'precious'


def test_a_claimed_empty_name_is_taken_by_one_writer_only(tmp_path):
    """An empty file (a name default_output claimed) is written; a second writer is refused."""
    path = tmp_path / 'claimed.mcap'
    path.write_bytes(b'')
    with McapWriter(path) as first:
        with pytest.raises(FileExistsError):
            McapWriter(path)      # locked by the first, and no longer empty
        first.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
    assert summarize(path).finalised
    empty = tmp_path / 'empty.mcap'
    empty.write_bytes(b'')
    link = tmp_path / 'link.mcap'
    link.symlink_to(empty)
    with pytest.raises(FileExistsError):
        McapWriter(link)          # never through a symbolic link
    assert empty.read_bytes() == b''


def test_channel_and_write_arguments_are_checked(tmp_path):
    data = vector_payloads(1)[0]
    with McapWriter(tmp_path / 'args.mcap') as writer:
        channel = writer.add_channel('/w', 'geometry_msgs/Vector3Stamped')
        assert writer.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped') == channel
        other = writer.add_channel('/v', 'geometry_msgs/msg/Vector3Stamped')
        assert other != channel
        with pytest.raises(ValueError, match='already has type'):
            writer.add_channel('/w', 'rosgraph_msgs/msg/Clock')
        with pytest.raises(MessageDefinitionError, match='geometry_msgs/msg/Nope'):
            writer.add_channel('/n', 'geometry_msgs/msg/Nope')
        with pytest.raises(ValueError, match='topic'):
            writer.add_channel('', 'rosgraph_msgs/msg/Clock')
        with pytest.raises(ValueError, match='offered_qos_profiles'):
            writer.add_channel('/q', 'rosgraph_msgs/msg/Clock', '- history: keep_last')
        with pytest.raises(ValueError, match='offered_qos_profiles'):
            writer.add_channel('/q', 'rosgraph_msgs/msg/Clock', 'a: [')
        writer.add_channel('/q', 'rosgraph_msgs/msg/Clock', offered_qos_yaml({'depth': 5}))
        with pytest.raises(ValueError, match='channel_id'):
            writer.write(99, data, 1)
        with pytest.raises(ValueError, match='log_time_ns'):
            writer.write(channel, data, -1)
        with pytest.raises(ValueError, match='log_time_ns'):
            writer.write(channel, data, 1.5)
        with pytest.raises(ValueError, match='log_time_ns'):
            writer.write(channel, data, True)
        with pytest.raises(ValueError, match='publish_time_ns'):
            writer.write(channel, data, 1, 2 ** 64)
        with pytest.raises(ValueError, match='data'):
            writer.write(channel, 'not bytes', 1)
        writer.write(channel, bytearray(data), 7, 3)
        writer.write(channel, memoryview(data), numpy.int64(8))        # numpy ints are fine
        assert writer.counts == {'/w': 2, '/v': 0, '/q': 0}
    first, second = list(read_messages(writer.path))
    assert (first.log_time_ns, first.publish_time_ns) == (7, 3)
    assert (second.log_time_ns, second.publish_time_ns) == (8, 8)
    assert summarize(writer.path).topics['/v'].message_count == 0


def test_offered_qos_yaml():
    text = offered_qos_yaml({'depth': 1, 'durability': 'transient_local'},
                            {'reliability': 'best_effort', 'deadline': (1, 5)})
    import yaml
    first, second = yaml.safe_load(text)
    assert first['depth'] == 1 and first['durability'] == 'transient_local'
    assert first['deadline'] == {'sec': 9223372036, 'nsec': 854775807}
    assert second['reliability'] == 'best_effort' and second['deadline'] == {'sec': 1, 'nsec': 5}
    assert offered_qos_yaml() == ''
    with pytest.raises(ValueError, match='unknown QoS keys'):
        offered_qos_yaml({'depht': 1})

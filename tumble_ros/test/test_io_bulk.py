"""
McapWriter's bulk paths (io/mcap_bulk.py) against one mcap add_message per message.

write_rows (fixed-size samples of several channels) and write_many (messages of any sizes).

The same rows, single messages around them and chunk sizes that cut the blocks anywhere: the
two files must be the same bytes (records, chunks, message indexes, statistics, summary), and
the bulk file must read back with mcap's own seeking reader through its indexes. The chunks
finalised in a thread (``background=True``, mcap_bulk.ChunkFinisher): the same bytes again, the
file flushed as far as the thread has written it, several chunks handed over while the thread is
busy, an error of the thread raised by the writer and no chunk written after a failed one.
"""
import threading

from mcap.reader import make_reader
import numpy as np
import pytest

from tumble_ros.io import McapWriter
from tumble_ros.io.mcap_bulk import bulk_supported, ChunkFinisher, IN_FLIGHT


def _write(path, bulk: bool, chunk_bytes: int, compression: str,
           background: bool = False) -> None:
    with McapWriter(path, chunk_bytes=chunk_bytes, chunk_seconds=float('inf'),
                    compression=compression, background=background) as w:
        assert bulk_supported(w._writer)
        # the finisher is used where asked for, except with lz4 (left to mcap's Writer)
        assert (w._finisher is not None) == (background and compression != 'lz4')
        w._bulk = bulk                                  # the reference: one add_message each
        a = w.add_channel('/a', 'geometry_msgs/msg/Vector3Stamped')
        b = w.add_channel('/b', 'geometry_msgs/msg/QuaternionStamped')
        c = w.add_channel('/c', 'std_msgs/msg/String')
        rng = np.random.default_rng(11)
        t = 1_000
        for block in (1, 7, 250, 3, 1000):
            w.write(c, b'single message', t, t + 1)     # a message outside the blocks
            rows = [rng.integers(0, 256, (block, 40), dtype=np.uint8),
                    rng.integers(0, 256, (block, 56), dtype=np.uint8)]
            logs = t + 10 * np.arange(block, dtype=np.int64)
            w.write_rows([a, b], rows, logs, logs - 3)
            w.write(a, b'x' * 40, int(logs[-1]) + 1, int(logs[-1]))   # same channel, single
            t = int(logs[-1]) + 100
            # messages of any sizes, on every channel, some sharing a log time
            many = [(int(rng.choice([a, b, c])), bytes(rng.integers(0, 256, int(size),
                                                                    dtype=np.uint8)),
                     t + k // 2, t + k)
                    for k, size in enumerate(rng.integers(0, 700, block))]
            w.write_many(many)
            t += block + 100


@pytest.mark.parametrize('chunk_bytes, compression', [
    (1, 'none'), (1000, 'zstd'), (4096, 'lz4'), (10_000_000, 'zstd')])
def test_the_bulk_path_writes_the_same_bytes(tmp_path, chunk_bytes, compression):
    _write(tmp_path / 'bulk.mcap', True, chunk_bytes, compression)
    _write(tmp_path / 'each.mcap', False, chunk_bytes, compression)
    bulk, each = (tmp_path / 'bulk.mcap').read_bytes(), (tmp_path / 'each.mcap').read_bytes()
    assert len(bulk) > 10_000
    assert bulk == each
    with open(tmp_path / 'bulk.mcap', 'rb') as f:
        reader = make_reader(f)
        stats = reader.get_summary().statistics
        assert stats.message_count == 3 * (1 + 7 + 250 + 3 + 1000) + 10
        times = [m.log_time for _, _, m in reader.iter_messages(log_time_order=True)]
    assert len(times) == stats.message_count and times == sorted(times)


@pytest.mark.parametrize('chunk_bytes, compression', [
    (1, 'none'), (1000, 'zstd'), (4096, 'lz4'), (30_000, 'zstd'), (10_000_000, 'zstd')])
@pytest.mark.parametrize('bulk', [True, False])
def test_chunks_finalised_in_a_thread_are_the_same_bytes(tmp_path, chunk_bytes, compression,
                                                         bulk):
    _write(tmp_path / 'thread.mcap', bulk, chunk_bytes, compression, background=True)
    _write(tmp_path / 'each.mcap', False, chunk_bytes, compression)
    thread, each = (tmp_path / 'thread.mcap').read_bytes(), (tmp_path / 'each.mcap').read_bytes()
    assert len(thread) > 10_000
    assert thread == each


def test_a_flush_waits_for_the_thread_and_the_file_is_read_as_far(tmp_path):
    """The durability contract with background=True: after flush() the chunks are in the file."""
    path = tmp_path / 'open.mcap'
    w = McapWriter(path, chunk_bytes=500, chunk_seconds=float('inf'), background=True)
    try:
        a = w.add_channel('/a', 'std_msgs/msg/String')
        for k in range(300):
            w.write(a, b'\x00\x01\x00\x00\x04\x00\x00\x00abc\x00' + bytes(40), 1000 + k)
        w.flush()
        assert w.chunks_written > 10
        from tumble_ros.io import read_messages
        assert sum(1 for _ in read_messages(path)) == 300     # unfinished file, streamed
    finally:
        w.close()
    assert not any(t.name.startswith('mcap-chunks') for t in threading.enumerate())


def test_an_error_in_the_thread_is_raised_by_the_writer(tmp_path, monkeypatch):
    w = McapWriter(tmp_path / 'x.mcap', chunk_bytes=100, chunk_seconds=float('inf'),
                   background=True)
    a = w.add_channel('/a', 'std_msgs/msg/String')

    def fail(*args):
        raise OSError(28, 'No space left on device')
    monkeypatch.setattr(ChunkFinisher, '_write', fail)
    w.write(a, bytes(200), 1)               # a chunk handed over: the thread fails
    with pytest.raises(OSError, match='No space left'):
        w.close()
    assert w.closed
    assert not any(t.name.startswith('mcap-chunks') for t in threading.enumerate())


def _chunks(w, n):
    """Write n messages of 200 bytes to a writer of 100-byte chunks: n chunks handed over."""
    a = w.add_channel('/a', 'std_msgs/msg/String')
    for k in range(n):
        w.write(a, b'\x00\x01\x00\x00\x04\x00\x00\x00abc\x00' + bytes(188), 1000 + k)


def test_chunks_are_handed_over_without_waiting_for_the_thread(tmp_path, monkeypatch):
    """IN_FLIGHT chunks wait for a busy thread; then in order, the same bytes as without it."""
    go, real, written = threading.Event(), ChunkFinisher._write, []

    def slow(self, data, *args):
        assert go.wait(60), 'the thread was never let go'
        written.append(data)
        real(self, data, *args)
    monkeypatch.setattr(ChunkFinisher, '_write', slow)
    with McapWriter(tmp_path / 'thread.mcap', chunk_bytes=100, chunk_seconds=float('inf'),
                    background=True) as w:
        _chunks(w, IN_FLIGHT)       # the thread blocked on the first: none of them waited
        assert len(w._finisher._pending) == IN_FLIGHT and written == []
        go.set()
    with McapWriter(tmp_path / 'each.mcap', chunk_bytes=100, chunk_seconds=float('inf')) as w:
        _chunks(w, IN_FLIGHT)
    assert len(written) == IN_FLIGHT
    assert (tmp_path / 'thread.mcap').read_bytes() == (tmp_path / 'each.mcap').read_bytes()


def test_no_chunk_is_written_after_one_that_failed(tmp_path, monkeypatch):
    calls, real = [], ChunkFinisher._write

    def fail_second(self, *args):
        calls.append(len(calls))
        if len(calls) == 2:
            raise OSError(28, 'No space left on device')
        real(self, *args)
    monkeypatch.setattr(ChunkFinisher, '_write', fail_second)
    w = McapWriter(tmp_path / 'x.mcap', chunk_bytes=100, chunk_seconds=float('inf'),
                   background=True)
    with pytest.raises(OSError, match='No space left'):
        _chunks(w, IN_FLIGHT + 3)   # raised by a later hand-over, or by close()
        w.close()
    w.close()
    assert calls == [0, 1] and w.closed


@pytest.mark.parametrize('times, message', [
    (np.array([5, -1, 7]), r'log_time_ns must be in \[0, 2\*\*64\), got -1'),
    (np.array([5.0, 6.0, 7.0]), 'log_time_ns must be an int number of nanoseconds, got 5.0'),
    (np.array([True, False, True]), 'log_time_ns must be an int number of nanoseconds, got True'),
    ([5, 6, -3], r'log_time_ns must be in \[0, 2\*\*64\), got -3'),
])
def test_write_rows_refuses_the_times_write_refuses(tmp_path, times, message):
    """Integer arrays are checked at once (write_rows' fast path), the rest one by one: alike."""
    with McapWriter(tmp_path / 'bad.mcap', chunk_seconds=float('inf')) as w:
        a = w.add_channel('/a', 'std_msgs/msg/String')
        with pytest.raises(ValueError, match=message):
            w.write_rows([a], [np.zeros((3, 8), dtype=np.uint8)], times)
        with pytest.raises(ValueError, match=message.replace('log_', 'publish_')):
            w.write_rows([a], [np.zeros((3, 8), dtype=np.uint8)], [1, 2, 3], times)
        w.write_rows([a], [np.zeros((3, 8), dtype=np.uint8)], np.array([1, 2, 3]))
        assert w.counts == {'/a': 3}


def test_write_many_refuses_what_write_refuses_and_writes_nothing_then(tmp_path):
    """A bad message in a batch (unknown channel, negative time, not bytes): nothing written."""
    with McapWriter(tmp_path / 'bad.mcap', chunk_seconds=float('inf')) as w:
        a = w.add_channel('/a', 'std_msgs/msg/String')
        for bad, words in [((a + 7, b'x', 1, 1), 'not returned by add_channel'),
                           ((a, b'x', -1, 1), 'log_time_ns must be in'),
                           ((a, 'text', 1, 1), 'must be bytes')]:
            with pytest.raises(ValueError, match=words):
                w.write_many([(a, b'fine', 1, 1), bad])
        assert w.counts == {'/a': 0}

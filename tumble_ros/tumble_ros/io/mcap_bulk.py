"""
Append many fixed-size messages to an mcap ``Writer``'s chunk at once, with numpy.

mcap's ``Writer.add_message`` costs ~3-4 us a message in Python (a ``Message`` object, eight
small writes, an index tuple), and its ``MessageIndex.write`` packs every index entry apart
(~1 us each): for the 1.4 M messages of the Fig 9 main job, most of its wall time. Here a block
of n samples of m channels, each channel's messages of one fixed size (the per-sample topics),
becomes one numpy structured array whose bytes are exactly the n * m Message records
``add_message`` would have written, in the same order (sample by sample, channel by channel);
the index entries become arrays, packed in one call when the chunk is finalised.

This fills the ``Writer``'s private chunk builder and statistics (mcap 1.x,
``mcap/writer.py``): :func:`bulk_supported` checks they are there, and the caller falls back to
``add_message`` otherwise. ``test_io_roundtrip.py`` checks the file is byte for byte the one
``add_message`` writes.

:class:`ChunkFinisher` finalises the ``Writer``'s chunks in a thread: the caller hands over a
full chunk (its bytes and index entries, taken out of the chunk builder at once) and goes on
filling the next, while the thread compresses it (zstd releases the GIL), computes its CRC and
writes the Chunk and MessageIndex records and the chunk index as ``Writer.flush`` does, in the
same order: the same file byte for byte (``test_io_written.py``). The offline recording uses
it: ~0.2-0.4 s of the Fig 9 main job's critical path on the other core (benchmarks/HISTORY.md).
Up to :data:`IN_FLIGHT` chunks wait for the thread (one write of the Fig 9 run fills about
three: with one, the caller waited for each compression in turn, 0.1-0.17 s of that run);
after a chunk failed to be written the thread writes no later one.
"""
from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
import struct
from typing import Any, Callable, Sequence
import zlib

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import Chunk, ChunkIndex, MessageIndex
from mcap.writer import CompressionType, IndexType, Writer
import numpy as np
import zstandard

__all__ = ['bulk_supported', 'append_block', 'append_messages', 'ChunkFinisher', 'IN_FLIGHT']

#: Most chunks handed to a :class:`ChunkFinisher` and not yet written (memory: ``chunk_bytes``
#: each, uncompressed).
IN_FLIGHT = 8

#: A Message record's bytes before its data: opcode, length, channel, sequence, log and publish
#: time (mcap spec: 1 + 8 + 2 + 4 + 8 + 8).
_HEADER = 31


def _private(writer: Writer, name: str) -> Any:
    return getattr(writer, f'_Writer__{name}', None)


def bulk_supported(writer: Writer) -> bool:
    """Tell whether ``writer`` (an mcap ``Writer``) has the chunk builder this module fills."""
    builder = _private(writer, 'chunk_builder')
    stats = _private(writer, 'statistics')
    return (builder is not None and stats is not None
            and all(hasattr(builder, a) for a in ('record_writer', 'message_indices',
                                                  'num_messages', 'message_start_time',
                                                  'message_end_time'))
            and hasattr(builder.record_writer, 'write') and hasattr(stats, 'message_count'))


@dataclass
class _BlockIndex(MessageIndex):
    """A MessageIndex whose entries may come as arrays; written in one call."""

    def __post_init__(self) -> None:
        self.blocks: list[np.ndarray] = []

    def add_block(self, log_times: np.ndarray, offsets: np.ndarray) -> None:
        """Append entries (log time [ns], offset in the chunk), after those in ``records``."""
        if self.records:
            self.blocks.append(np.array(self.records, dtype='<u8').reshape(-1, 2))
            self.records.clear()
        self.blocks.append(np.column_stack([log_times, offsets]).astype('<u8'))

    def write(self, stream: RecordBuilder) -> None:
        """Write the record as MessageIndex.write does, the entries packed at once."""
        parts = self.blocks + ([np.array(self.records, dtype='<u8').reshape(-1, 2)]
                               if self.records else [])
        entries = np.concatenate(parts) if parts else np.empty((0, 2), dtype='<u8')
        stream.start_record(Opcode.MESSAGE_INDEX)
        stream.write2(self.channel_id)
        stream.write4(len(entries) * 16)
        stream.write(np.ascontiguousarray(entries, dtype='<u8').tobytes())
        stream.finish_record()  # type: ignore[no-untyped-call]  # unannotated in mcap


def _record_dtype(sizes: Sequence[int]) -> tuple[np.dtype[np.void], list[int]]:
    """Return the packed dtype of one sample's m records and each record's offset in it."""
    fields, offsets, at = [], [], 0
    for j, size in enumerate(sizes):
        fields += [(f'op{j}', 'u1'), (f'len{j}', '<u8'), (f'ch{j}', '<u2'), (f'seq{j}', '<u4'),
                   (f'log{j}', '<u8'), (f'pub{j}', '<u8'), (f'data{j}', 'u1', (size,))]
        offsets.append(at)
        at += _HEADER + size
    return np.dtype(fields), offsets


def _widen(span: Any, empty: bool, first: int, last: int) -> None:
    """Widen a chunk builder's or the statistics' message time span [ns] as add_message does."""
    span.message_start_time = first if empty else min(span.message_start_time, first)
    span.message_end_time = max(span.message_end_time, last)


def append_block(writer: Writer, channel_ids: Sequence[int], rows: Sequence[np.ndarray],
                 log_times: np.ndarray,
                 publish_times: np.ndarray) -> None:
    """
    Append n samples of m channels to ``writer``'s chunk in progress (one chunk, no flush).

    ``rows[j]``: (n, size_j) uint8, channel ``channel_ids[j]``'s messages; ``log_times``,
    ``publish_times``: (n,) [ns]. The same bytes, index entries and statistics as n * m calls of
    ``writer.add_message(channel, log, data, publish)`` sample by sample.
    """
    n = len(log_times)
    if n == 0:
        return
    builder = _private(writer, 'chunk_builder')
    stats = _private(writer, 'statistics')
    dtype, starts = _record_dtype([r.shape[1] for r in rows])
    records = np.empty(n, dtype=dtype)
    log = np.asarray(log_times, dtype=np.uint64)
    pub = np.asarray(publish_times, dtype=np.uint64)
    for j, (channel, data) in enumerate(zip(channel_ids, rows)):
        records[f'op{j}'] = int(Opcode.MESSAGE)
        records[f'len{j}'] = _HEADER - 9 + data.shape[1]
        records[f'ch{j}'] = channel
        records[f'seq{j}'] = 0
        records[f'log{j}'] = log
        records[f'pub{j}'] = pub
        records[f'data{j}'] = data
    base = builder.record_writer.count
    first, last = int(log.min()), int(log.max())
    _widen(builder, builder.num_messages == 0, first, last)
    sample = np.arange(n, dtype=np.uint64) * np.uint64(dtype.itemsize) + np.uint64(base)
    for j, channel in enumerate(channel_ids):
        index = builder.message_indices.get(channel)
        if not isinstance(index, _BlockIndex):
            index = _BlockIndex(channel_id=channel,
                                records=list(index.records) if index else [])
            builder.message_indices[channel] = index
        index.add_block(log, sample + np.uint64(starts[j]))
        stats.channel_message_counts[channel] += n
    builder.num_messages += n * len(rows)
    builder.record_writer.write(records.view(np.uint8).data)   # (not copied first)
    _widen(stats, stats.message_count == 0, first, last)
    stats.message_count += n * len(rows)


#: A Message record's header (see _HEADER), packed by struct.
_MESSAGE_HEADER = struct.Struct('<BQHIQQ')


def append_messages(writer: Writer, messages: Sequence[tuple[int, bytes, int, int]]) -> int:
    """
    Append messages of any sizes to ``writer``'s chunk in progress (one chunk, no flush).

    ``messages``: (channel id, data, log time [ns], publish time [ns]) each, in write order.
    The same bytes, index entries and statistics as one ``writer.add_message`` each (~3 us a
    message instead of ~20). Returns the bytes of data appended.
    """
    if not messages:
        return 0
    builder = _private(writer, 'chunk_builder')
    stats = _private(writer, 'statistics')
    offset = builder.record_writer.count
    parts: list[bytes] = []
    data_bytes = 0
    counts = stats.channel_message_counts
    for channel, data, log, pub in messages:
        index = builder.message_indices.get(channel)
        if not index:   # (as add_message: a new MessageIndex for a channel without entries)
            index = builder.message_indices[channel] = MessageIndex(channel_id=channel,
                                                                    records=[])
        index.records.append((log, offset))
        header = _MESSAGE_HEADER.pack(int(Opcode.MESSAGE), _HEADER - 9 + len(data), channel, 0,
                                      log, pub)
        parts += (header, data)
        offset += _HEADER + len(data)
        data_bytes += len(data)
        counts[channel] += 1
    logs = [m[2] for m in messages]
    first, last = min(logs), max(logs)
    _widen(builder, builder.num_messages == 0, first, last)
    builder.num_messages += len(messages)
    builder.record_writer.write(b''.join(parts))
    _widen(stats, stats.message_count == 0, first, last)
    stats.message_count += len(messages)
    return data_bytes


#: The compressions a :class:`ChunkFinisher` applies, as ``Writer.flush`` does: mcap's name of
#: it in the Chunk record and the function. (lz4 is left to the Writer.)
_COMPRESSORS: dict[CompressionType, tuple[str, Callable[[bytes], bytes]]] = {
    CompressionType.ZSTD: ('zstd', zstandard.compress),
    CompressionType.NONE: ('', bytes),
}
#: The Writer's private fields a ChunkFinisher reads or updates (mcap 1.x, ``mcap/writer.py``).
_FINISHER_FIELDS = ('chunk_builder', 'statistics', 'record_builder', 'stream', 'compression',
                    'enable_crcs', 'index_types', 'chunk_indices', 'flush')


def finisher_supported(writer: Writer) -> bool:
    """Tell whether a :class:`ChunkFinisher` can finalise ``writer``'s chunks."""
    return (bulk_supported(writer)
            and all(_private(writer, name) is not None for name in _FINISHER_FIELDS)
            and _private(writer, 'compression') in _COMPRESSORS)


class ChunkFinisher:
    """
    Finalise an mcap ``Writer``'s chunks in a thread, one at a time, in order (see the module).

    :meth:`finalize` takes the chunk in progress out of the writer and hands it to the thread;
    :meth:`wait` returns when every chunk handed over is written (raising what writing one
    raised); :meth:`close` waits and ends the thread. Only the thread writes to the writer's
    stream between :meth:`finalize` and :meth:`wait`: the caller must not call the writer's
    ``flush`` or ``finish`` meanwhile. Check :func:`finisher_supported` first.
    """

    def __init__(self, writer: Writer) -> None:
        if not finisher_supported(writer):
            raise ValueError('ChunkFinisher: this mcap Writer has not the private fields it '
                             f'needs ({", ".join(_FINISHER_FIELDS)}) or compresses with lz4')
        self._writer = writer
        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix='mcap-chunks')
        self._pending: deque[Future[None]] = deque()
        self._failed = False        # a chunk failed to be written: no later one is

    def finalize(self) -> bool:
        """Hand the chunk in progress to the thread (none without messages); True if handed."""
        builder = _private(self._writer, 'chunk_builder')
        if builder.num_messages == 0:
            return False
        # at most IN_FLIGHT chunks waiting (memory); errors raised in order, at the latest here
        while self._pending and (self._pending[0].done() or len(self._pending) >= IN_FLIGHT):
            self._pending.popleft().result()
        _private(self._writer, 'statistics').chunk_count += 1
        data = builder.end()
        indexes = list(builder.message_indices.items())
        start, end = builder.message_start_time, builder.message_end_time
        # ChunkBuilder.reset(), without clearing the index entries handed over
        builder.message_indices = {}
        builder.message_start_time = builder.message_end_time = 0
        builder.num_messages = 0
        self._pending.append(self._thread.submit(self._write_unless_failed, data, indexes,
                                                 start, end))
        return True

    def wait(self) -> None:
        """Return when every chunk handed over is written; raise what writing one raised."""
        while self._pending:
            self._pending.popleft().result()

    def _write_unless_failed(self, data: bytes, indexes: list[tuple[int, MessageIndex]],
                             start: int, end: int) -> None:
        """:meth:`_write`, unless an earlier chunk failed (the file ends with what was written)."""
        if self._failed:
            return
        try:
            self._write(data, indexes, start, end)
        except BaseException:
            self._failed = True
            raise

    def close(self) -> None:
        """Wait for the chunks handed over, then end the thread (also when writing failed)."""
        try:
            self.wait()
        finally:
            self._thread.shutdown(wait=True)

    def _write(self, data: bytes, indexes: list[tuple[int, MessageIndex]], start: int,
               end: int) -> None:
        """Compress and write one chunk, as mcap's ``Writer.__finalize_chunk`` and ``flush``."""
        writer = self._writer
        records: RecordBuilder = _private(writer, 'record_builder')
        stream = _private(writer, 'stream')
        flush = _private(writer, 'flush')
        name, compress = _COMPRESSORS[_private(writer, 'compression')]
        compressed = compress(data)
        chunk = Chunk(compression=name, data=compressed, message_start_time=start,
                      message_end_time=end,
                      uncompressed_crc=zlib.crc32(data) if _private(writer, 'enable_crcs') else 0,
                      uncompressed_size=len(data))
        flush()
        chunk_start = stream.tell()
        chunk.write(records)
        chunk_index = ChunkIndex(message_start_time=start, message_end_time=end,
                                 chunk_start_offset=chunk_start, chunk_length=records.count,
                                 message_index_offsets={}, message_index_length=0,
                                 compression=name, compressed_size=len(compressed),
                                 uncompressed_size=len(data))
        flush()
        index_start = stream.tell()
        if _private(writer, 'index_types') & IndexType.MESSAGE:
            for channel, index in indexes:
                chunk_index.message_index_offsets[channel] = index_start + records.count
                index.write(records)
        chunk_index.message_index_length = records.count
        flush()
        _private(writer, 'chunk_indices').append(chunk_index)
        stream.flush()

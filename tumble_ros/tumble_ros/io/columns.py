"""
Columnar reading of flat CDR messages: a topic's numeric fields as numpy columns.

Almost all of a recording is fixed-layout messages (``Vector3Stamped``, ``QuaternionStamped``,
``Clock``, ``ErrorNorm``): a header, maybe a string or two, then numbers. Decoding each one
generically (mcap-ros2-support builds a Python object per message, ~45 us) caps a reader at
~20,000 messages/s. Here a topic whose type is *flat* (its fields, flattened, are primitives and
strings: no sequence, no array) is read differently: the records of each decompressed chunk are
located once, and every numeric field of the topic's messages is gathered at its offset in one
numpy operation. The offsets are computed from the first message (the strings' lengths fix
them); a message whose size or string lengths differ from it is decoded by the generic decoder
and its values appended in order, so any file gives the same values as :func:`read_messages`
(the reference, tests/test_io_columns.py).

CDR (XCDR1, as ROS 2 writes it): a 4-byte encapsulation header (``00 01``: little endian), then
the fields in order, each primitive aligned to its own size counted from the end of that header;
a string is a uint32 length (including the terminating NUL) and its bytes.
"""
from __future__ import annotations

from collections.abc import Callable, Container, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
import os
from pathlib import Path
import queue
import struct
import threading
from typing import Any

from mcap.records import Message
import numpy as np
import numpy.typing as npt
from tumble_ros.topics import SampleTopic

from .mcap_reader import (chunk_records, Decoders, McapError, open_recording, RecordedMessage,
                          RecordScan, Registry, split_sections)
from .mcap_writer import WrittenBlock, WrittenMessages
from .msgdefs import MessageDefinitionError, parse_msg, SEPARATOR

__all__ = ['FlatLayout', 'FlatEncoder', 'MessageEncoder', 'MessageTemplate', 'TopicColumns',
           'read_columns', 'written_columns', 'encode_rows', 'sample_values',
           'BackgroundColumns', 'gather_in_background']

#: numpy types of the primitive types a flat layout may hold (strings apart), little-endian.
_DTYPES = {'bool': '<u1', 'byte': '<u1', 'char': '<u1', 'int8': '<i1', 'uint8': '<u1',
           'int16': '<i2', 'uint16': '<u2', 'int32': '<i4', 'uint32': '<u4', 'int64': '<i8',
           'uint64': '<u8', 'float32': '<f4', 'float64': '<f8'}
#: Their CDR sizes (and alignments) [bytes].
_SIZES = {name: np.dtype(code).itemsize for name, code in _DTYPES.items()}
_ENCAPSULATION = 4
_LITTLE_ENDIAN = (b'\x00\x01', b'\x00\x03')   # CDR_LE, PL_CDR_LE
_RECORD = struct.Struct('<BQ')                 # opcode, length
_MESSAGE = struct.Struct('<HIQQ')              # channel id, sequence, log time, publish time
_RECORD_AND_MESSAGE = struct.Struct('<BQHIQQ')
_MESSAGE_OPCODE = 0x05
_MESSAGE_HEAD = _RECORD.size + _MESSAGE.size   # 31 bytes before a message's data
#: A chunk's messages located: (channel ids, log times, data starts, data lengths), and whether
#: the chunk holds other records too.
_Located = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]


@dataclass(frozen=True)
class FlatLayout:
    """
    The flattened fields of a message type without sequences or arrays, in CDR order.

    ``fields``: (dotted name, primitive type) pairs, e.g. ('header.stamp.sec', 'int32'),
    ('header.frame_id', 'string'), ('vector.x', 'float64').
    """

    type_name: str
    fields: tuple[tuple[str, str], ...]

    @classmethod
    def from_schema(cls, type_name: str, schema_text: str) -> FlatLayout | None:
        """Return the layout of ``type_name`` from its ros2msg schema text; None if not flat."""
        specs = _specs(type_name, schema_text)
        if specs is None:
            return None
        fields: list[tuple[str, str]] = []
        if not _flatten(specs, _short(type_name), '', fields, depth=0):
            return None
        return cls(type_name, tuple(fields))

    def offsets(self, data: bytes) -> tuple[dict[str, int], dict[int, int]] | None:
        """
        Walk one message's CDR: (offset of each primitive field, {string length offset: length}).

        Offsets count from the start of ``data`` (the encapsulation header included). None when
        the message is not little-endian CDR or ends before its last field.
        """
        if data[:2] not in _LITTLE_ENDIAN:
            return None
        at, offsets, strings = 0, {}, {}
        size = len(data) - _ENCAPSULATION
        for name, kind in self.fields:
            if kind == 'string':
                at += -at % 4
                if at + 4 > size:
                    return None
                length = int.from_bytes(data[_ENCAPSULATION + at:_ENCAPSULATION + at + 4],
                                        'little')
                strings[_ENCAPSULATION + at] = length
                at += 4 + length
            else:
                width = _SIZES[kind]
                at += -at % width
                offsets[name] = _ENCAPSULATION + at
                at += width
            if at > size:
                return None
        return offsets, strings


def _specs(type_name: str, schema_text: str) -> dict[str, Any] | None:
    """Return {'pkg/Type': MsgSpec} of a ros2msg schema text (None if it does not parse)."""
    specs: dict[str, Any] = {}
    try:
        for header, body in split_sections(schema_text):
            name = type_name if not header else header.partition('MSG: ')[2].strip()
            if not name or header.startswith('SRV: '):
                return None
            package = name.split('/')[0]
            specs[_short(name)] = parse_msg(body, package, source=name)
    except MessageDefinitionError:
        return None
    return specs


def _short(type_name: str) -> str:
    """'pkg/msg/Type' or 'pkg/Type' -> 'pkg/Type'."""
    parts = type_name.split('/')
    return f'{parts[0]}/{parts[-1]}'


def _flatten(specs: dict[str, Any], type_name: str, prefix: str, out: list[tuple[str, str]],
             depth: int) -> bool:
    spec = specs.get(type_name)
    if spec is None or depth > 16:
        return False
    for f in spec.fields:
        if f.array is not None:
            return False
        name = prefix + f.name
        if f.type == 'string':
            out.append((name, 'string'))
        elif f.type in _SIZES:
            out.append((name, f.type))
        elif f.is_primitive:       # wstring and anything else not handled here
            return False
        elif not _flatten(specs, _short(f.type), name + '.', out, depth + 1):
            return False
    return True


@dataclass
class TopicColumns:
    """
    One topic's messages as columns, in file order.

    ``columns``: dotted field name -> (n,) array of every numeric field; ``log_time_ns`` (n,);
    ``strings``: dotted field name -> the distinct values of each string field, in order of
    first appearance; ``columnar``/``generic``: how many messages each path decoded.
    """

    topic: str
    type_name: str
    layout: FlatLayout
    log_time_ns: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    strings: dict[str, list[str]] = field(default_factory=dict)
    columnar: int = 0
    generic: int = 0

    def __len__(self) -> int:
        return len(self.log_time_ns)


class _Builder:
    """Collects one topic's columns, block by block (a block: its messages of one chunk)."""

    def __init__(self, topic: str, type_name: str, layout: FlatLayout):
        self.result = TopicColumns(topic, type_name, layout)
        self.times: list[np.ndarray] = []
        self.parts: dict[str, list[np.ndarray]] = {
            name: [] for name, kind in layout.fields if kind != 'string'}
        self.seen: dict[str, dict[str, None]] = {
            name: {} for name, kind in layout.fields if kind == 'string'}

    def add_block(self, buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
                  times: np.ndarray, decode_one: Callable[[bytes, int], Any]) -> None:
        """
        Add the messages whose data (``lengths`` bytes) start at ``starts`` in the chunk ``buf``.

        ``decode_one(data, k)`` decodes message k of them generically (k names it in an error).

        The CDR walk of :meth:`FlatLayout.offsets`, done for all messages at once (strings of any
        length); a message that is not little-endian CDR or ends early is decoded generically.
        """
        n = len(starts)
        ok = (_gather(buf, starts, 0, '<u1') == 0) & np.isin(_gather(buf, starts, 1, '<u1'),
                                                             (1, 3))
        size = lengths - _ENCAPSULATION
        at = np.zeros(n, dtype=np.int64)         # counted from the end of the encapsulation
        where: dict[str, np.ndarray] = {}        # field -> offset from the data's start
        spans: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for name, kind in self.result.layout.fields:
            width = 4 if kind == 'string' else _SIZES[kind]
            at += -at % width
            ok &= at + width <= size
            if kind == 'string':
                length = np.zeros(n, dtype=np.int64)
                length[ok] = _gather(buf, starts[ok] + at[ok], _ENCAPSULATION, '<u4')
                spans[name] = (at + _ENCAPSULATION + 4, length)
                at += 4 + length
                ok &= at <= size
            else:
                where[name] = at + _ENCAPSULATION
                at += width
        good = np.flatnonzero(ok)
        for name, kind in self.result.layout.fields:
            if kind == 'string':
                offset, length = spans[name]
                for text in _distinct_strings(buf, starts[good] + offset[good], length[good]):
                    self.seen[name].setdefault(text, None)
            else:
                column = np.zeros(n, dtype=_DTYPES[kind])
                column[good] = _gather(buf, starts[good] + where[name][good], 0, _DTYPES[kind])
                self.parts[name].append(column)
        for k in np.flatnonzero(~ok).tolist():   # in place, so the file order is kept
            start = int(starts[k])
            message = decode_one(buf[start:start + int(lengths[k])].tobytes(), k)
            self._set(message, k)
        self.times.append(np.asarray(times, dtype=np.int64))
        self.result.columnar += len(good)
        self.result.generic += n - len(good)

    def _set(self, message: Any, k: int) -> None:
        """Write a generically decoded message's values at row k of the last block."""
        for name, kind in self.result.layout.fields:
            value = _attribute(message, name)
            if kind == 'string':
                self.seen[name].setdefault(str(value), None)
            else:
                self.parts[name][-1][k] = value

    def add_generic(self, message: Any, log_time: int) -> None:
        """Add one generically decoded message (outside chunks)."""
        for name, kind in self.result.layout.fields:
            if kind != 'string':
                self.parts[name].append(np.zeros(1, dtype=_DTYPES[kind]))
        self._set(message, 0)
        self.times.append(np.array([log_time], dtype=np.int64))
        self.result.generic += 1

    def finish(self) -> TopicColumns:
        r = self.result
        r.log_time_ns = np.concatenate(self.times) if self.times else np.empty(0, np.int64)
        for name, kind in r.layout.fields:
            if kind != 'string':
                native = np.dtype(_DTYPES[kind]).newbyteorder('=')
                parts = self.parts[name]
                # (concatenate made a new array: cast, not copied again, when native already)
                r.columns[name] = (np.concatenate(parts) if parts
                                   else np.empty(0, native)).astype(native, copy=False)
        r.strings = {name: list(values) for name, values in self.seen.items()}
        return r


def _distinct_strings(buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray) -> list[str]:
    """Return the distinct strings (NUL stripped) at ``offsets``, in order of first appearance."""
    found: dict[int, str] = {}
    for length in np.unique(lengths).tolist():
        rows = np.flatnonzero(lengths == length)
        if length == 0:
            found[int(rows[0])] = ''
            continue
        text = buf[offsets[rows][:, None] + np.arange(length)]
        if (text == text[0]).all():
            firsts = [0]
        else:
            firsts = np.unique(text, axis=0, return_index=True)[1].tolist()
        for first in firsts:
            raw = text[first].tobytes().rstrip(b'\x00')
            found[int(rows[first])] = raw.decode('utf-8', 'replace')
    return [found[k] for k in sorted(found)]


def _gather(buf: np.ndarray, starts: np.ndarray, at: int, dtype: str) -> np.ndarray:
    """
    Return the values of type ``dtype`` at ``starts + at`` in ``buf``.

    Positions at a constant step (the same messages written sample after sample, in a chunk
    or in a writer's rows) are read through a strided view, the others by an index array.
    """
    width = np.dtype(dtype).itemsize
    where = starts + at
    if len(where) > 1:
        step = int(where[1] - where[0])
        last = int(where[0]) + step * (len(where) - 1)
        if step >= width and last + width <= len(buf) and (np.diff(where) == step).all():
            view = np.lib.stride_tricks.as_strided(buf[int(where[0]):], (len(where), width),
                                                   (step * buf.strides[0], buf.strides[0]),
                                                   writeable=False)
            return np.ascontiguousarray(view).view(dtype).reshape(-1)
    index = where[:, None] + np.arange(width)
    return np.ascontiguousarray(buf[index]).view(dtype).reshape(-1)


def _attribute(message: Any, dotted: str) -> Any:
    for part in dotted.split('.'):
        message = getattr(message, part)
    return message


def _chunk_messages(raw: bytes) -> _Located:
    """
    Locate the message records of a decompressed chunk.

    Returns (channel ids, log times, data starts, data lengths) as arrays, and whether the
    chunk also holds other records (schemas, channels).
    """
    channels: list[int] = []
    times: list[int] = []
    starts: list[int] = []
    lengths: list[int] = []
    others = False
    position, end = 0, len(raw)
    record, message = _RECORD.unpack_from, _RECORD_AND_MESSAGE.unpack_from
    last = end - _MESSAGE_HEAD
    while position < end:
        if position <= last:
            opcode, length, channel, _, log_time, _ = message(raw, position)
        else:
            (opcode, length), channel, log_time = record(raw, position), 0, 0
        if opcode == _MESSAGE_OPCODE:
            channels.append(channel)
            times.append(log_time)
            starts.append(position)
            lengths.append(length)
        else:
            others = True
        position += _RECORD.size + length
    return (np.array(channels, dtype=np.int64), np.array(times, dtype=np.int64),
            np.array(starts, dtype=np.int64) + _MESSAGE_HEAD,
            np.array(lengths, dtype=np.int64) - _MESSAGE.size, others)


def read_columns(path: str | os.PathLike[str], topics: Iterable[str],
                 as_messages: Iterable[str] = (), progress: Callable[[int], None] | None = None
                 ) -> tuple[dict[str, TopicColumns], list[RecordedMessage]]:
    """
    Read ``topics`` of ``path`` in one pass: flat topics as columns, the others decoded.

    Returns ({topic: TopicColumns} for the flat topics, [RecordedMessage] of the other requested
    topics, and of those in ``as_messages`` (decoded even if flat), in file order).
    ``progress(messages_read)`` is called after every chunk (all topics counted). Same file
    handling as :func:`~.mcap_reader.read_messages`: a truncated file gives the messages of its
    complete chunks; McapError for a file that cannot be read or a message that cannot be
    decoded.
    """
    wanted = _wanted(topics, as_messages)
    path, stream = open_recording(path)
    with stream:
        scan = RecordScan(path, stream)
        reader = _ColumnReader(path, scan, wanted, set(as_messages), progress)
        reader.read_file(scan)
    return reader.results()


def written_columns(written: WrittenMessages, topics: Iterable[str],
                    as_messages: Iterable[str] = (),
                    progress: Callable[[int], None] | None = None
                    ) -> tuple[dict[str, TopicColumns], list[RecordedMessage]]:
    """
    Return what :func:`read_columns` gives of a file, from the messages its writer kept.

    ``written``: the :class:`~.mcap_writer.WrittenMessages` a :class:`~.mcap_writer.McapWriter`
    filled while writing the file (``keep=``), in the same process: the same messages' bytes,
    gathered into columns by the same code (:class:`_Builder`) and decoded by the same decoders,
    without compressing, reading back and locating the records (tests/test_io_written.py
    compares both, array for array). ``progress(messages_read)`` after every written block.
    McapError as :func:`read_columns` for a message that cannot be decoded.
    """
    wanted = _wanted(topics, as_messages)
    reader = _ColumnReader(written.path or Path(), written, wanted, set(as_messages), progress)
    background, written.background = written.background, None
    if isinstance(background, BackgroundColumns):
        reader.adopt(background.finish())
    reader.read_written(written.blocks)
    return reader.results()


class _Everything:
    """Every topic wanted (the background gather's: which ones the reader wants comes later)."""

    def __contains__(self, topic: object) -> bool:
        return True


class BackgroundColumns:
    """
    The flat channels of a :class:`~.mcap_writer.WrittenMessages` gathered in a thread.

    Started before anything is written (:func:`gather_in_background`), it gathers each block
    into columns as the writer keeps it (``WrittenMessages.on_block``): the same
    :class:`_Builder` work :func:`written_columns` does after the file is closed, done while
    the caller simulates and writes (numpy's copies release the GIL; the main job's Fig 9 run:
    1.4 M messages, ~0.3 s of CPU on the other core instead of after the recording). Every
    flat channel is gathered (the reader's choice of topics comes later); the others, and the
    topics a reader wants as messages, are decoded by :func:`written_columns` as before.
    :func:`written_columns` takes the result (:meth:`finish`): the same columns
    (tests/test_io_background.py). An error of the thread is raised by :meth:`finish`.
    """

    def __init__(self, written: WrittenMessages) -> None:
        if written.blocks or written.on_block is not None:
            raise ValueError('gather_in_background: written must be new (nothing kept yet, no '
                             f'other follower), got {len(written.blocks)} block(s) kept and '
                             f'on_block={written.on_block!r}')
        self._written = written
        self._reader: _ColumnReader | None = None   # made at the first block: the path known
        self._blocks: queue.SimpleQueue[WrittenBlock | None] = queue.SimpleQueue()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name='tumble_ros-columns',
                                        daemon=True)
        written.on_block = self._blocks.put
        written.background = self
        self._thread.start()

    def _run(self) -> None:
        try:
            while (block := self._blocks.get()) is not None:
                if self._reader is None:    # its errors name the file, as written_columns'
                    self._reader = _ColumnReader(self._written.path or Path(), self._written,
                                                 _Everything(), set(), None, flat_only=True)
                self._reader.read_written((block,))
        except BaseException as err:  # noqa: BLE001 - raised by finish(), in the caller
            self._error = err
            while self._blocks.get() is not None:   # drain until told to stop
                pass

    def close(self) -> None:
        """Stop following the writer and end the thread (after the blocks kept so far)."""
        if self._written.on_block == self._blocks.put:
            self._written.on_block = None
        if self._thread.is_alive():
            self._blocks.put(None)
            self._thread.join()

    def finish(self) -> dict[int, _Builder | None]:
        """End the thread; return its builders by channel id; raise the thread's error."""
        self.close()
        if self._error is not None:
            raise self._error
        return {} if self._reader is None else self._reader.builders


def gather_in_background(written: WrittenMessages) -> BackgroundColumns:
    """
    Gather ``written``'s flat channels into columns in a thread as they are written.

    ``written``: a new :class:`~.mcap_writer.WrittenMessages`, before its writer writes;
    :func:`written_columns` of it then takes the columns gathered (:class:`BackgroundColumns`).
    Call :meth:`BackgroundColumns.close` when they will not be read (the thread is a daemon).
    """
    return BackgroundColumns(written)


def _wanted(topics: Iterable[str], as_messages: Iterable[str]) -> set[str]:
    wanted = set(topics) | set(as_messages)
    if not all(isinstance(t, str) for t in wanted):
        raise McapError(f'topics must be topic names (str), got {sorted(map(repr, wanted))}')
    return wanted


def sample_values(table: TopicColumns, topic: SampleTopic
                  ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """
    Return (stamps [ns], values (n, len(topic.fields))) of a per-sample topic read as columns.

    ``table``: the topic's :class:`TopicColumns` (:func:`read_columns`); ``topic``: its
    description (:class:`tumble_ros.topics.SampleTopic`), whose ``fields`` give the values'
    columns, in order, as floats. Rows in file order, stamps from ``header.stamp``.
    """
    c = table.columns
    stamps = (c['header.stamp.sec'].astype(np.int64) * 1_000_000_000
              + c['header.stamp.nanosec'].astype(np.int64))
    values = np.column_stack([c[name].astype(np.float64, copy=False)      # (stacked: a copy)
                              for name in topic.fields]).reshape(
        len(stamps), len(topic.fields))
    return stamps, values


class _ColumnReader:
    """
    One pass over a recording's messages: flat topics gathered, other messages decoded.

    The messages come from a file (:meth:`read_file`: chunks located and gathered) or from its
    writer's memory (:meth:`read_written`); ``scan``: their schemas and channels.
    """

    def __init__(self, path: Path, scan: Registry, wanted: Container[str],
                 as_messages: set[str], progress: Callable[[int], None] | None,
                 flat_only: bool = False):
        self.progress = progress
        self.flat_only = flat_only      # read_written: the flat channels only, others skipped
        self.adopted: set[int] = set()  # channels whose columns were gathered before
        self.scan = scan
        self.as_messages = as_messages
        self.decoders = Decoders(path)
        self.wanted = wanted
        self.builders: dict[int, _Builder | None] = {}
        self.others: list[RecordedMessage] = []
        self.count = 0

    def read_file(self, scan: RecordScan) -> None:
        """Read the file ``scan`` walks (``scan`` is :attr:`scan`)."""
        def locate(chunk: Any, data: bytes) -> Iterator[tuple[bytes, _Located]]:
            return self._locate(scan, chunk, data)

        for item in scan.items(locate):
            if isinstance(item, tuple):
                self._chunk(*item)
                if self.progress is not None:
                    self.progress(self.count)
            else:                               # a message outside chunks
                self._one(item.channel_id, item.log_time, item.publish_time, bytes(item.data))
        scan.check_recoverable(self.count)

    def read_written(self, blocks: Iterable[WrittenBlock]) -> None:
        """
        Read the blocks a writer kept, as :meth:`read_file` reads the file they made.

        A block's messages lie in the file sample by sample (for each k, one per channel): its
        flat channels are gathered from their rows, the others decoded in that order.
        """
        for block in blocks:
            n, width = len(block.log_time_ns), len(block.channel_ids)
            first = self.count
            pending: list[tuple[int, RecordedMessage]] = []
            for j, (channel_id, rows) in enumerate(zip(block.channel_ids, block.rows)):
                channel = self.scan.channels.get(channel_id)
                if (channel is not None and channel.topic not in self.wanted
                        or channel_id in self.adopted):
                    continue
                builder = self._builder(channel_id)
                if builder is None:
                    if self.flat_only:
                        continue
                    for k in range(n):
                        record = _Record(channel_id, int(block.log_time_ns[k]),
                                         int(block.publish_time_ns[k]), rows[k].tobytes())
                        at = k * width + j          # its place in the file
                        pending.append((at, self.decoders.decode(self.scan, record, first + at)))
                    continue

                def decode_one(raw: bytes, k: int, channel_id: int = channel_id,
                               at: int = first + j, width: int = width) -> Any:
                    # message k of this channel is the file's message first + k * width + j
                    return self.decoders.decode(self.scan, _Record(channel_id, 0, 0, raw),
                                                at + k * width).message

                size = rows.shape[1]
                builder.add_block(np.ascontiguousarray(rows).reshape(-1),
                                  np.arange(n, dtype=np.int64) * size,
                                  np.full(n, size, dtype=np.int64), block.log_time_ns,
                                  decode_one)
            self.count += n * width
            if pending:
                self.others.extend(m for _, m in sorted(pending, key=lambda item: item[0]))
            if self.progress is not None:
                self.progress(self.count)

    def adopt(self, gathered: Mapping[int, _Builder | None]) -> None:
        """
        Take the columns gathered before (:meth:`BackgroundColumns.finish`).

        Those of the wanted flat topics not wanted as messages: :meth:`read_written` then
        skips their channels. They are what this reader's own builders would gather (the same
        layout: a flat channel's builder does not depend on the other topics wanted).
        """
        for channel_id, builder in gathered.items():
            if (builder is not None and builder.result.topic in self.wanted
                    and builder.result.topic not in self.as_messages):
                self.builders[channel_id] = builder
                self.adopted.add(channel_id)

    def results(self) -> tuple[dict[str, TopicColumns], list[RecordedMessage]]:
        return ({b.result.topic: b.finish() for b in self.builders.values() if b is not None},
                self.others)

    @staticmethod
    def _locate(scan: RecordScan, chunk: Any, data: bytes) -> Iterator[tuple[bytes, _Located]]:
        """Find the chunk's messages (parsing only); keep its schemas and channels."""
        located = _chunk_messages(data)
        if located[4]:
            for record in chunk_records(chunk, data):
                if not isinstance(record, Message):
                    scan.add(record)
        yield (data, located)

    def _builder(self, channel_id: int) -> _Builder | None:
        if channel_id not in self.builders:
            channel = self.scan.channels.get(channel_id)
            schema = self.scan.schemas.get(channel.schema_id) if channel is not None else None
            layout = None
            if (channel is not None and schema is not None and channel.topic in self.wanted
                    and channel.topic not in self.as_messages
                    and channel.message_encoding == 'cdr' and schema.encoding == 'ros2msg'
                    and not schema.data.startswith(f'{SEPARATOR}\n'.encode())):
                layout = FlatLayout.from_schema(schema.name, schema.data.decode('utf-8',
                                                                                'replace'))
            self.builders[channel_id] = (
                _Builder(channel.topic, schema.name, layout)
                if layout is not None and channel is not None and schema is not None else None)
        return self.builders[channel_id]

    def _chunk(self, data: bytes, located: _Located) -> None:
        ids, times, starts, lengths, _ = located
        buf = np.frombuffer(data, dtype=np.uint8)
        first = self.count
        pending: list[tuple[int, RecordedMessage]] = []
        if len(ids) and (ids.min() != ids.max()):
            channel_ids = np.unique(ids).tolist()
        else:
            channel_ids = ids[:1].tolist()
        for channel_id in channel_ids:
            channel = self.scan.channels.get(channel_id)
            if channel is not None and channel.topic not in self.wanted:
                continue
            picked = np.flatnonzero(ids == channel_id)
            builder = self._builder(channel_id)
            if builder is None:
                for k in picked.tolist():
                    _, _, log_time, publish_time = _MESSAGE.unpack_from(
                        data, int(starts[k]) - _MESSAGE.size)
                    record = _Record(channel_id, log_time, publish_time,
                                     data[starts[k]:starts[k] + lengths[k]])
                    pending.append((k, self.decoders.decode(self.scan, record, first + k)))
                continue

            def decode_one(raw: bytes, k: int, channel_id: int = channel_id,
                           at: np.ndarray = first + picked) -> Any:
                # message k of this channel is the chunk's message picked[k]
                return self.decoders.decode(self.scan, _Record(channel_id, 0, 0, raw),
                                            int(at[k])).message

            builder.add_block(buf, starts[picked], lengths[picked], times[picked], decode_one)
        self.count += len(ids)
        if pending:  # the other topics' messages of this chunk, in file order
            self.others.extend(m for _, m in sorted(pending, key=lambda item: item[0]))

    def _one(self, channel_id: int, log_time: int, publish_time: int, data: bytes,
             index: int | None = None) -> None:
        """Decode one message generically: into its topic's builder, or onto ``others``."""
        if index is None:
            index = self.count
            self.count += 1
        channel = self.scan.channels.get(channel_id)
        if channel is not None and channel.topic not in self.wanted:
            return
        record = _Record(channel_id, log_time, publish_time, data)
        builder = self._builder(channel_id)
        if builder is not None:
            builder.add_generic(self.decoders.decode(self.scan, record, index).message, log_time)
            return
        self.others.append(self.decoders.decode(self.scan, record, index))


class _Record:
    """The fields of an MCAP message record that the decoders use."""

    __slots__ = ('channel_id', 'log_time', 'publish_time', 'data')

    def __init__(self, channel_id: int, log_time: int, publish_time: int, data: bytes):
        self.channel_id, self.log_time = channel_id, log_time
        self.publish_time, self.data = publish_time, data


def encode_rows(layout: FlatLayout, count: int, values: dict[str, np.ndarray],
                strings: dict[str, str]) -> np.ndarray:
    """
    Return ``count`` CDR messages of a flat type as a (count, size) uint8 array, one per row.

    The inverse of the columnar read: ``values`` holds every numeric field (dotted name ->
    (count,) array, cast to the field's type), ``strings`` every string field (one value for
    all rows). Little-endian CDR as ROS 2 serializes it (tests/test_node_messages.py compares
    with rclpy's messages). :class:`FlatEncoder` does the same and keeps the template.
    """
    return FlatEncoder(layout, strings).rows(count, values)


def _template_rows(template: np.ndarray, fields: dict[str, tuple[int, str]], count: int,
                   values: dict[str, np.ndarray]) -> np.ndarray:
    """
    Return ``count`` copies of the message ``template`` (uint8), ``values`` written into them.

    ``fields``: path -> (offset, primitive type); ``values``: path -> (count,) column or a number
    (cast to the field's type). KeyError for a path not in ``fields``.
    """
    rows = np.empty((count, template.size), dtype=np.uint8)
    rows[:] = template
    for name, column in values.items():
        offset, kind = fields[name]
        width = _SIZES[kind]
        data = np.ascontiguousarray(np.broadcast_to(column, (count,)), dtype=_DTYPES[kind])
        rows[:, offset:offset + width] = data.view(np.uint8).reshape(count, width)
    return rows


#: struct codes of the primitive types (little-endian, no alignment: offsets are explicit).
_STRUCT_CODES = {'bool': '?', 'byte': 'B', 'char': 'B', 'int8': 'b', 'uint8': 'B', 'int16': 'h',
                 'uint16': 'H', 'int32': 'i', 'uint32': 'I', 'int64': 'q', 'uint64': 'Q',
                 'float32': 'f', 'float64': 'd'}


class FlatEncoder:
    """
    Messages of a flat type whose strings are fixed: their CDR bytes, n rows or one at a time.

    The template (encapsulation header, strings, zero padding) and the offset of every numeric
    field are worked out once; :meth:`rows` writes columns into n copies of it (numpy), and
    :meth:`one` packs one message's numbers into one copy (``struct``, ~1 us: what a node that
    receives samples one at a time publishes).
    """

    def __init__(self, layout: FlatLayout, strings: dict[str, str]):
        template = bytearray(b'\x00\x01\x00\x00')
        #: numeric field path -> (offset, primitive type), in CDR order
        self.fields: dict[str, tuple[int, str]] = {}
        at = 0
        for name, kind in layout.fields:
            width = 4 if kind == 'string' else _SIZES[kind]
            pad = -at % width
            template += b'\x00' * pad
            at += pad
            if kind == 'string':
                text = strings[name].encode() + b'\x00'
                template += len(text).to_bytes(4, 'little') + text
                at += 4 + len(text)
            else:
                self.fields[name] = (_ENCAPSULATION + at, kind)
                template += b'\x00' * width
                at += width
        self.template = bytes(template)
        self._rows_template = np.frombuffer(self.template, dtype=np.uint8)
        self._runs = self._packing_runs()

    def _packing_runs(self) -> list[tuple[int, struct.Struct, int]]:
        """Group adjacent numeric fields: [(offset, Struct of the run, number of fields)]."""
        runs: list[list[Any]] = []
        end = -1
        for offset, kind in self.fields.values():
            if offset != end:
                runs.append([offset, '<', 0])
            runs[-1][1] += _STRUCT_CODES[kind]
            runs[-1][2] += 1
            end = offset + _SIZES[kind]
        return [(offset, struct.Struct(codes), n) for offset, codes, n in runs]

    def rows(self, count: int, values: dict[str, np.ndarray]) -> np.ndarray:
        """Encode ``count`` messages, one per row of a uint8 array (``values``: name -> column)."""
        missing = [name for name in self.fields if name not in values]
        if missing:
            raise KeyError(f'{missing[0]}: no values for this field')
        return _template_rows(self._rows_template, self.fields, count, values)

    def one(self, *numbers: float) -> bytes:
        """Return one message whose numeric fields hold ``numbers`` (in :attr:`fields` order)."""
        data = bytearray(self.template)
        k = 0
        for offset, packer, n in self._runs:
            packer.pack_into(data, offset, *numbers[k:k + n])
            k += n
        return bytes(data)


class MessageTemplate:
    """
    Messages of one shape (the same strings and sequence lengths), numbers from numpy columns.

    A ``visualization_msgs/MarkerArray`` of one scene differs from sample to sample only in its
    numbers (stamps, poses, points): its CDR bytes have the same length and the numbers sit at
    the same offsets. ``MessageTemplate(type_name, schema_text, data)`` walks one serialised
    message ``data`` (rclpy's ``serialize_message``) once and finds the offset of every numeric
    field, named by its path (``markers[2].pose.orientation.w``); :meth:`encode` then writes
    n messages as rows of a (n, size) uint8 array, the template's bytes with the given
    columns put in: ~1 us a message instead of ~1 ms for building and serialising one in
    Python. Padding bytes are zero. ValueError when the type is not known to the schema or
    ``data`` does not hold a message of it.
    """

    def __init__(self, type_name: str, schema_text: str, data: bytes):
        specs = _specs(type_name, schema_text)
        if specs is None or _short(type_name) not in specs:
            raise ValueError(f'{type_name}: no usable ros2msg definition')
        if data[:2] not in _LITTLE_ENDIAN:
            raise ValueError(f'{type_name}: not little-endian CDR')
        self.type_name = type_name
        self.fields: dict[str, tuple[int, str]] = {}     # path -> (offset, primitive type)
        body = np.frombuffer(data, dtype=np.uint8)[_ENCAPSULATION:]
        clean = np.zeros(len(body), dtype=np.uint8)      # the template, padding zeroed
        end = self._walk(specs, _short(type_name), body, clean, 0, '')
        if not 0 <= len(body) - end < 8:      # (CDR may pad the end to a multiple of 4 or 8)
            raise ValueError(f'{type_name}: {len(body)} bytes of CDR, the definition reads {end}')
        self.template = np.concatenate([np.frombuffer(data[:_ENCAPSULATION], dtype=np.uint8),
                                        clean[:len(body)]])

    def _walk(self, specs: dict[str, Any], type_name: str, body: np.ndarray, clean: np.ndarray,
              at: int, prefix: str) -> int:
        for f in specs[type_name].fields:
            name = prefix + f.name
            if f.array is None:
                at = self._one(specs, f, body, clean, at, name)
                continue
            if f.array == '' or f.array.startswith('<='):
                at += -at % 4
                count = int.from_bytes(bytes(body[at:at + 4]), 'little')
                clean[at:at + 4] = body[at:at + 4]
                at += 4
            else:
                count = int(f.array)
            for k in range(count):
                at = self._one(specs, f, body, clean, at, f'{name}[{k}]')
        return at

    def _one(self, specs: dict[str, Any], f: Any, body: np.ndarray, clean: np.ndarray, at: int,
             name: str) -> int:
        if f.type == 'string':
            at += -at % 4
            length = int.from_bytes(bytes(body[at:at + 4]), 'little')
            clean[at:at + 4 + length] = body[at:at + 4 + length]
            return at + 4 + length
        if f.type in _SIZES:
            width = _SIZES[f.type]
            at += -at % width
            if at + width > len(body):
                raise ValueError(f'{self.type_name}: the message ends inside {name}')
            self.fields[name] = (_ENCAPSULATION + at, f.type)
            clean[at:at + width] = body[at:at + width]
            return at + width
        if f.is_primitive:
            raise ValueError(f'{self.type_name}: {name}: type {f.type} is not handled')
        return self._walk(specs, _short(f.type), body, clean, at, name + '.')

    @property
    def size(self) -> int:
        """Return the size of one message [bytes], its encapsulation header included."""
        return len(self.template)

    def encode(self, count: int, values: dict[str, np.ndarray]) -> np.ndarray:
        """
        Return ``count`` messages as a (count, size) uint8 array, one CDR message per row.

        ``values``: field path -> (count,) array or a number (cast to the field's type); the
        fields not given keep the template's values. KeyError for a path the type lacks.
        """
        return _template_rows(self.template, self.fields, count, values)


#: MessageEncoder's plan steps: a run of numbers, a string, a sequence (or array) of messages.
_NUMBERS, _STRING, _MESSAGES = 0, 1, 2
#: CDR alignment phases of a run of numbers: its offset modulo the largest primitive size.
_PHASES = 8
#: Strings MessageEncoder keeps encoded (their CDR bytes, by text): a run's repeated ones.
_STRINGS_KEPT = 64
_ZEROS = tuple(bytes(n) for n in range(4))
#: struct codes of MessageEncoder's values: rclpy's Python types (a ``byte`` is a bytes of one).
_VALUE_CODES = {**_STRUCT_CODES, 'byte': 'c'}


class MessageEncoder:
    """
    Messages of a type made of numbers, strings and sequences of messages: CDR bytes from values.

    For the messages whose strings change from one to the next (a scenario description, an
    impact event, a status line), which :class:`FlatEncoder` (fixed strings) does not cover and
    rclpy builds as Python objects (~8 us) before serialising them (~5-9 us): the type's
    definition is walked once into a plan (runs of adjacent numbers packed by one ``struct``
    each, for each alignment phase the run may start at; strings; sequences of messages), and
    :meth:`encode` follows it, ~2-4 us a message. The bytes are rclpy's (little-endian CDR,
    XCDR1) with zero padding (rclpy leaves its padding bytes as they were: tests/
    test_record_messages.py compares every field and the length). ``fields`` names the values
    :meth:`encode` takes, in CDR order (nested fields dotted, as :class:`FlatLayout`'s). A
    field that is an array of primitives is not handled (ValueError at construction).
    """

    def __init__(self, type_name: str, schema_text: str):
        specs = _specs(type_name, schema_text)
        if specs is None or _short(type_name) not in specs:
            raise ValueError(f'{type_name}: no usable ros2msg definition')
        self.type_name = type_name
        #: the values :meth:`encode` takes, in order: a sequence field takes one value, a
        #: sequence of tuples (the values of each element's fields, in order)
        self.fields: tuple[str, ...] = ()
        names: list[str] = []
        self._plan = self._compile(specs, _short(type_name), '', names, 0)
        self.fields = tuple(names)
        self._strings: dict[str, bytes] = {}

    def _compile(self, specs: dict[str, Any], type_name: str, prefix: str, names: list[str],
                 depth: int) -> list[tuple[Any, ...]]:
        """Return the plan of ``type_name``'s fields, their names appended to ``names``."""
        plan: list[tuple[Any, ...]] = []
        run: list[str] = []
        self._walk(specs, type_name, prefix, names, depth, plan, run)
        self._close(plan, run)
        return plan

    def _walk(self, specs: dict[str, Any], type_name: str, prefix: str, names: list[str],
              depth: int, plan: list[tuple[Any, ...]], run: list[str]) -> None:
        spec = specs.get(type_name)
        if spec is None or depth > 16:
            raise ValueError(f'{self.type_name}: no definition of {type_name}')
        for f in spec.fields:
            name = prefix + f.name
            if f.array is not None:
                if f.is_primitive:
                    raise ValueError(f'{self.type_name}: {name}: arrays of {f.type} are not '
                                     'handled')
                self._close(plan, run)
                fixed = None if f.array == '' or f.array.startswith('<=') else int(f.array)
                bound = int(f.array[2:]) if f.array.startswith('<=') else None
                element = self._compile(specs, _short(f.type), '', [], depth + 1)
                plan.append((_MESSAGES, fixed, bound, element, name))
                names.append(name)
            elif f.type == 'string':
                self._close(plan, run)
                plan.append((_STRING,))
                names.append(name)
            elif f.type in _SIZES:
                run.append(f.type)
                names.append(name)
            elif f.is_primitive:
                raise ValueError(f'{self.type_name}: {name}: type {f.type} is not handled')
            else:
                self._walk(specs, _short(f.type), name + '.', names, depth + 1, plan, run)

    @staticmethod
    def _close(plan: list[tuple[Any, ...]], run: list[str]) -> None:
        """Append the run of numbers ``run`` (emptied) to ``plan``: one Struct per phase."""
        if not run:
            return
        structs = []
        for phase in range(_PHASES):
            at, codes = phase, '<'
            for kind in run:
                pad = -at % _SIZES[kind]
                codes += 'x' * pad + _VALUE_CODES[kind]
                at += pad + _SIZES[kind]
            structs.append(struct.Struct(codes))
        plan.append((_NUMBERS, tuple(structs), len(run)))
        run.clear()

    def encode(self, *values: Any) -> bytes:
        """
        Return one message holding ``values`` (one per name of :attr:`fields`, in order).

        Numbers as rclpy takes them (int for integer types, float, bool, bytes of one for
        ``byte``), str for strings, a sequence of tuples for a sequence of messages. struct.error
        for a value of the wrong type or range, ValueError for a sequence of the wrong length.
        """
        out = bytearray(b'\x00\x01\x00\x00')
        self._encode(self._plan, values, out)
        return bytes(out)

    def _encode(self, plan: list[tuple[Any, ...]], values: Sequence[Any], out: bytearray) -> None:
        i = 0
        for step in plan:
            kind = step[0]
            if kind == _NUMBERS:
                n = step[2]
                # the phase: the offset after the encapsulation header, modulo 8
                out += step[1][(len(out) - _ENCAPSULATION) % _PHASES].pack(*values[i:i + n])
                i += n
            elif kind == _STRING:
                text = values[i]
                i += 1
                encoded = self._strings.get(text)
                if encoded is None:   # (a run's descriptions repeat one scenario text of ~1 kB)
                    raw = text.encode() + b'\x00'
                    encoded = len(raw).to_bytes(4, 'little') + raw
                    if len(self._strings) >= _STRINGS_KEPT:
                        self._strings.clear()
                    self._strings[text] = encoded
                out += _ZEROS[-len(out) % 4]
                out += encoded
            else:
                _, fixed, bound, element, name = step
                items = values[i]
                i += 1
                if fixed is None:
                    if bound is not None and len(items) > bound:
                        raise ValueError(f'{name}: at most {bound} elements, got {len(items)}')
                    out += _ZEROS[-len(out) % 4]
                    out += len(items).to_bytes(4, 'little')
                elif len(items) != fixed:
                    raise ValueError(f'{name}: {fixed} elements, got {len(items)}')
                for item in items:
                    self._encode(element, item, out)

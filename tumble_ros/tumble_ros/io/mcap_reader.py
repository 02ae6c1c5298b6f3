"""
Read ROS 2 MCAP recordings without a ROS runtime (mcap + mcap-ros2-support, no rclpy).

- :func:`read_messages` streams the decoded messages of a file in file order. It reads the file
  front to back like a non-seeking reader, so a file whose writer was killed (no summary, last
  chunk cut off) yields every message of its complete chunks and then stops cleanly.
- :func:`summarize` tells what a file holds: profile, topics with types and message counts, first
  and last log time, chunk count, and whether the file was finalised (summary and footer written
  by a clean close) or is truncated.

Every failure is an :class:`McapError` with a one-line message naming the file: a missing,
unreadable or empty file, a path that is not a regular file (a directory, a FIFO, a device: a FIFO
would block the reader forever, so it is refused before any read), a file that is not MCAP (bad
magic), a truncated file without a single complete chunk, a message that cannot be decoded (topic
and type named). Library errors are translated at this boundary.

The work and the memory are bounded by the file's size: a record that declares more bytes than
remain in the file ends the reading at once (it is a truncation, nothing is allocated for it),
and a chunk may expand to at most :data:`MAX_CHUNK_RATIO` times its compressed size and
:data:`MAX_CHUNK_BYTES` in all; a chunk that declares more is damaged (it is not decompressed).
Decompression never produces more than the declared size.

Service introspection events (``pkg/srv/Name_Event``) recorded by rosbag2 (Jazzy) or by
:class:`~tumble_ros.io.mcap_writer.McapWriter` carry a schema holding the ``.srv`` file
(``SRV: pkg/srv/Name``, see :mod:`tumble_ros.io.msgdefs`), which generic ros2msg decoders cannot
use; it is rewritten here into the event's real layout (``service_msgs/ServiceEventInfo info``,
``Name_Request[<=1] request``, ``Name_Response[<=1] response``) before decoding.
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
import io
import os
from pathlib import Path
import stat
import struct
from typing import Any
import zlib

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (Channel, Chunk, ChunkIndex, Footer, Header, Message, Schema,
                          Statistics)
from mcap_ros2.decoder import DecoderFactory

from tumble_ros.errors import IoError

try:                                # both come with mcap; a missing one only refuses its chunks
    import lz4.frame as lz4_frame
except ImportError:  # pragma: no cover
    lz4_frame = None
try:
    import zstandard
except ImportError:  # pragma: no cover
    zstandard = None

__all__ = ['MAX_CHUNK_BYTES', 'MAX_CHUNK_RATIO', 'McapError', 'McapSummary', 'RecordedMessage',
           'TopicSummary', 'read_messages', 'summarize']

MAGIC = b'\x89MCAP0\r\n'
_SEPARATOR = '=' * 80
_FOOTER_LENGTH = 8 + 8 + 4
_RECORD_HEADER = 9            # opcode (1) + length (8)
#: A chunk that declares an uncompressed size above this many times its compressed size is
#: damaged (or hostile: a zstd frame of zeros expands ~30,000 times). Recorded CDR compresses
#: 3-5 times with zstd; lz4 cannot exceed ~255 times.
MAX_CHUNK_RATIO = 1000
#: ... or above this many bytes in all: the recorder's largest ``chunk_bytes`` (1 GiB) with room
#: for the message that crosses it.
MAX_CHUNK_BYTES = 2 * 2 ** 30


class McapError(IoError):
    """Any failure to read an MCAP file (one-line message naming the file)."""


@dataclass(frozen=True)
class RecordedMessage:
    """One decoded message: attribute access to its fields (``m.message.header.stamp.sec``)."""

    topic: str
    type_name: str
    log_time_ns: int
    publish_time_ns: int
    message: Any


@dataclass(frozen=True)
class TopicSummary:
    type_name: str
    message_count: int
    message_encoding: str = 'cdr'
    schema_encoding: str = 'ros2msg'


@dataclass(frozen=True)
class McapSummary:
    """
    What :func:`summarize` found in a file.

    ``finalised``: the file ends with a footer and the closing magic (a clean close wrote the
    summary); ``truncated`` is its negation (the writer died, or the file was cut).
    ``start_time_ns``/``end_time_ns``: first/last log time (None without messages).
    ``problem``: why reading stopped before a footer (None for a finalised file).
    """

    path: Path
    profile: str
    library: str
    topics: dict[str, TopicSummary]
    message_count: int
    start_time_ns: int | None
    end_time_ns: int | None
    chunk_count: int
    finalised: bool
    problem: str | None = None
    compressions: tuple[str, ...] = field(default=())

    @property
    def truncated(self) -> bool:
        return not self.finalised


def _one_line(text: object) -> str:
    return ' '.join(str(text).split()) or type(text).__name__


def _describe(err: BaseException) -> str:
    text = _one_line(err)
    name = type(err).__name__
    return text if text == name else f'{name}: {text}'


# -- record stream ------------------------------------------------------------------------------

class _Truncated(Exception):
    """The record stream ends (or breaks) before the footer."""


_FILE_KINDS = ((stat.S_ISDIR, 'is a directory'), (stat.S_ISFIFO, 'is a FIFO (named pipe)'),
               (stat.S_ISCHR, 'is a character device'), (stat.S_ISBLK, 'is a block device'),
               (stat.S_ISSOCK, 'is a socket'))


def _not_regular(path: Path, mode: int) -> McapError:
    kind = next((text for test, text in _FILE_KINDS if test(mode)), 'is not a regular file')
    return McapError(f'{path}: {kind}, not an MCAP file (only regular files are read)')


def _open_regular(path: Path) -> io.BufferedReader:
    """
    Open ``path`` for reading without ever blocking on it.

    O_NONBLOCK makes the open of a FIFO return at once, and the opened file (not the name,
    which may change) must be a regular file.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, 'O_NONBLOCK', 0))
    except FileNotFoundError:
        raise McapError(f'{path}: no such file') from None
    except IsADirectoryError:
        raise McapError(f'{path}: is a directory, not an MCAP file') from None
    except OSError as err:
        try:
            mode = os.stat(path).st_mode      # a socket fails to open: say what it is
        except OSError:
            mode = stat.S_IFREG
        if not stat.S_ISREG(mode):
            raise _not_regular(path, mode) from None
        raise McapError(f'{path}: cannot open: {_one_line(err.strerror or err)}') from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise _not_regular(path, mode)
        os.set_blocking(fd, True)
        return os.fdopen(fd, 'rb')
    except BaseException:
        os.close(fd)
        raise


def _open(path) -> tuple[Path, io.BufferedReader]:
    try:
        path = Path(os.fspath(path))
    except TypeError:
        raise McapError(f'not a file path: {path!r}') from None
    stream = _open_regular(path)
    try:
        magic = stream.read(len(MAGIC))
    except OSError as err:
        stream.close()
        raise McapError(f'{path}: cannot read: {_one_line(err.strerror or err)}') from None
    if not magic:
        stream.close()
        raise McapError(f'{path}: empty file (0 bytes), not an MCAP file')
    if magic != MAGIC:
        stream.close()
        if MAGIC.startswith(magic):
            raise McapError(f'{path}: truncated after {len(magic)} bytes: no complete chunk')
        raise McapError(f'{path}: not an MCAP file (bad magic {magic[:8]!r})')
    return path, stream


def _remaining(stream) -> int:
    """Return the bytes from the stream's position to the end of the file (as it is now)."""
    return os.fstat(stream.fileno()).st_size - stream.tell()


def _records(stream) -> Iterator[tuple[int, bytes]]:
    """
    (opcode, body) of each record after the magic, up to and including the footer.

    Raises _Truncated where the stream ends or breaks before the footer and its closing magic,
    and at once, before reading it, for a record longer than what remains of the file.
    """
    while True:
        head = stream.read(_RECORD_HEADER)
        if len(head) < _RECORD_HEADER:
            raise _Truncated('file ends before the footer' if not head
                             else 'file ends inside a record header')
        opcode, length = struct.unpack('<BQ', head)
        remaining = _remaining(stream)
        if length > remaining:
            raise _Truncated(f'file ends inside a record (opcode {opcode:#x}, '
                             f'{remaining} of {length} bytes)')
        body = stream.read(length)
        if len(body) < length:
            raise _Truncated(f'file ends inside a record (opcode {opcode:#x}, '
                             f'{len(body)} of {length} bytes)')
        yield opcode, body
        if opcode == Opcode.FOOTER:
            if stream.read(len(MAGIC)) != MAGIC:
                raise _Truncated('footer without the closing magic')
            return


def _parse(cls, body: bytes, *args):
    return cls.read(ReadDataStream(io.BytesIO(body)), *args)


class _Damaged(Exception):
    """A record that is complete in the file but cannot be used (one-line message)."""


def _check_chunk_size(chunk: Chunk) -> None:
    size, packed = chunk.uncompressed_size, len(chunk.data)
    compression = chunk.compression or 'none'
    if size > MAX_CHUNK_BYTES:
        raise _Damaged(f'a chunk declares {size} bytes uncompressed, more than the limit of '
                       f'{MAX_CHUNK_BYTES}: refused')
    if size > MAX_CHUNK_RATIO * max(packed, 1):
        raise _Damaged(f'a chunk declares {size} bytes uncompressed from {packed} bytes of '
                       f'{compression} data, more than {MAX_CHUNK_RATIO} times: refused')


def _read_exactly(reader, size: int) -> bytes:
    """Return the ``size`` bytes ``reader`` produces; _Damaged if it produces fewer or more."""
    buffer = bytearray(size + 1)           # one more: a stream that goes on is an error too
    view = memoryview(buffer)
    got = 0
    while got < len(buffer):
        n = reader.readinto(view[got:])
        if not n:
            break
        got += n
    view.release()
    if got != size:
        raise _Damaged(f'a chunk decompresses to {"more than " if got > size else ""}'
                       f'{min(got, size)} bytes, it declares {size}')
    del buffer[size:]
    return bytes(buffer)


class _Lz4Reader:
    """readinto() over an lz4 frame, never producing more than asked for."""

    def __init__(self, data: bytes):
        self.decompressor = lz4_frame.LZ4FrameDecompressor()
        self.data = data

    def readinto(self, view) -> int:
        if self.decompressor.eof:
            return 0
        out = self.decompressor.decompress(self.data, max_length=len(view))
        self.data = b''
        view[:len(out)] = out
        return len(out)


def _decompressing_reader(chunk: Chunk):
    """Return a reader (readinto) of the chunk's decompressed records; None if uncompressed."""
    compression = chunk.compression or 'none'
    if compression == 'none':
        return None
    module = {'zstd': zstandard, 'lz4': lz4_frame}.get(compression, False)
    if module is False:
        raise _Damaged(f'a chunk has unknown compression {compression!r}')
    if module is None:
        raise _Damaged(f'a chunk is {compression}-compressed and its Python module is missing')
    if compression == 'lz4':
        return _Lz4Reader(chunk.data)
    return zstandard.ZstdDecompressor().stream_reader(io.BytesIO(chunk.data),
                                                      read_across_frames=True)


def _chunk_data(chunk: Chunk) -> bytes:
    """Return the chunk's records, decompressed to at most its declared size, CRC checked."""
    _check_chunk_size(chunk)
    reader = _decompressing_reader(chunk)
    data = chunk.data if reader is None else _read_exactly(reader, chunk.uncompressed_size)
    if chunk.uncompressed_crc != 0 and zlib.crc32(data) != chunk.uncompressed_crc:
        raise _Damaged('a chunk fails its CRC check')
    return data


def _chunk_records(chunk: Chunk) -> list[Schema | Channel | Message]:
    """
    Return the schemas, channels and messages of a chunk.

    As the mcap library's breakup_chunk, with every record's length checked against what
    remains of the chunk.
    """
    data = _chunk_data(chunk)
    stream = ReadDataStream(io.BytesIO(data))
    records: list[Schema | Channel | Message] = []
    while stream.count < len(data):
        if len(data) - stream.count < _RECORD_HEADER:
            raise _Damaged('a chunk ends inside a record header')
        opcode, length = stream.read1(), stream.read8()
        if length > len(data) - stream.count:
            raise _Damaged(f'a record in a chunk (opcode {opcode:#x}) declares {length} bytes, '
                           f'{len(data) - stream.count} remain in the chunk')
        if opcode == Opcode.SCHEMA:
            records.append(Schema.read(stream))
        elif opcode == Opcode.CHANNEL:
            records.append(Channel.read(stream))
        elif opcode == Opcode.MESSAGE:
            records.append(Message.read(stream, length))
        else:
            stream.read(length)
    return records


class _Scan:
    """Walks a file's records; collects schemas, channels and statistics on the way."""

    def __init__(self, path: Path, stream):
        self.path = path
        self.stream = stream
        self.header: Header | None = None
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.statistics: Statistics | None = None
        self.chunk_count = 0
        self.compressions: set[str] = set()
        self.finalised = False
        self.problem: str | None = None

    def messages(self) -> Iterator[Message]:
        """Messages in file order (chunks expanded); stops cleanly at a truncation."""
        try:
            for opcode, body in _records(self.stream):
                if opcode == Opcode.HEADER:
                    self.header = _parse(Header, body)
                elif opcode == Opcode.SCHEMA:
                    schema = _parse(Schema, body)
                    self.schemas[schema.id] = schema
                elif opcode == Opcode.CHANNEL:
                    channel = _parse(Channel, body)
                    self.channels[channel.id] = channel
                elif opcode == Opcode.MESSAGE:
                    yield _parse(Message, body, len(body))
                elif opcode == Opcode.CHUNK:
                    chunk = _parse(Chunk, body)
                    records = _chunk_records(chunk)
                    self.chunk_count += 1
                    self.compressions.add(chunk.compression or 'none')
                    for record in records:
                        if isinstance(record, Schema):
                            self.schemas[record.id] = record
                        elif isinstance(record, Channel):
                            self.channels[record.id] = record
                        elif isinstance(record, Message):
                            yield record
                elif opcode == Opcode.STATISTICS:
                    self.statistics = _parse(Statistics, body)
                elif opcode == Opcode.FOOTER:
                    _parse(Footer, body)
            self.finalised = True
        except _Truncated as err:
            self.problem = str(err)
        except _Damaged as err:
            self.problem = f'damaged record: {err}'
        except OSError as err:
            self.problem = f'read error: {_one_line(err.strerror or err)}'
        except Exception as err:  # noqa: BLE001
            # A record that does not parse, a chunk that does not decompress (zstd, lz4 raise
            # their own types) or fails its CRC: the file is damaged from here on; a streaming
            # reader cannot resynchronise.
            self.problem = f'damaged record: {_describe(err)}'

    def check_recoverable(self, message_count: int) -> None:
        if not self.finalised and message_count == 0 and self.chunk_count == 0:
            raise McapError(f'{self.path}: truncated or damaged before the first complete chunk '
                            f'({self.problem}): no messages recoverable')


# -- decoding -----------------------------------------------------------------------------------

# service_msgs/msg/ServiceEventInfo and builtin_interfaces/msg/Time as in ROS 2 Jazzy, for the
# service event layout (the .srv-based schema rosbag2 writes does not contain them).
_SERVICE_EVENT_INFO = """uint8 REQUEST_SENT = 0
uint8 REQUEST_RECEIVED = 1
uint8 RESPONSE_SENT = 2
uint8 RESPONSE_RECEIVED = 3
uint8 event_type
builtin_interfaces/Time stamp
char[16] client_gid
int64 sequence_number
"""
_TIME = """int32 sec
uint32 nanosec
"""


def _split_sections(text: str) -> list[tuple[str, str]]:
    """[(header line or '', body)] of a concatenated ros2msg text."""
    sections: list[tuple[str, str]] = []
    current_header = ''
    current: list[str] = []
    lines = text.split('\n')
    index = 0
    while index < len(lines):
        line = lines[index]
        if line.strip() == _SEPARATOR and index + 1 < len(lines):
            sections.append((current_header, '\n'.join(current)))
            current_header, current = lines[index + 1].strip(), []
            index += 2
            continue
        current.append(line)
        index += 1
    sections.append((current_header, '\n'.join(current)))
    return sections


def _service_event_schema(schema: Schema) -> Schema:
    """
    Rewrite rosbag2's 'SRV: pkg/srv/Name' schema into the event message layout.

    The parser of mcap-ros2-support accepts no '_' in message names, so the event, request and
    response types are renamed NameEvent, NameRequest, NameResponse (decoding only needs the
    layout; RecordedMessage.type_name keeps the recorded name).
    """
    sections = _split_sections(schema.data.decode('utf-8'))
    srv = [(h, b) for h, b in sections if h.startswith('SRV:')]
    if len(srv) != 1:
        return schema
    service = srv[0][0][len('SRV:'):].strip()            # pkg/srv/Name
    package, _, name = service.partition('/srv/')
    request, _, response = srv[0][1].partition('\n---')
    response = response.lstrip('-')
    root = '\n'.join([
        'service_msgs/ServiceEventInfo info',
        f'{package}/{name}Request[<=1] request',
        f'{package}/{name}Response[<=1] response',
    ]) + '\n'
    extra = [('MSG: service_msgs/ServiceEventInfo', _SERVICE_EVENT_INFO),
             (f'MSG: {package}/{name}Request', request),
             (f'MSG: {package}/{name}Response', response)]
    headers = {h for h, _ in sections}
    if 'MSG: builtin_interfaces/Time' not in headers:
        extra.append(('MSG: builtin_interfaces/Time', _TIME))
    extra += [(h, b) for h, b in sections if h.startswith('MSG:')]
    text = root + ''.join(f'{_SEPARATOR}\n{h}\n{b.strip()}\n' for h, b in extra)
    return Schema(id=schema.id, name=f'{package}/msg/{name}Event', encoding=schema.encoding,
                  data=text.encode('utf-8'))


class _Decoders:
    def __init__(self, path: Path):
        self.path = path
        self.factory = DecoderFactory()
        self.by_channel: dict[int, Any] = {}

    def decode(self, scan: _Scan, message: Message, index: int) -> RecordedMessage:
        channel = scan.channels.get(message.channel_id)
        if channel is None:
            raise McapError(f'{self.path}: message {index} refers to unknown channel '
                            f'{message.channel_id}')
        schema = scan.schemas.get(channel.schema_id)
        type_name = schema.name if schema is not None else '(no schema)'
        decoder = self.by_channel.get(channel.id)
        try:
            if decoder is None:
                if schema is None:
                    raise ValueError('the channel has no schema')
                if schema.data.startswith(f'{_SEPARATOR}\nSRV: '.encode()):
                    schema = _service_event_schema(schema)
                decoder = self.factory.decoder_for(channel.message_encoding, schema)
                if decoder is None:
                    raise ValueError(
                        f'no decoder for message encoding {channel.message_encoding!r} with '
                        f'schema encoding {schema.encoding!r} (need cdr + ros2msg)')
                self.by_channel[channel.id] = decoder
            decoded = decoder(message.data)
        except McapError:
            raise
        except Exception as err:  # noqa: BLE001 - any decoder failure is reported the same way
            raise McapError(f'{self.path}: cannot decode message {index} on topic '
                            f'{channel.topic!r} of type {type_name!r}: {_describe(err)}') from None
        return RecordedMessage(channel.topic, type_name, message.log_time, message.publish_time,
                               decoded)


# -- public API ---------------------------------------------------------------------------------

def read_messages(path, topics: Iterable[str] | str | None = None) -> Iterator[RecordedMessage]:
    """
    Yield the decoded messages of ``path`` in file order, optionally only those of ``topics``.

    Reads the file front to back (no seeking, the summary is not needed): a truncated file
    yields the messages of all its complete chunks, then the iteration ends. Raises McapError at
    once for a missing, empty or non-MCAP file; during the iteration for a truncated file without
    a complete chunk and for a message that cannot be decoded.
    """
    if isinstance(topics, str):
        wanted = {topics}
    elif topics is None:
        wanted = None
    else:
        wanted = set(topics)
        if not all(isinstance(t, str) for t in wanted):
            raise McapError(f'topics must be topic names (str), got {sorted(map(repr, wanted))}')
    path, stream = _open(path)
    return _read_messages(path, stream, wanted)


def _read_messages(path: Path, stream, wanted: set[str] | None) -> Iterator[RecordedMessage]:
    with stream:
        scan = _Scan(path, stream)
        decoders = _Decoders(path)
        count = 0
        for message in scan.messages():
            count += 1
            if wanted is not None:
                channel = scan.channels.get(message.channel_id)
                if channel is not None and channel.topic not in wanted:
                    continue
            yield decoders.decode(scan, message, count - 1)
        scan.check_recoverable(count)


def summarize(path) -> McapSummary:
    """
    Summarise ``path`` (see McapSummary).

    Raises McapError for a missing, empty or non-MCAP file and for a truncated file without a
    complete chunk.
    """
    path, stream = _open(path)
    with stream:
        finalised = _summary_from_footer(path, stream)
        if finalised is not None:
            return finalised
        stream.seek(len(MAGIC))
        scan = _Scan(path, stream)
        counts: dict[int, int] = {}
        start = end = None
        total = 0
        for message in scan.messages():
            total += 1
            counts[message.channel_id] = counts.get(message.channel_id, 0) + 1
            start = message.log_time if start is None else min(start, message.log_time)
            end = message.log_time if end is None else max(end, message.log_time)
        scan.check_recoverable(total)
        return _make_summary(path, scan, counts, total, start, end)


def _make_summary(path, scan: _Scan, counts, total, start, end) -> McapSummary:
    topics: dict[str, TopicSummary] = {}
    for channel in sorted(scan.channels.values(), key=lambda c: c.id):
        schema = scan.schemas.get(channel.schema_id)
        previous = topics.get(channel.topic)
        count = counts.get(channel.id, 0) + (previous.message_count if previous else 0)
        topics[channel.topic] = TopicSummary(
            type_name=schema.name if schema else '(no schema)',
            message_count=count,
            message_encoding=channel.message_encoding,
            schema_encoding=schema.encoding if schema else '')
    header = scan.header
    return McapSummary(
        path=path, profile=header.profile if header else '',
        library=header.library if header else '', topics=topics, message_count=total,
        start_time_ns=start, end_time_ns=end, chunk_count=scan.chunk_count,
        finalised=scan.finalised, problem=scan.problem,
        compressions=tuple(sorted(scan.compressions)))


def _summary_from_footer(path: Path, stream) -> McapSummary | None:
    """Fast path for a finalised file with statistics in its summary section, else None."""
    try:
        size = stream.seek(0, os.SEEK_END)
        footer_size = 9 + _FOOTER_LENGTH + len(MAGIC)
        if size < len(MAGIC) + footer_size:
            return None
        stream.seek(size - footer_size)
        tail = stream.read(footer_size)
        if tail[-len(MAGIC):] != MAGIC or tail[0] != Opcode.FOOTER:
            return None
        (length,) = struct.unpack_from('<Q', tail, 1)
        if length != _FOOTER_LENGTH:
            return None
        summary_start, _, _ = struct.unpack_from('<QQI', tail, 9)
        if not len(MAGIC) < summary_start < size - footer_size:
            return None
        stream.seek(len(MAGIC))
        scan = _Scan(path, stream)
        # The header is the first record; the summary section holds schemas, channels, stats.
        records = _records(stream)
        opcode, body = next(records)
        if opcode != Opcode.HEADER:
            return None
        scan.header = _parse(Header, body)
        stream.seek(summary_start)
        stats = None
        compressions: set[str] = set()
        for opcode, body in _records(stream):
            if opcode == Opcode.SCHEMA:
                schema = _parse(Schema, body)
                scan.schemas[schema.id] = schema
            elif opcode == Opcode.CHANNEL:
                channel = _parse(Channel, body)
                scan.channels[channel.id] = channel
            elif opcode == Opcode.STATISTICS:
                stats = _parse(Statistics, body)
            elif opcode == Opcode.CHUNK_INDEX:
                compressions.add(_parse(ChunkIndex, body).compression or 'none')
        if stats is None:
            return None
        scan.finalised = True
        scan.chunk_count = stats.chunk_count
        scan.compressions = compressions
        total = stats.message_count
        start = stats.message_start_time if total else None
        end = stats.message_end_time if total else None
        return _make_summary(path, scan, dict(stats.channel_message_counts), total, start, end)
    except Exception:  # noqa: BLE001 - any doubt about the summary: scan the file instead
        return None

"""
Read ROS 2 MCAP recordings without a ROS runtime (mcap + mcap-ros2-support, no rclpy).

- :func:`read_messages` streams the decoded messages of a file in file order. It reads the file
  front to back like a non-seeking reader, so a file whose writer was killed (no summary, last
  chunk cut off) yields every message of its complete chunks and then stops cleanly.
- :func:`summarize` tells what a file holds: profile, topics with types and message counts, first
  and last log time, chunk count, and whether the file was finalised (summary and footer written
  by a clean close) or is truncated.

An adapter over the mcap library: its ``StreamReader`` reads the records (the footer and the
summary section of a finalised file too), its ``breakup_chunk`` splits a chunk into its records
and checks the chunk's CRC, and the decoder factory of ``mcap_ros2`` decodes the messages. What
this module adds is at the boundary:

- every failure is an :class:`McapError` with a one-line message naming the file: a missing,
  unreadable or empty file, a path that is not a regular file (a directory, a FIFO, a device: a
  FIFO would block the reader forever, so it is refused before any read), a file that is not MCAP
  (bad magic), a truncated file without a single complete chunk, a message that cannot be decoded
  (topic and type named). Library errors are translated here (``raise ... from None``);
- a file that ends early (or a record that cannot be read) ends the reading after the messages
  of the complete chunks before it, and the summary says why (``problem``: where the library
  stops, the record headers after the last whole record tell where the file ends);
- the work and the memory are bounded by the file's size. A read that asks for more bytes than
  remain in the file (a record, or a chunk's data, that declares more than the file holds) ends
  the reading at once: it is a truncation, nothing is allocated for it. A chunk may expand to at
  most :data:`MAX_CHUNK_RATIO` times its compressed size and :data:`MAX_CHUNK_BYTES` in all; a
  chunk that declares more is damaged (it is not decompressed). Decompression never produces more
  than the declared size.

Chunks are decompressed here, the one piece not left to the library, because its decompression
cannot be bounded: it calls ``zstandard.decompress(data, uncompressed_size)``, which allocates
what the zstd frame itself announces (32 MiB for a chunk that declares 100 kB), and
``lz4.frame.decompress(data)``, which has no bound at all. So the library's ``SeekingReader`` and
``NonSeekingReader`` (and ``SeekingReader.get_summary``, which decompresses any chunk it meets
after a damaged footer) are not used: ``StreamReader(emit_chunks=True)`` hands the chunks over
compressed, and ``breakup_chunk`` gets them decompressed.

Service introspection events (``pkg/srv/Name_Event``) recorded by rosbag2 (Jazzy) or by
:class:`~tumble_ros.io.mcap_writer.McapWriter` carry a schema holding the ``.srv`` file
(``SRV: pkg/srv/Name``, see :mod:`tumble_ros.io.msgdefs`), which generic ros2msg decoders cannot
use; it is rewritten here into the event's real layout (``service_msgs/ServiceEventInfo info``,
``Name_Request[<=1] request``, ``Name_Response[<=1] response``) before decoding.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field, replace
import io
import os
from pathlib import Path
import stat
import struct
from typing import Any, Protocol
import zlib

from mcap.exceptions import EndOfFile
from mcap.opcode import Opcode
from mcap.reader import FOOTER_SIZE
from mcap.records import (Channel, Chunk, ChunkIndex, Footer, Header, Message, Schema,
                          Statistics)
from mcap.stream_reader import breakup_chunk, MAGIC_SIZE, StreamReader
from mcap_ros2.decoder import DecoderFactory

from tumble_ros.errors import IoError
from tumble_ros.file_kinds import file_kind

from .msgdefs import SEPARATOR

lz4_frame: Any
zstandard: Any
try:                                # both come with mcap; a missing one only refuses its chunks
    import lz4.frame
    lz4_frame = lz4.frame
except ImportError:  # pragma: no cover
    lz4_frame = None
try:
    import zstandard
except ImportError:  # pragma: no cover
    zstandard = None

__all__ = ['MAX_CHUNK_BYTES', 'MAX_CHUNK_RATIO', 'McapError', 'McapSummary', 'RecordedMessage',
           'TopicSummary', 'read_messages', 'summarize',
           # for io.columns, which reads the same files by chunks
           'chunk_records', 'Decoders', 'open_recording', 'RecordScan', 'Registry',
           'split_sections']

MAGIC = b'\x89MCAP0\r\n'
_RECORD_HEADER = 9            # opcode (1) + length (8)
_OPCODES = frozenset(Opcode)  # the records the library reads; it skips others unseen
#: Reads up to this size go to the file unchecked (all but a chunk's data, in practice).
_UNCHECKED_READ = 2 ** 16
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


# -- opening --------------------------------------------------------------------------------------

def _not_regular(path: Path, mode: int) -> McapError:
    return McapError(f'{path}: {file_kind(mode)}, not an MCAP file (only regular files are read)')


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


def open_recording(path: str | os.PathLike[str]) -> tuple[Path, io.BufferedReader]:
    """Open ``path`` and check its magic (at once, with a message for each way it is wrong)."""
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


# -- records: the library's StreamReader on a bounded file ---------------------------------------

class _BoundedFile:
    """
    The open file as the library reads it: no read may ask for more than remains of the file.

    The library reads each field of a record straight from the file, and a length that lies (a
    record's, a chunk's data) would have it allocate what it claims before meeting the end of the
    file; such a read raises the library's EndOfFile at once instead.
    """

    def __init__(self, file: io.BufferedReader):
        self.file = file
        self.seek, self.tell = file.seek, file.tell

    def read(self, size: int = -1) -> bytes:
        if size > _UNCHECKED_READ:
            remaining = os.fstat(self.file.fileno()).st_size - self.file.tell()
            if size > remaining:
                raise EndOfFile(f'a read of {size} bytes, {remaining} remain in the file')
        return self.file.read(size)


class _StreamReader(StreamReader):
    """
    mcap's StreamReader, passing over the message indexes without parsing them.

    A front-to-back reader has no use for them, and the library parses each entry of an index
    (two 8-byte reads per message): for a recording of 1.4 M messages that took longer than
    decoding the messages themselves as columns (:mod:`.columns`). The record is consumed as
    the library consumes a record it does not know (``_read_record`` returning None).
    """

    def _read_record(self, opcode: int, length: int) -> Any:
        if opcode == Opcode.MESSAGE_INDEX:
            return None
        return super()._read_record(opcode, length)


def _records(file: io.BufferedReader) -> Iterator[Any]:
    """Return the library's records from the file's position on, chunks still compressed."""
    bounded: Any = _BoundedFile(file)     # (a file to the library: read, seek, tell)
    return _StreamReader(bounded, skip_magic=True, emit_chunks=True).records


def _truncation(file: io.BufferedReader, position: int) -> str | None:
    """
    Say how the file ends inside a record at or after ``position``; None if it does not.

    ``position`` is the end of the last record read whole; the walk passes over the records of
    unknown type after it, which the library skips without handing them over.
    """
    size = os.fstat(file.fileno()).st_size
    while True:
        file.seek(position)
        head = file.read(_RECORD_HEADER)
        if len(head) < _RECORD_HEADER:
            return 'file ends inside a record header' if head else 'file ends before the footer'
        opcode, length = struct.unpack('<BQ', head)
        remaining = size - position - _RECORD_HEADER
        if length > remaining:
            return f'file ends inside a record (opcode {opcode:#x}, {remaining} of {length} bytes)'
        if opcode in _OPCODES:
            return None
        position += _RECORD_HEADER + length


# -- chunks: the one custom piece, bounded decompression -----------------------------------------

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


def _read_exactly(reader: Any, size: int) -> bytes:
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

    def readinto(self, view: memoryview) -> int:
        if self.decompressor.eof:
            return 0
        out = self.decompressor.decompress(self.data, max_length=len(view))
        self.data = b''
        view[:len(out)] = out
        return len(out)


def _decompressing_reader(chunk: Chunk) -> Any:
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
    """Return the chunk's decompressed records, within the bounds, its CRC checked."""
    _check_chunk_size(chunk)
    reader = _decompressing_reader(chunk)
    data = (_read_exactly(reader, chunk.uncompressed_size) if reader is not None
            else bytes(chunk.data))
    if len(data) != chunk.uncompressed_size:
        raise _Damaged(f'a chunk holds {len(data)} bytes, it declares {chunk.uncompressed_size}')
    if chunk.uncompressed_crc and zlib.crc32(data) != chunk.uncompressed_crc:
        raise _Damaged('a chunk fails its CRC check (the data is damaged)')
    return data


def chunk_records(chunk: Chunk, data: bytes) -> list[Any]:
    """Return the schemas, channels and messages of a chunk (the library's breakup_chunk)."""
    return breakup_chunk(replace(chunk, compression='', data=data), validate_crc=False)


# -- scanning -------------------------------------------------------------------------------------

class Registry(Protocol):
    """The schemas and channels of a recording, by id: a file's (RecordScan), or a writer's."""

    schemas: dict[int, Schema]
    channels: dict[int, Channel]


class RecordScan:
    """Walks a file's records; collects header, schemas, channels and chunks on the way."""

    def __init__(self, path: Path, file: io.BufferedReader):
        self.path = path
        self.file = file
        self.header: Header | None = None
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.chunk_count = 0
        self.compressions: set[str] = set()
        self.finalised = False
        self.problem: str | None = None
        self._end = file.tell()           # the end of the last record read whole
        self._footer = False

    def add(self, record: Any) -> None:
        """Keep a header, schema or channel record."""
        if isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel):
            self.channels[record.id] = record
        elif isinstance(record, Header):
            self.header = record

    def messages(self) -> Iterator[Message]:
        """Messages in file order (chunks expanded); stops cleanly where the file breaks."""
        def expand(chunk: Chunk, data: bytes) -> Iterator[Message]:
            for item in chunk_records(chunk, data):
                if isinstance(item, Message):
                    yield item
                else:
                    self.add(item)

        return self.items(expand)

    def items(self, chunk_items: Callable[[Chunk, bytes], Iterable[Any]]) -> Iterator[Any]:
        """
        Yield the file's Messages outside chunks, and the items ``chunk_items`` makes of chunks.

        ``chunk_items(chunk, data)`` is called for each chunk, in file order.
        ``data`` is a chunk's decompressed records (bounded, CRC checked). Stops cleanly where the
        file breaks (``finalised`` / ``problem`` say how), ``chunk_items`` included: it parses,
        the caller decodes.
        """
        try:
            for record in _records(self.file):
                self._end = self.file.tell()
                if isinstance(record, Chunk):
                    data = _chunk_data(record)
                    self.chunk_count += 1
                    self.compressions.add(record.compression or 'none')
                    yield from chunk_items(record, data)
                elif isinstance(record, Message):
                    yield record
                elif isinstance(record, Footer):
                    self._footer = True
                else:
                    self.add(record)
            self.finalised = True
        except Exception as err:  # noqa: BLE001 - the library, zstd, lz4 raise their own types
            # The file is truncated or damaged from here on: a streaming reader cannot
            # resynchronise.
            self.problem = self._stop_reason(err)

    def _stop_reason(self, err: Exception) -> str:
        if isinstance(err, _Damaged):
            return f'damaged record: {err}'
        if isinstance(err, OSError):
            return f'read error: {_one_line(err.strerror or err)}'
        if self._footer:
            return 'footer without the closing magic'
        try:
            truncation = _truncation(self.file, self._end)
        except OSError as walk_error:
            return f'read error: {_one_line(walk_error.strerror or walk_error)}'
        return truncation or f'damaged record: {_describe(err)}'

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


def split_sections(text: str) -> list[tuple[str, str]]:
    """[(header line or '', body)] of a concatenated ros2msg text."""
    sections: list[tuple[str, str]] = []
    current_header = ''
    current: list[str] = []
    lines = text.split('\n')
    index = 0
    while index < len(lines):
        line = lines[index]
        if line.strip() == SEPARATOR and index + 1 < len(lines):
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
    sections = split_sections(schema.data.decode('utf-8'))
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
    text = root + ''.join(f'{SEPARATOR}\n{h}\n{b.strip()}\n' for h, b in extra)
    return Schema(id=schema.id, name=f'{package}/msg/{name}Event', encoding=schema.encoding,
                  data=text.encode('utf-8'))


class Decoders:
    def __init__(self, path: Path):
        self.path = path
        self.factory = DecoderFactory()
        self.by_channel: dict[int, Any] = {}

    def decode(self, scan: Registry, message: Any, index: int) -> RecordedMessage:
        """Decode ``message`` (a record with channel_id, log_time, publish_time, data)."""
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
                if schema.data.startswith(f'{SEPARATOR}\nSRV: '.encode()):
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

def read_messages(path: str | os.PathLike[str], topics: Iterable[str] | str | None = None
                  ) -> Iterator[RecordedMessage]:
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
    path, stream = open_recording(path)
    return _read_messages(path, stream, wanted)


def _read_messages(path: Path, stream: io.BufferedReader, wanted: set[str] | None
                   ) -> Iterator[RecordedMessage]:
    with stream:
        scan = RecordScan(path, stream)
        decoders = Decoders(path)
        count = 0
        for message in scan.messages():
            count += 1
            if wanted is not None:
                channel = scan.channels.get(message.channel_id)
                if channel is not None and channel.topic not in wanted:
                    continue
            yield decoders.decode(scan, message, count - 1)
        scan.check_recoverable(count)


def summarize(path: str | os.PathLike[str]) -> McapSummary:
    """
    Summarise ``path`` (see McapSummary).

    Raises McapError for a missing, empty or non-MCAP file and for a truncated file without a
    complete chunk.
    """
    path, stream = open_recording(path)
    with stream:
        finalised = _summary_from_footer(path, stream)
        if finalised is not None:
            return finalised
        stream.seek(len(MAGIC))
        scan = RecordScan(path, stream)
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


def _make_summary(path: Path, scan: RecordScan, counts: dict[int, int], total: int,
                  start: int | None, end: int | None) -> McapSummary:
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


def _summary_from_footer(path: Path, stream: io.BufferedReader) -> McapSummary | None:
    """
    Return the summary of a finalised file with statistics in its summary section, else None.

    As the library's ``SeekingReader.get_summary``: the footer (and the closing magic) at the
    end of the file, then the summary records from its ``summary_start`` on. A chunk met there
    (a damaged footer) is not decompressed, the file is scanned instead; so is a file with any
    doubt about its summary.
    """
    try:
        stream.seek(-(FOOTER_SIZE + MAGIC_SIZE), os.SEEK_END)
        (footer,) = _records(stream)
        if not isinstance(footer, Footer) or not footer.summary_start:
            return None
        stream.seek(len(MAGIC))
        scan = RecordScan(path, stream)
        scan.header = next(_records(stream))
        if not isinstance(scan.header, Header):
            return None
        stream.seek(footer.summary_start)
        stats = None
        for record in _records(stream):
            if isinstance(record, Chunk):
                return None
            if isinstance(record, Statistics):
                stats = record
            elif isinstance(record, ChunkIndex):
                scan.compressions.add(record.compression or 'none')
            else:
                scan.add(record)
        if stats is None:
            return None
        scan.finalised = True
        scan.chunk_count = stats.chunk_count
        total = stats.message_count
        start = stats.message_start_time if total else None
        end = stats.message_end_time if total else None
        return _make_summary(path, scan, dict(stats.channel_message_counts), total, start, end)
    except Exception:  # noqa: BLE001 - any doubt about the summary: scan the file instead
        return None

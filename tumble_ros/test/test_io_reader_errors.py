"""
tumble_ros.io.mcap_reader's errors.

Every problem with a file is an McapError with a one-line message; a truncated file yields
exactly the messages of its complete chunks.
"""
from pathlib import Path
import struct
import tracemalloc

from mcap.reader import make_reader
import pytest

from tumble_ros import topics
from tumble_ros.io import McapError, McapWriter, read_messages, summarize

GOLDEN = Path(__file__).parent / 'data' / 'golden.mcap'
MAGIC = b'\x89MCAP0\r\n'
MIB = 2 ** 20


def one_line_error(call):
    with pytest.raises(McapError) as info:
        call()
    message = str(info.value)
    assert message and '\n' not in message
    assert info.value.__cause__ is None      # translated at the boundary ('from None')
    return message


def both(path):
    """Return the error of read_messages and of summarize for ``path``."""
    return (one_line_error(lambda: list(read_messages(path))),
            one_line_error(lambda: summarize(path)))


def test_missing_file(tmp_path):
    path = tmp_path / 'nope.mcap'
    for message in both(path):
        assert 'no such file' in message and str(path) in message
    # Raised at once, not at the first iteration.
    one_line_error(lambda: read_messages(path))


def test_empty_file(tmp_path):
    path = tmp_path / 'empty.mcap'
    path.write_bytes(b'')
    for message in both(path):
        assert 'empty' in message


def test_not_mcap(tmp_path):
    path = tmp_path / 'notes.mcap'
    path.write_text('these are not the bytes you are looking for\n' * 10)
    for message in both(path):
        assert 'not an MCAP file' in message
    one_line_error(lambda: read_messages(path))


def test_directory(tmp_path):
    for message in both(tmp_path):
        assert 'directory' in message


def full_messages():
    return [(m.topic, m.log_time_ns) for m in read_messages(GOLDEN)]


def chunk_ends_and_counts():
    """[(offset just after the chunk record, messages in the chunks up to it)] of the golden."""
    with open(GOLDEN, 'rb') as stream:
        summary = make_reader(stream).get_summary()
        out, total = [], 0
        for index in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
            total += sum((offset_length(summary, index, channel))
                         for channel in index.message_index_offsets)
            out.append((index.chunk_start_offset + index.chunk_length, total))
    return out


def offset_length(summary, index, channel):
    # Message index records: 16 bytes per message after a 15-byte record prefix; the offsets of
    # consecutive channels delimit them.
    offsets = sorted(index.message_index_offsets.values())
    start = index.message_index_offsets[channel]
    later = [o for o in offsets if o > start]
    end = later[0] if later else (index.chunk_start_offset + index.chunk_length
                                  + index.message_index_length)
    return (end - start - 15) // 16


def test_truncated_at_chunk_boundaries(tmp_path):
    full = full_messages()
    ends = chunk_ends_and_counts()
    assert len(ends) >= 3 and ends[-1][1] == len(full)
    data = GOLDEN.read_bytes()
    path = tmp_path / 'cut.mcap'

    def read_prefix(size):
        path.write_bytes(data[:size])
        return [(m.topic, m.log_time_ns) for m in read_messages(path)]

    previous = 0
    for end, count in ends:
        # Cut right after a chunk: every message of it (and of the earlier ones) is back.
        assert read_prefix(end) == full[:count]
        # One byte short: that chunk is incomplete, only the earlier chunks' messages remain.
        if previous:
            assert read_prefix(end - 1) == full[:previous]
        previous = count


def test_truncated_anywhere_is_clean_or_mcap_error(tmp_path):
    data = GOLDEN.read_bytes()
    full = full_messages()
    first_chunk_end = chunk_ends_and_counts()[0][0]
    cuts = sorted(set(list(range(1, 120, 7)) + list(range(120, len(data), 613))
                      + [first_chunk_end - 1, len(data) - 40, len(data) - 8, len(data) - 1]))
    path = tmp_path / 'cut.mcap'
    outcomes = {'error': 0, 'partial': 0}
    for cut in cuts:
        path.write_bytes(data[:cut])
        try:
            got = [(m.topic, m.log_time_ns) for m in read_messages(path)]
        except McapError as err:
            assert '\n' not in str(err)
            assert cut < first_chunk_end, f'cut at {cut}: {err}'
            outcomes['error'] += 1
            one_line_error(lambda: summarize(path))
            continue
        assert cut >= first_chunk_end
        assert got == full[:len(got)] and got, f'cut at {cut}'
        summary = summarize(path)
        assert summary.truncated and not summary.finalised and summary.problem
        assert summary.message_count == len(got)
        outcomes['partial'] += 1
    assert outcomes['error'] >= 10 and outcomes['partial'] >= 10


def test_bad_magic_prefix_and_garbage_after_header(tmp_path):
    path = tmp_path / 'x.mcap'
    path.write_bytes(GOLDEN.read_bytes()[:5])
    assert 'truncated' in one_line_error(lambda: list(read_messages(path)))
    # A valid start followed by garbage: damaged before the first chunk.
    data = GOLDEN.read_bytes()
    path.write_bytes(data[:8] + b'\xff' * 200)
    assert 'no messages recoverable' in one_line_error(lambda: list(read_messages(path)))


def test_undecodable_message_names_topic_and_type(tmp_path):
    path = tmp_path / 'bad.mcap'
    omega_topic = '/' + topics.ANGULAR_VELOCITY
    with McapWriter(path) as writer:
        good = writer.add_channel('/good', 'rosgraph_msgs/msg/Clock')
        bad = writer.add_channel(omega_topic, 'geometry_msgs/msg/Vector3Stamped')
        writer.write(good, b'\x00\x01\x00\x00' + bytes(8), 1)
        writer.write(bad, b'\x00\x01\x00\x00\x05', 2)          # far too short
    messages = read_messages(path)
    assert next(messages).topic == '/good'
    message = one_line_error(lambda: next(messages))
    assert f"'{omega_topic}'" in message and 'geometry_msgs/msg/Vector3Stamped' in message
    # Filtering the bad topic out leaves a readable file.
    assert [m.topic for m in read_messages(path, topics='/good')] == ['/good']


def test_corrupt_uncompressed_chunk_fails_its_crc(tmp_path):
    path = tmp_path / 'plain.mcap'
    payload = b'\x00\x01\x00\x00' + bytes(range(8))
    with McapWriter(path, compression='none', chunk_bytes=len(payload) * 3) as writer:
        channel = writer.add_channel(topics.CLOCK, 'rosgraph_msgs/msg/Clock')
        for k in range(9):
            writer.write(channel, payload, k)
    data = bytearray(path.read_bytes())
    found = [i for i in range(len(data)) if data.startswith(payload, i)]
    assert len(found) == 9
    data[found[3] + 6] ^= 0x01        # in the first message of the second chunk: still decodable
    path.write_bytes(bytes(data))
    assert [m.log_time_ns for m in read_messages(path)] == [0, 1, 2]


def test_corrupt_chunk_stops_cleanly(tmp_path):
    # A flipped byte inside the second chunk: its CRC fails; the first chunk's messages are
    # returned and the summary says why reading stopped.
    data = bytearray(GOLDEN.read_bytes())
    ends = chunk_ends_and_counts()
    data[ends[1][0] - 30] ^= 0xFF
    path = tmp_path / 'corrupt.mcap'
    path.write_bytes(bytes(data))
    got = [(m.topic, m.log_time_ns) for m in read_messages(path)]
    assert got == full_messages()[:ends[0][1]]


# -- the bounds the adapter keeps around the library's StreamReader -------------------------------

def record(opcode, body):
    return struct.pack('<BQ', opcode, len(body)) + body


def string(text):
    return struct.pack('<I', len(text)) + text.encode()


def chunk(data, uncompressed_size, compression='zstd', data_length=None):
    """Return a chunk record; ``data_length`` (default: the real one) may lie."""
    length = len(data) if data_length is None else data_length
    return record(0x06, struct.pack('<QQQI', 0, 0, uncompressed_size, 0) + string(compression)
                  + struct.pack('<Q', length) + data)


HEADER = record(0x01, string('ros2') + string('test'))


def peak_of(call):
    """Return (the McapError message of ``call``, peak bytes Python allocated meanwhile)."""
    tracemalloc.start()
    try:
        return one_line_error(call), tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_a_chunk_whose_data_length_lies_is_damaged_and_allocates_nothing(tmp_path):
    # The record is complete, but its data claims 1 GiB: the library would read (and allocate)
    # that much straight from the file; the read is refused because the file is shorter.
    path = tmp_path / 'liar.mcap'
    path.write_bytes(MAGIC + HEADER + chunk(bytes(100), 10, data_length=2 ** 30) + bytes(MIB))
    for call in (lambda: list(read_messages(path)), lambda: summarize(path)):
        message, peak = peak_of(call)
        assert f'damaged record: EndOfFile: a read of {2 ** 30} bytes' in message
        assert 'no messages recoverable' in message
        assert peak < 4 * MIB, f'{peak / MIB:.0f} MiB allocated'


def test_footer_pointing_at_a_chunk_is_not_trusted(tmp_path):
    # A footer whose summary_start points at a (hostile) chunk: the library's get_summary would
    # decompress it unguarded; summarize scans the file instead, where the chunk is refused.
    zstandard = pytest.importorskip('zstandard')
    bomb = zstandard.ZstdCompressor().compress(bytes(32 * MIB))
    head = MAGIC + HEADER
    footer = record(0x02, struct.pack('<QQI', len(head), 0, 0))
    path = tmp_path / 'bomb.mcap'
    path.write_bytes(head + chunk(bomb, 100_000) + footer + MAGIC)
    message, peak = peak_of(lambda: summarize(path))
    assert 'a chunk decompresses to more than 100000 bytes, it declares 100000' in message
    assert peak < 4 * MIB, f'{peak / MIB:.0f} MiB allocated'


@pytest.mark.parametrize('cut, problem', [
    (3, 'footer without the closing magic'),
    (8 + 9, 'file ends inside a record (opcode 0x2, 11 of 20 bytes)'),
    (8 + 25, 'file ends inside a record header'),
])
def test_the_summary_says_where_a_cut_file_ends(tmp_path, cut, problem):
    path = tmp_path / 'cut.mcap'
    path.write_bytes(GOLDEN.read_bytes()[:-cut])
    summary = summarize(path)
    assert summary.truncated and summary.problem == problem
    assert summary.message_count == len(full_messages())


def test_unknown_records_are_skipped_and_a_cut_after_them_is_named(tmp_path):
    path = tmp_path / 'unknown.mcap'
    path.write_bytes(MAGIC + HEADER + record(0x80, b'future') + struct.pack('<BQ', 0x06, 1000)
                     + bytes(10))
    message = one_line_error(lambda: summarize(path))
    assert 'file ends inside a record (opcode 0x6, 10 of 1000 bytes)' in message


def test_unknown_compression_is_damage(tmp_path):
    path = tmp_path / 'brotli.mcap'
    path.write_bytes(MAGIC + HEADER + chunk(b'abc', 3, compression='brotli'))
    assert "unknown compression 'brotli'" in one_line_error(lambda: list(read_messages(path)))

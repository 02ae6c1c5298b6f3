"""
The columns of a recording gathered in a thread while it is written (io.gather_in_background).

The main job gathers the flat topics' columns from the messages its writer keeps as they are
written, on the other core while it simulates. Here: what written_columns returns with the
background gather is what reading the file back returns (columns bit for bit, the same
strings, generic fall-backs and other messages in file order), whichever topics are asked for
and whichever as messages; load_recording gives the same Recording on an offline run with
impacts; an error in the thread is raised by the reader, not lost (a message that cannot be
decoded: the same error as without the thread); a WrittenMessages already
written to or followed is refused; close() ends the thread and stops following the writer; and
the main job stopped by SIGTERM while it records (the thread gathering) still finalises its
file and ends.
"""
from pathlib import Path
import signal
import threading

import pytest

from test_io_written import _assert_same_recording, _assert_same_tables, _write, CONFIG
from tumble_ros.analysis import load_recording
from tumble_ros.io import (BackgroundColumns, columns, gather_in_background, McapError,
                           McapWriter, read_columns, summarize, written_columns,
                           WrittenMessages)


def _threads():
    return [t for t in threading.enumerate() if t.name == 'tumble_ros-columns']


@pytest.mark.parametrize('wanted, as_messages', [(['/v', '/q', '/s'], ()),
                                                 (['/v', '/q', '/s'], ('/v',)),
                                                 (['/q'], ('/v', '/s')),
                                                 (['/v', '/q', '/s', '/skipped'], ('/q',))])
def test_columns_gathered_while_writing_are_the_files(tmp_path, wanted, as_messages):
    keep = WrittenMessages()
    background = gather_in_background(keep)
    assert keep.background is background and _threads()
    path = tmp_path / 'kept.mcap'
    _write(path, keep)
    done = []
    from_memory = written_columns(keep, wanted, as_messages, progress=done.append)
    from_file = read_columns(path, wanted, as_messages)
    assert keep.background is None and keep.on_block is None and not _threads()
    _assert_same_tables(from_file[0], from_memory[0])
    assert [(m.topic, m.log_time_ns, m.publish_time_ns, repr(m.message)) for m in from_file[1]] \
        == [(m.topic, m.log_time_ns, m.publish_time_ns, repr(m.message)) for m in from_memory[1]]
    assert done[-1] == keep.message_count and done == sorted(done)
    if '/q' not in as_messages:
        assert from_memory[0]['/q'].generic == 7 and from_memory[0]['/q'].columnar == 46


def test_the_flat_channels_are_gathered_in_the_thread(tmp_path):
    keep = WrittenMessages()
    background = gather_in_background(keep)
    _write(tmp_path / 'kept.mcap', keep)
    builders = background.finish()
    topics = {b.result.topic for b in builders.values() if b is not None}
    assert topics == {'/v', '/q', '/s', '/skipped'}     # every flat topic, wanted or not
    plain = read_columns(tmp_path / 'kept.mcap', ['/v', '/q', '/s', '/skipped'])[0]
    _assert_same_tables(plain, {b.result.topic: b.finish() for b in builders.values()
                                if b is not None})


def test_an_error_in_the_thread_is_raised_by_the_reader(tmp_path, monkeypatch):
    def fail(*args, **kwargs):
        raise RuntimeError('cannot gather this block')
    monkeypatch.setattr(columns._Builder, 'add_block', fail)
    keep = WrittenMessages()
    gather_in_background(keep)
    _write(tmp_path / 'kept.mcap', keep)       # the writer goes on: the file is written
    with pytest.raises(RuntimeError, match='cannot gather this block'):
        written_columns(keep, ['/v'])
    assert not _threads()
    monkeypatch.undo()                          # (the thread may gather after the writer)
    assert len(read_columns(tmp_path / 'kept.mcap', ['/v'])[0]['/v']) == 53 + 4


def test_a_message_that_cannot_be_decoded_is_the_same_error_as_without_the_thread(tmp_path):
    """
    Raised by the reader, naming the file and the message, as written_columns without it.

    And as reading the file back, which numbered that message 0 (the first of its channel in
    the chunk) where it is message 1.
    """
    from test_io_columns import _vector3_stamped

    def write(path, keep):
        with McapWriter(path, chunk_seconds=float('inf'), keep=keep) as w:
            v = w.add_channel('/v', 'geometry_msgs/msg/Vector3Stamped')
            w.write(v, _vector3_stamped(1, 2, 'body', 1.0, 2.0, 3.0), 5)
            w.write(v, b'\x00\x01\x00\x00\x07', 6)    # CDR, little-endian, cut short
    errors = []
    for background in (True, False):
        keep = WrittenMessages()
        if background:
            gather_in_background(keep)
        write(tmp_path / f'{background}.mcap', keep)
        with pytest.raises(McapError) as raised:
            written_columns(keep, ['/v'])
        errors.append(str(raised.value).replace(f'{background}.mcap', 'x.mcap'))
        with pytest.raises(McapError) as raised:
            read_columns(tmp_path / f'{background}.mcap', ['/v'])
        errors.append(str(raised.value).replace(f'{background}.mcap', 'x.mcap'))
    assert errors[0] == errors[1] == errors[2] == errors[3]
    assert errors[0].startswith(f"{tmp_path / 'x.mcap'}: cannot decode message 1 on topic '/v'")


def test_a_bad_message_inside_a_block_of_rows_is_named_by_its_place_in_the_file(tmp_path):
    """Row 2 of /v in a block of /v and /w rows is the file's message 2 * 2 + 0 = 4, both ways."""
    import numpy as np
    from test_io_columns import _vector3_stamped

    good = np.frombuffer(_vector3_stamped(1, 2, 'body', 1.0, 2.0, 3.0), dtype=np.uint8)
    rows_v, rows_w = np.tile(good, (4, 1)), np.tile(good, (4, 1))
    rows_v[2, 12:16] = 0xFF                     # frame_id's length: past the message's end
    keep = WrittenMessages()
    with McapWriter(tmp_path / 'rows.mcap', chunk_seconds=float('inf'), keep=keep) as w:
        v = w.add_channel('/v', 'geometry_msgs/msg/Vector3Stamped')
        u = w.add_channel('/w', 'geometry_msgs/msg/Vector3Stamped')
        w.write_rows([v, u], [rows_v, rows_w], np.arange(4, dtype=np.int64) + 10)
    errors = []
    for read in (lambda: written_columns(keep, ['/v']),
                 lambda: read_columns(tmp_path / 'rows.mcap', ['/v'])):
        with pytest.raises(McapError) as raised:
            read()
        errors.append(str(raised.value))
    assert errors[0] == errors[1], errors
    assert errors[0].startswith(f"{tmp_path / 'rows.mcap'}: cannot decode message 4 on topic "
                                "'/v'"), errors[0]


def test_only_a_new_written_messages_is_followed(tmp_path):
    keep = WrittenMessages()
    _write(tmp_path / 'kept.mcap', keep)
    # 4 rounds of 6 blocks: write, write_many's 2 messages, write_rows, write, write
    with pytest.raises(ValueError, match=r'written must be new .* 24 block\(s\) kept'):
        gather_in_background(keep)
    fresh = WrittenMessages()
    background = BackgroundColumns(fresh)
    with pytest.raises(ValueError, match='on_block=<built-in method put'):
        gather_in_background(fresh)
    background.close()
    background.close()                          # again: nothing more
    assert fresh.on_block is None and not _threads()


def test_a_recording_gathered_while_writing_is_the_recording_read_back(tmp_path):
    """fig10: impacts, segments, the comparator; through bringup --offline, as the main job."""
    from tumble_ros.nodes.bringup import run_bringup

    keep = WrittenMessages()
    background = gather_in_background(keep)
    output = tmp_path / 'fig10.mcap'
    result = run_bringup(str(CONFIG / 'fig10.yaml'), str(output), progress=None, offline=True,
                         keep=keep)
    assert result.ok, result
    assert keep.background is background
    from_memory = load_recording(output, written=keep)
    assert keep.background is None
    from_file = load_recording(output)
    _assert_same_recording(from_file, from_memory)
    assert from_file.n > 100 and len(from_file.impacts) >= 1 and len(from_file.segments) >= 2


def test_the_main_job_stopped_while_recording_finalises_its_file(spawn, tmp_path):
    """SIGTERM to `python -m tumble_ros` on a 20,000-yr Fig 9 run, mid-recording."""
    scenario = tmp_path / 'fig9_long.yaml'
    text = (Path(CONFIG) / 'fig9.yaml').read_text()
    assert 'duration: 2000.0' in text
    scenario.write_text(text.replace('duration: 2000.0', 'duration: 20000.0'))
    run = spawn('', scenario, module=True, cwd=tmp_path)
    assert run.wait_for('samples/s', 120), run.output
    run.signal(signal.SIGTERM)
    assert run.wait(60) == 128 + signal.SIGTERM, run.output
    assert 'stopped by SIGTERM' in run.output and 'Traceback' not in run.output
    (recording,) = (tmp_path / 'recordings').glob('fig9_long_*.mcap')
    assert summarize(recording).finalised and summarize(recording).message_count > 1000

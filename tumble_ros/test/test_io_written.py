"""
The messages a writer kept in memory (io.WrittenMessages) against the file it wrote.

The main job analyses what it has just recorded from memory instead of reading the file back.
Here: keeping them changes no byte of the file; written_columns gives what read_columns gives of
the file (columns bit for bit, the same strings, the same generic fall-backs, the other messages
in file order); load_recording(written=...) gives the same Recording, array for array, as
reading the file, on offline recordings with impacts, an orbit and a lightcurve; and a
WrittenMessages that is not the file's (another file, an unfinished writer, missing messages)
is not used.
"""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from test_io_columns import _vector3_stamped
from tumble_ros.analysis import load_recording
from tumble_ros.io import McapWriter, read_columns, summarize, written_columns, WrittenMessages

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def _write(path, keep=None):
    """Write rows blocks, single messages (flat, big-endian, write_many), a topic not read."""
    rng = np.random.default_rng(5)
    with McapWriter(path, chunk_bytes=900, chunk_seconds=float('inf'), keep=keep) as w:
        v = w.add_channel('/v', 'geometry_msgs/msg/Vector3Stamped')
        q = w.add_channel('/q', 'geometry_msgs/msg/Vector3Stamped')
        s = w.add_channel('/s', 'std_msgs/msg/String')
        skipped = w.add_channel('/skipped', 'std_msgs/msg/String')
        t = 100
        for block in (1, 9, 40, 3):
            w.write(s, b'\x00\x01\x00\x00\x06\x00\x00\x00hello\x00', t, t + 1)
            w.write_many([(s, b'\x00\x01\x00\x00\x04\x00\x00\x00abc\x00', t + 2, t + 3),
                          (skipped, b'\x00\x01\x00\x00\x01\x00\x00\x00\x00', t + 4, t + 4)])
            rows = [np.frombuffer(b''.join(_vector3_stamped(k, k, 'body', *rng.normal(size=3))
                                           for k in range(block)), dtype=np.uint8
                                  ).reshape(block, -1),
                    np.frombuffer(b''.join(_vector3_stamped(k, 2 * k, 'orbital', *rng.normal(
                        size=3), little=(k % 7 != 3)) for k in range(block)), dtype=np.uint8
                    ).reshape(block, -1)]
            logs = t + 10 * np.arange(block, dtype=np.int64)
            w.write_rows([v, q], rows, logs, logs + 3)
            w.write(v, _vector3_stamped(9, 9, 'b', 1.0, 2.0, 3.0), int(logs[-1]) + 1)
            w.write(skipped, b'\x00\x01\x00\x00\x02\x00\x00\x00x\x00', int(logs[-1]) + 2)
            t = int(logs[-1]) + 100


def test_keeping_the_messages_changes_no_byte_of_the_file(tmp_path):
    keep = WrittenMessages()
    _write(tmp_path / 'kept.mcap', keep)
    _write(tmp_path / 'plain.mcap')
    kept, plain = (tmp_path / 'kept.mcap').read_bytes(), (tmp_path / 'plain.mcap').read_bytes()
    assert len(kept) > 2000 and kept == plain
    assert keep.closed and keep.path == tmp_path / 'kept.mcap'
    assert keep.counts() == {name: t.message_count
                             for name, t in summarize(tmp_path / 'kept.mcap').topics.items()}
    assert keep.message_count == summarize(tmp_path / 'kept.mcap').message_count == 2 * 53 + 20


def _assert_same_tables(a, b):
    assert set(a) == set(b)
    for topic in a:
        x, y = a[topic], b[topic]
        assert (x.topic, x.type_name, x.layout) == (y.topic, y.type_name, y.layout)
        assert (x.columnar, x.generic, x.strings) == (y.columnar, y.generic, y.strings)
        assert x.log_time_ns.dtype == y.log_time_ns.dtype
        assert x.log_time_ns.tobytes() == y.log_time_ns.tobytes()
        assert x.columns.keys() == y.columns.keys()
        for name in x.columns:
            assert x.columns[name].dtype == y.columns[name].dtype, name
            assert x.columns[name].tobytes() == y.columns[name].tobytes(), name


@pytest.mark.parametrize('as_messages', [(), ('/v',), ('/v', '/q', '/s')])
def test_written_columns_are_the_files_columns(tmp_path, as_messages):
    keep = WrittenMessages()
    path = tmp_path / 'kept.mcap'
    _write(path, keep)
    wanted = ['/v', '/q', '/s']
    done = []
    from_file = read_columns(path, wanted, as_messages)
    from_memory = written_columns(keep, wanted, as_messages, progress=done.append)
    _assert_same_tables(from_file[0], from_memory[0])
    assert [(m.topic, m.type_name, m.log_time_ns, m.publish_time_ns, repr(m.message))
            for m in from_file[1]] == [
        (m.topic, m.type_name, m.log_time_ns, m.publish_time_ns, repr(m.message))
        for m in from_memory[1]]
    # decoded one by one, in file order: the rows blocks' messages interleaved sample by sample
    assert len(from_memory[1]) == {0: 0, 1: 53 + 4, 3: 53 + 4 + 53 + 8}[len(as_messages)]
    if not as_messages:
        q = from_memory[0]['/q']
        assert q.generic == 7 and q.columnar == 46        # the big-endian ones, decoded alike
    assert done[-1] == keep.message_count and done == sorted(done)


def _assert_same_recording(a, b):
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, f.name
            assert x.tobytes() == y.tobytes(), f.name
        else:
            assert x == y, f.name


def _params(tmp_path, text):
    params = tmp_path / 'params.yaml'
    params.write_text('sim:\n  ros__parameters:\n' + text)
    return str(params)


@pytest.mark.parametrize('config', ['fig10', 'apophis_2029'])
def test_a_recording_from_memory_is_the_recording_read_back(tmp_path, config):
    """fig10: impacts, segments; apophis_2029: a flyby's perturber, the lightcurve, hours."""
    from tumble_ros.nodes.bringup import run_bringup

    keep = WrittenMessages()
    output = tmp_path / f'{config}.mcap'
    result = run_bringup(str(CONFIG / f'{config}.yaml'), str(output), progress=None,
                         offline=True, keep=keep)
    assert result.ok, result
    read, gathered = [], []
    from_file = load_recording(output, progress=lambda *done: read.append(done))
    from_memory = load_recording(output, written=keep,
                                 progress=lambda *done: gathered.append(done))
    _assert_same_recording(from_file, from_memory)
    # progress reports reading: none when nothing is read (the main job printed "reading: N%")
    assert read and read[-1][0] == read[-1][1] and gathered == []
    assert from_file.n > 100 and from_file.has_comparator and from_file.scenario is not None
    assert len(from_file.quaternion_t) == from_file.n and len(from_file.error_t) > 100
    if config == 'fig10':
        assert len(from_file.impacts) >= 1 and len(from_file.segments) >= 2
    else:
        assert len(from_file.perturber_t) == len(from_file.lightcurve_t) == from_file.n


def test_messages_that_are_not_the_files_are_not_used(tmp_path, monkeypatch):
    from tumble_ros.analysis import recording
    from tumble_ros.nodes.bringup import run_bringup

    keep = WrittenMessages()
    run_bringup(str(CONFIG / 'fig10.yaml'), str(tmp_path / 'a.mcap'), progress=None,
                offline=True, keep=keep)
    other = tmp_path / 'b.mcap'
    run_bringup(_params(tmp_path, '    duration: 1.0\n'), str(other), progress=None,
                offline=True)
    used = []
    real = recording.written_columns
    monkeypatch.setattr(recording, 'written_columns',
                        lambda *a, **k: used.append(1) or real(*a, **k))
    _assert_same_recording(load_recording(other, written=keep), load_recording(other))
    unfinished = dataclasses.replace(keep, closed=False)
    fewer = dataclasses.replace(keep, blocks=keep.blocks[:-1])
    for wrong in (unfinished, fewer):
        rec = load_recording(tmp_path / 'a.mcap', written=wrong)
        _assert_same_recording(rec, load_recording(tmp_path / 'a.mcap'))
    assert used == []
    load_recording(tmp_path / 'a.mcap', written=keep)
    assert used == [1]

"""The analyze command on hostile or unusual input.

Bounded work, no blocking, no writing through links or over existing files. Every refusal is one
``ERROR:`` line and status 1 (docs/analysis.md, "Command").
"""
from __future__ import annotations

import os
from pathlib import Path
import struct
import subprocess
import sys
import tracemalloc

import lz4.frame
import pytest
from tumble_ros.analysis import load_recording, write_figures
from tumble_ros.analysis.cli import command
from tumble_ros.io import McapError, read_messages, summarize
import zstandard

DATA = Path(__file__).resolve().parent / 'data'
GOLDEN = DATA / 'golden.mcap'
MAGIC = b'\x89MCAP0\r\n'
MIB = 2 ** 20
#: Reading a refused file may allocate at most this much (tracemalloc peak).
SMALL = 8 * MIB


def _one_error_line(capsys) -> str:
    out, err = capsys.readouterr()
    assert out == ''
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith('ERROR: ') and 'Traceback' not in err
    return lines[0]


def _peak_memory(call) -> tuple[object, int]:
    """Return (call's result, peak bytes allocated by Python objects during the call)."""
    tracemalloc.start()
    try:
        result = call()
        return result, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


# -- raw MCAP bytes -----------------------------------------------------------------------------

def _record(opcode: int, body: bytes) -> bytes:
    return struct.pack('<BQ', opcode, len(body)) + body


def _string(text: str) -> bytes:
    return struct.pack('<I', len(text)) + text.encode()


def _header() -> bytes:
    return _record(0x01, _string('ros2') + _string('test'))


def _chunk(data: bytes, uncompressed_size: int, compression: str) -> bytes:
    return _record(0x06, struct.pack('<QQQI', 0, 0, uncompressed_size, 0) + _string(compression)
                   + struct.pack('<Q', len(data)) + data)


def _zeros_zstd(size: int, declare_size: bool) -> bytes:
    """Return a zstd frame of ``size`` zero bytes, without holding the zeros in memory.

    ``declare_size``: the frame header states the size.
    """
    compressor = zstandard.ZstdCompressor().compressobj(size=size if declare_size else -1)
    block = bytes(MIB)
    return b''.join([compressor.compress(block) for _ in range(size // MIB)]
                    + [compressor.flush()])


def _zeros_lz4(size: int) -> bytes:
    """Return an lz4 frame of ``size`` zero bytes (its size in the frame header)."""
    compressor = lz4.frame.LZ4FrameCompressor()
    parts = [compressor.begin(source_size=size)]
    block = bytes(MIB)
    parts += [compressor.compress(block) for _ in range(size // MIB)]
    return b''.join(parts + [compressor.flush()])


# -- bounded work ---------------------------------------------------------------------------------

def test_chunk_declaring_a_huge_uncompressed_size_is_refused_before_decompressing(tmp_path,
                                                                                  capsys):
    """Refuse a decompression bomb from its declared sizes alone, without allocating.

    32 MiB of zeros in 1 kB of zstd, declared as such: more than 1000 times the compressed size.
    """
    data = _zeros_zstd(32 * MIB, declare_size=True)
    assert len(data) < 32 * MIB // 1000
    path = tmp_path / 'bomb.mcap'
    path.write_bytes(MAGIC + _header() + _chunk(data, 32 * MIB, 'zstd'))
    status, peak = _peak_memory(lambda: command([str(path)]))
    assert status == 1
    line = _one_error_line(capsys)
    assert f'declares {32 * MIB} bytes uncompressed from {len(data)} bytes of zstd' in line
    assert 'more than 1000 times' in line and 'no messages recoverable' in line
    assert peak < SMALL, f'{peak / MIB:.0f} MiB allocated'
    # The same at the io boundary, as an McapError of its own ('from None').
    for call in (lambda: list(read_messages(path)), lambda: summarize(path)):
        with pytest.raises(McapError) as info:
            call()
        assert info.value.__cause__ is None and 'more than 1000 times' in str(info.value)


@pytest.mark.parametrize('compression', ['zstd', 'zstd, no size in the frame', 'lz4'])
def test_chunk_that_expands_beyond_its_declared_size_stops_there(tmp_path, capsys, compression):
    """Stop decompressing at the declared size, and refuse the chunk.

    The chunk declares 100 kB but its frame holds 32 MiB (and may say so in its own header).
    """
    size = 32 * MIB
    if compression == 'lz4':
        data = _zeros_lz4(size)
    else:
        data = _zeros_zstd(size, declare_size=compression == 'zstd')
    path = tmp_path / 'liar.mcap'
    path.write_bytes(MAGIC + _header() + _chunk(data, 100_000, compression.split(',')[0]))
    status, peak = _peak_memory(lambda: command([str(path)]))
    assert status == 1
    assert 'a chunk decompresses to more than 100000 bytes, it declares 100000' in \
        _one_error_line(capsys)
    assert peak < SMALL, f'{peak / MIB:.0f} MiB allocated'


def test_record_longer_than_the_file_is_refused_without_reading(tmp_path, capsys):
    """Allocate nothing for a chunk record of 512 MiB declared in a 16 kB file."""
    path = tmp_path / 'short.mcap'
    path.write_bytes(MAGIC + _header() + struct.pack('<BQ', 0x06, 512 * MIB) + bytes(16_000))
    status, peak = _peak_memory(lambda: command([str(path)]))
    assert status == 1
    assert f'file ends inside a record (opcode 0x6, 16000 of {512 * MIB} bytes)' in \
        _one_error_line(capsys)
    assert peak < SMALL, f'{peak / MIB:.0f} MiB allocated'


# -- files that are not regular files -------------------------------------------------------------

_FIFO_CHECK = """
import sys
from tumble_ros.analysis.cli import command
from tumble_ros.io import McapError, read_messages, summarize
for name, call in (('read_messages', lambda: read_messages(sys.argv[1])),
                   ('summarize', lambda: summarize(sys.argv[1]))):
    try:
        call()
    except McapError as err:
        print(name, err)
sys.exit(command([sys.argv[1]]))
"""


@pytest.mark.skipif(not hasattr(os, 'mkfifo'), reason='no FIFOs here')
def test_fifo_is_refused_without_blocking(tmp_path):
    """Refuse a FIFO before opening it for reading, which would block without a writer.

    Run in a subprocess with a timeout, so that a regression fails this test instead of
    hanging the suite.
    """
    fifo = tmp_path / 'pipe.mcap'
    os.mkfifo(fifo)
    try:
        done = subprocess.run([sys.executable, '-c', _FIFO_CHECK, str(fifo)],
                              capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail('analyze blocked on a FIFO')
    assert done.returncode == 1, done.stderr
    refused = f'{fifo}: is a FIFO (named pipe), not an MCAP file (only regular files are read)'
    assert done.stderr.splitlines() == [f'ERROR: {refused}']
    assert done.stdout.splitlines() == [f'read_messages {refused}', f'summarize {refused}']


@pytest.mark.skipif(not Path('/dev/null').exists(), reason='no /dev/null')
def test_device_is_refused(capsys):
    assert command(['/dev/null']) == 1
    assert _one_error_line(capsys) == \
        'ERROR: /dev/null: is a character device, not an MCAP file (only regular files are read)'


# -- figures: no overwriting, no links ------------------------------------------------------------

FIGURES = ['impact_0_id1.png', 'omega.png', 'spectrum_wx.png', 'wy_vs_wx.png']


def test_existing_figure_is_not_overwritten_and_nothing_is_written(tmp_path, capsys):
    out_dir = tmp_path / 'figs'
    out_dir.mkdir()
    (out_dir / 'omega.png').write_bytes(b'my own work')
    assert command([str(GOLDEN), '--figures', str(out_dir)]) == 1
    line = _one_error_line(capsys)
    assert line == (f'ERROR: {out_dir / "omega.png"}: exists, not overwritten (--overwrite '
                    f'replaces existing figures)')
    assert (out_dir / 'omega.png').read_bytes() == b'my own work'
    assert sorted(p.name for p in out_dir.iterdir()) == ['omega.png']     # all or nothing


def test_second_run_refuses_and_overwrite_replaces(tmp_path, capsys):
    out_dir = tmp_path / 'figs'
    assert command([str(GOLDEN), '--figures', str(out_dir)]) == 0
    capsys.readouterr()
    before = {name: (out_dir / name).stat().st_ino for name in FIGURES}
    assert command([str(GOLDEN), '--figures', str(out_dir)]) == 1
    line = _one_error_line(capsys)
    assert all(str(out_dir / name) in line for name in FIGURES)
    assert 'exist, not overwritten' in line
    assert command([str(GOLDEN), '--figures', str(out_dir), '--overwrite']) == 0
    out = capsys.readouterr().out
    assert f'figures: 4 written to {out_dir}' in out
    assert sorted(p.name for p in out_dir.iterdir()) == FIGURES        # no temporary left
    assert all((out_dir / name).stat().st_ino != before[name] for name in FIGURES)
    assert all((out_dir / name).read_bytes()[:4] == b'\x89PNG' for name in FIGURES)


@pytest.mark.parametrize('overwrite', [[], ['--overwrite']])
@pytest.mark.parametrize('target', ['existing', 'dangling'])
def test_link_at_a_figure_path_is_refused(tmp_path, capsys, overwrite, target):
    victim = tmp_path / 'victim.txt'
    if target == 'existing':
        victim.write_bytes(b'precious')
    out_dir = tmp_path / 'figs'
    out_dir.mkdir()
    (out_dir / 'wy_vs_wx.png').symlink_to(victim)
    assert command([str(GOLDEN), '--figures', str(out_dir), *overwrite]) == 1
    assert _one_error_line(capsys) == (f'ERROR: {out_dir / "wy_vs_wx.png"}: is a symbolic link: '
                                       f'figures are not written through links')
    assert (victim.read_bytes() == b'precious') if target == 'existing' else not victim.exists()
    assert sorted(p.name for p in out_dir.iterdir()) == ['wy_vs_wx.png']
    assert (out_dir / 'wy_vs_wx.png').is_symlink()


@pytest.mark.parametrize('overwrite', [[], ['--overwrite']])
def test_link_as_the_figure_directory_is_refused(tmp_path, capsys, overwrite):
    real = tmp_path / 'elsewhere'
    real.mkdir()
    link = tmp_path / 'figs'
    link.symlink_to(real)
    for given in (str(link), str(link) + '/'):
        assert command([str(GOLDEN), '--figures', given, *overwrite]) == 1
        assert _one_error_line(capsys) == (f'ERROR: {link}: is a symbolic link: figures are not '
                                           f'written through links')
    assert list(real.iterdir()) == []


def test_non_regular_file_at_a_figure_path_is_refused_even_with_overwrite(tmp_path, capsys):
    out_dir = tmp_path / 'figs'
    (out_dir / 'omega.png').mkdir(parents=True)
    assert command([str(GOLDEN), '--figures', str(out_dir), '--overwrite']) == 1
    assert _one_error_line(capsys) == \
        f'ERROR: {out_dir / "omega.png"}: exists and is not a regular file'


def test_overwrite_needs_figures(capsys):
    assert command([str(GOLDEN), '--overwrite']) == 1
    assert _one_error_line(capsys) == 'ERROR: --overwrite needs --figures DIR'


def test_python_api_refuses_existing_figures_unless_told(tmp_path):
    from tumble_ros.analysis.figures import FigureExistsError, FigurePathError
    rec = load_recording(GOLDEN)
    first = write_figures(rec, tmp_path)
    with pytest.raises(FigureExistsError):
        write_figures(rec, tmp_path)
    assert write_figures(rec, tmp_path, overwrite=True) == first
    (tmp_path / 'link').symlink_to(tmp_path)
    with pytest.raises(FigurePathError):
        write_figures(rec, tmp_path / 'link', overwrite=True)

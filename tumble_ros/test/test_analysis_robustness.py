"""
The analyze command on hostile or unusual input.

Bounded work, no blocking, no writing through links or over existing files, and recordings of
simulators in ROS namespaces. Every refusal is one ``ERROR:`` line and status 1
(docs/analysis.md, "Command").
"""
from __future__ import annotations

import functools
import math
import os
from pathlib import Path
import struct
import subprocess
import sys
import tracemalloc

from cli_checks import one_error_line
import lz4.frame
from mcap.reader import make_reader
import numpy as np
import pytest
from test_analysis_support import RUN_ID, write_recording
from tumble_ros import topics
from tumble_ros.analysis import analyze, load_recording, write_figures
from tumble_ros.analysis.cli import command
from tumble_ros.core import dump_scenario, Scenario
from tumble_ros.io import McapError, McapWriter, read_messages, summarize
from tumble_ros_interfaces.msg import ScenarioDescription
import zstandard

DATA = Path(__file__).resolve().parent / 'data'
GOLDEN = DATA / 'golden.mcap'
MAGIC = b'\x89MCAP0\r\n'
MIB = 2 ** 20
#: Reading a refused file may allocate at most this much (tracemalloc peak).
SMALL = 8 * MIB


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
    """
    Return a zstd frame of ``size`` zero bytes, without holding the zeros in memory.

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
    """
    Refuse a decompression bomb from its declared sizes alone, without allocating.

    32 MiB of zeros in 1 kB of zstd, declared as such: more than 1000 times the compressed size.
    """
    data = _zeros_zstd(32 * MIB, declare_size=True)
    assert len(data) < 32 * MIB // 1000
    path = tmp_path / 'bomb.mcap'
    path.write_bytes(MAGIC + _header() + _chunk(data, 32 * MIB, 'zstd'))
    status, peak = _peak_memory(lambda: command([str(path)]))
    assert status == 1
    line = one_error_line(capsys)
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
    """
    Stop decompressing at the declared size, and refuse the chunk.

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
        one_error_line(capsys)
    assert peak < SMALL, f'{peak / MIB:.0f} MiB allocated'


def test_record_longer_than_the_file_is_refused_without_reading(tmp_path, capsys):
    """Allocate nothing for a chunk record of 512 MiB declared in a 16 kB file."""
    path = tmp_path / 'short.mcap'
    path.write_bytes(MAGIC + _header() + struct.pack('<BQ', 0x06, 512 * MIB) + bytes(16_000))
    status, peak = _peak_memory(lambda: command([str(path)]))
    assert status == 1
    assert f'file ends inside a record (opcode 0x6, 16000 of {512 * MIB} bytes)' in \
        one_error_line(capsys)
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
    """
    Refuse a FIFO before opening it for reading, which would block without a writer.

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
    assert one_error_line(capsys) == \
        'ERROR: /dev/null: is a character device, not an MCAP file (only regular files are read)'


# -- figures: no overwriting, no links ------------------------------------------------------------

FIGURES = ['impact_0_id1.png', 'omega.png', 'spectrum_wx.png', 'wy_vs_wx.png']


def test_existing_figure_is_not_overwritten_and_nothing_is_written(tmp_path, capsys):
    out_dir = tmp_path / 'figs'
    out_dir.mkdir()
    (out_dir / 'omega.png').write_bytes(b'my own work')
    assert command([str(GOLDEN), '--figures', str(out_dir)]) == 1
    line = one_error_line(capsys)
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
    line = one_error_line(capsys)
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
    assert one_error_line(capsys) == (f'ERROR: {out_dir / "wy_vs_wx.png"}: is a symbolic link: '
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
        assert one_error_line(capsys) == (f'ERROR: {link}: is a symbolic link: figures are not '
                                          f'written through links')
    assert list(real.iterdir()) == []


def test_non_regular_file_at_a_figure_path_is_refused_even_with_overwrite(tmp_path, capsys):
    out_dir = tmp_path / 'figs'
    (out_dir / 'omega.png').mkdir(parents=True)
    assert command([str(GOLDEN), '--figures', str(out_dir), '--overwrite']) == 1
    assert one_error_line(capsys) == \
        f'ERROR: {out_dir / "omega.png"}: exists and is not a regular file'


def test_overwrite_needs_figures(capsys):
    assert command([str(GOLDEN), '--overwrite']) == 1
    assert one_error_line(capsys) == ('ERROR: --overwrite needs --figures DIR, --animate FILE or '
                                      '--still FILE')


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


# -- namespaces -----------------------------------------------------------------------------------

def _copy_into(writer: McapWriter, source: Path, namespace: str, channels: dict) -> None:
    """
    Copy every message of ``source`` into ``writer``, its topic moved into ``namespace``.

    ``/clock`` stays global, as the simulator publishes it.
    """
    with open(source, 'rb') as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            topic = channel.topic if channel.topic == topics.CLOCK else namespace + channel.topic
            if topic not in channels:
                channels[topic] = writer.add_channel(topic, schema.name)
            writer.write(channels[topic], message.data, message.log_time, message.publish_time)


def _namespaced(path: Path, sources: list[tuple[Path, str]]) -> Path:
    """Write one file holding the recordings ``sources``, each moved into its namespace."""
    with McapWriter(path, chunk_bytes=4096) as writer:
        channels: dict[str, int] = {}
        for source, namespace in sources:
            _copy_into(writer, source, namespace, channels)
    return path


def _simulator_run(path: Path, frequency: float) -> Path:
    """
    Write a recording as the simulator and the comparator publish it.

    wx at ``frequency`` rad/yr, a comparator with a known error, one impact, the scenario.
    """
    t = np.arange(400) * 0.002
    omega = np.stack([np.cos(frequency * t), np.sin(frequency * t), np.full_like(t, 30.0)], -1)
    model = omega.copy()
    model[:, 0] += 0.01 * frequency * t
    impacts = [{'id': 1, 'start': 0.4, 'end': 0.4 + 3e-7, 'torque': (0, 1e6, 0),
                'delta_omega': (0, 0.3, 0)}]
    quaternion = np.stack([np.cos(t), np.zeros_like(t), np.zeros_like(t), np.sin(t)], -1)
    return write_recording(path, t, omega, model=model, impacts=impacts, quaternion=quaternion,
                           scenario=Scenario(duration=0.8))


@pytest.fixture(scope='module')
def runs(tmp_path_factory):
    """Record two simulator runs without a namespace, wx at 100 and at 300 rad/yr."""
    d = tmp_path_factory.mktemp('runs')
    return _simulator_run(d / 'one.mcap', 100.0), _simulator_run(d / 'two.mcap', 300.0)


def _dominant(out: str) -> float:
    """Return the first peak of the text summary [rad/yr] (printed in rad/<display unit>)."""
    from tumble_ros.core.units import TIME_UNITS

    line = next(x for x in out.splitlines() if x.strip().startswith('1. '))
    value, unit = line.split()[1:3]
    return float(value) / TIME_UNITS[unit.split('/')[1]]


def test_recording_in_a_namespace_is_found_and_analysed_like_without(tmp_path, capsys, runs):
    plain = runs[0]
    path = _namespaced(tmp_path / 'ast1.mcap', [(plain, '/ast1')])
    assert command([str(path)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1] == 'namespace: /ast1'
    in_ast1 = functools.partial(topics.in_namespace, '/ast1')
    assert f'400 samples of {in_ast1(topics.ANGULAR_VELOCITY)}' in out
    assert (f'from {in_ast1(topics.ERROR_NORM)}' in out
            and f'attitude from {in_ast1(topics.ATTITUDE)}' in out)
    assert f'seconds_per_year = 1 (from {in_ast1(topics.SCENARIO)})' in out
    assert 'WARNING' not in out and 'note:' not in out
    ns, root = analyze(load_recording(path)), analyze(load_recording(plain))
    assert ns.namespace == '/ast1' and root.namespace == '/'
    assert ns.sampling == root.sampling and ns.impacts == root.impacts
    assert ns.comparator.max_abs == root.comparator.max_abs
    assert ns.invariant.segments == root.invariant.segments
    assert ns.spectrum.peaks == root.spectrum.peaks
    assert abs(_dominant(out) - 100.0) < ns.spectrum.resolution
    # Without a namespace, as before: no namespace line, the root names.
    assert command([str(plain)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].startswith('file: finalised')
    assert (f'400 samples of /{topics.ANGULAR_VELOCITY}' in out
            and f'(from /{topics.SCENARIO})' in out)


def test_two_namespaces_in_one_file_need_namespace(tmp_path, capsys, runs):
    path = _namespaced(tmp_path / 'both.mcap', [(runs[0], '/ast1'), (runs[1], '/ast2')])
    assert command([str(path)]) == 1
    assert one_error_line(capsys) == (f'ERROR: {path}: the tumble topics are in 2 namespaces: '
                                      f'/ast1, /ast2; choose one with --namespace')
    for namespace, frequency in (('/ast1', 100.0), ('ast2', 300.0), ('/ast2/', 300.0)):
        assert command([str(path), '--namespace', namespace]) == 0
        out = capsys.readouterr().out
        name = '/' + namespace.strip('/')
        omega_topic = topics.in_namespace(name, topics.ANGULAR_VELOCITY)
        assert f'namespace: {name}\n' in out and f'samples of {omega_topic}' in out
        assert abs(_dominant(out) - frequency) < 2 * math.pi / 0.8
        assert 'WARNING' not in out


def test_figures_of_one_namespace(tmp_path, capsys, runs):
    path = _namespaced(tmp_path / 'both.mcap', [(runs[0], '/ast1'), (runs[1], '/ast2')])
    for namespace in ('/ast1', '/ast2'):
        out_dir = tmp_path / namespace.strip('/')
        assert command([str(path), '--namespace', namespace, '--figures', str(out_dir)]) == 0
        names = sorted(p.name for p in out_dir.iterdir())
        assert names == ['error.png', 'impact_0_id1.png', 'omega.png', 'spectrum_wx.png',
                         'wy_vs_wx.png']
    capsys.readouterr()


def test_root_namespace_beside_a_namespace(tmp_path, capsys, runs):
    path = _namespaced(tmp_path / 'mixed.mcap', [(runs[0], ''), (runs[1], '/ast2')])
    assert command([str(path)]) == 1
    assert 'the tumble topics are in 2 namespaces: /, /ast2;' in one_error_line(capsys)
    assert command([str(path), '--namespace', '/', '--json']) == 0
    assert '"namespace": "/"' in capsys.readouterr().out


def test_namespace_without_the_topics(tmp_path, capsys, runs):
    path = _namespaced(tmp_path / 'both.mcap', [(runs[0], '/ast1'), (runs[1], '/ast2')])
    assert command([str(path), '--namespace', '/ast3']) == 1
    omega_topic = topics.in_namespace('/ast3', topics.ANGULAR_VELOCITY)
    assert one_error_line(capsys) == (f'ERROR: {path}: no {omega_topic} topic in '
                                      f'namespace /ast3 (namespaces with the tumble topics: '
                                      f'/ast1, /ast2)')
    assert command([str(GOLDEN), '--namespace', '/ast1']) == 1
    omega_topic = topics.in_namespace('/ast1', topics.ANGULAR_VELOCITY)
    assert f'no {omega_topic} topic in namespace /ast1 (namespaces with the tumble ' \
           'topics: /)' in one_error_line(capsys)


def test_the_analysis_takes_topic_names_and_types_from_the_topics_module():
    """tumble_ros.topics is the one list of names; the analysis spells none of them itself."""
    from tumble_ros.analysis import recording
    # /clock and the 3D scene (markers: read on demand by the still, analysis.scene) are counted
    assert set(recording.EXPECTED_TYPES) == set(topics.RECORDED) - {topics.CLOCK, topics.MARKERS}
    assert all(recording.EXPECTED_TYPES[name] == topics.TYPES[name]
               for name in recording.EXPECTED_TYPES)
    # Typed out on purpose: what in_namespace makes of a name, not computed by it.
    assert topics.in_namespace('/ast1', topics.ERROR_NORM) == '/ast1/comparison/error_norm'
    for path in Path(recording.__file__).parent.glob('*.py'):
        source = path.read_text()
        for name in topics.TYPES:
            literals = (f"'{name.lstrip('/')}'", f"'/{name.lstrip('/')}'")
            assert not any(literal in source for literal in literals), (path.name, name)


def test_python_api_refusals_are_the_packages_analysis_error(tmp_path, runs):
    """What the analysis refuses is tumble_ros.errors.AnalysisError, under the one root."""
    from tumble_ros import analysis, errors
    from tumble_ros.analysis.recording import normalize_namespace
    assert analysis.AnalysisError is errors.AnalysisError
    path = _namespaced(tmp_path / 'both.mcap', [(runs[0], '/ast1'), (runs[1], '/ast2')])
    with pytest.raises(errors.AnalysisError, match='2 namespaces'):
        load_recording(path)
    omega_topic = topics.in_namespace('/ast3', topics.ANGULAR_VELOCITY)
    with pytest.raises(errors.TumbleRosError, match=f'no {omega_topic} topic'):
        load_recording(path, namespace='/ast3')
    with pytest.raises(errors.TumbleRosError, match='not a ROS namespace'):
        normalize_namespace('/1ast')


@pytest.mark.parametrize('bad', ['a b', '/1ast', '/ast-1'])
def test_invalid_namespace_option(capsys, bad):
    assert command([str(GOLDEN), '--namespace', bad]) == 1
    assert one_error_line(capsys) == (f'ERROR: --namespace: not a ROS namespace: {bad!r} (each '
                                      f'name in it is letters, digits and _, not starting with '
                                      f'a digit)')


def test_unrelated_angular_velocity_of_another_type_does_not_make_it_ambiguous(tmp_path, capsys):
    """Only a namespace whose angular_velocity is a Vector3Stamped holds the tumble topics."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64
    t = np.arange(50) * 0.01
    plain = write_recording(
        tmp_path / 'extra.mcap', t, np.ones((50, 3)),
        extra_topics=[(topics.in_namespace('/wheel', topics.ANGULAR_VELOCITY),
                       'std_msgs/msg/Float64', 0, serialize_message(Float64(data=1.0)))])
    path = _namespaced(tmp_path / 'ns.mcap', [(plain, '/ast1')])
    assert topics.in_namespace('/ast1/wheel', topics.ANGULAR_VELOCITY) in summarize(path).topics
    assert command([str(path)]) == 0
    omega_topic = topics.in_namespace('/ast1', topics.ANGULAR_VELOCITY)
    assert f'samples of {omega_topic}' in capsys.readouterr().out


# -- foreign and non-finite samples ---------------------------------------------------------------

def test_non_finite_samples_are_counted_reported_and_left_out(tmp_path, capsys):
    """A foreign publisher's NaN samples: counted, said in one line, left out; the rest read."""
    t = np.arange(400) * 0.002
    omega = np.stack([np.cos(100.0 * t), np.sin(100.0 * t), np.full_like(t, 30.0)], -1)
    omega[[3, 50, 51, 200, 399]] = np.nan
    # an asymmetric body under torque: the theory's lines use max |w| of the samples
    scenario = Scenario(duration=0.8, inertia=(1.0, 1.2, 1.5))
    path = write_recording(tmp_path / 'nan.mcap', t, omega, scenario=scenario)
    assert command([str(path)]) == 0
    out, err = capsys.readouterr()
    notes = [line for line in (out + err).splitlines() if 'left out' in line]
    assert notes == [f'WARNING: /{topics.ANGULAR_VELOCITY}: left out 5 of 400 samples that are '
                     'not finite (NaN or infinite: a foreign publisher?)'], (out, err)
    assert f'395 samples of /{topics.ANGULAR_VELOCITY}' in out


def test_comparisons_of_samples_that_are_not_the_runs_are_left_out_and_said(tmp_path, capsys):
    """
    A foreign publisher's samples reached an older comparator: its comparisons are left out.

    The comparisons of the two NaN samples (NaN errors) and one of a sample the file does not
    hold (30 rad/yr: a foreign sample of zeros compared) are left out of every comparison
    topic, each topic says so in one line, and the error the summary reports is the run's.
    """
    from rclpy.serialization import serialize_message
    from tumble_ros_interfaces.msg import ErrorNorm
    t, omega = _spinning()
    model = omega + 1e-3
    omega[[3, 50]] = np.nan
    foreign = ErrorNorm(model='paper', norm=30.0, relative=1.0)
    foreign_ns = 1_000_000       # between the samples at 0 and 0.002 yr (1 s a year)
    foreign.header.stamp.nanosec = foreign_ns
    path = write_recording(
        tmp_path / 'compared.mcap', t, omega, scenario=Scenario(duration=0.8), model=model,
        extra_topics=[('/' + topics.ERROR_NORM, 'tumble_ros_interfaces/msg/ErrorNorm',
                       foreign_ns, serialize_message(foreign))])
    rec = load_recording(path)
    assert len(rec.norm_t) == len(rec.error_t) == len(rec.model_t) == 398
    assert np.isfinite(rec.error_norm).all() and rec.error_norm.max() < 2e-3
    assert command([str(path)]) == 0
    out, err = capsys.readouterr()
    said = [line for line in err.splitlines() if 'comparisons that are not' in line]
    assert [line.split(':')[1] for line in said] == [
        f' /{topics.MODEL_ANGULAR_VELOCITY}', f' /{topics.ERROR}', f' /{topics.ERROR_NORM}']
    assert 'left out 3 of 401 comparisons' in said[2] and 'left out 2 of 400' in said[0]


def test_samples_whose_stamps_go_back_in_the_file_are_said_to_have_two_sources(tmp_path, capsys):
    """One simulator writes in time order: stamps going back in the file mean a second source."""
    from geometry_msgs.msg import Vector3Stamped
    from rclpy.serialization import serialize_message
    path = tmp_path / 'two.mcap'
    with McapWriter(path) as writer:
        channel = writer.add_channel('/' + topics.ANGULAR_VELOCITY,
                                     'geometry_msgs/msg/Vector3Stamped')
        for ns in [0, 2_000_000, 1_000_000, 4_000_000, 3_000_000, 6_000_000]:
            msg = Vector3Stamped()
            msg.header.stamp.nanosec = ns
            msg.vector.z = 30.0
            writer.write(channel, serialize_message(msg), ns + 1000, ns)
    assert load_recording(path).n == 6
    assert command([str(path)]) == 0
    err = capsys.readouterr().err
    assert (f'WARNING: /{topics.ANGULAR_VELOCITY}: the stamps go back 2 times in the file: more '
            'than one publisher wrote samples on it') in err, err


def _description(scenario: Scenario, run_id: str, t0: float = 0.0) -> ScenarioDescription:
    """Return a ScenarioDescription of ``scenario`` from t0 [yr] (1 s a year), run ``run_id``."""
    d = ScenarioDescription(parameters_yaml=dump_scenario(scenario), seconds_per_year=1.0,
                            segment_start=t0, run_id=run_id)
    d.header.stamp.sec, d.header.stamp.nanosec = divmod(round(t0 * 1e9), 1_000_000_000)
    d.omega.x, d.omega.y, d.omega.z = scenario.omega0
    return d


def _spinning(n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) * 0.002
    return t, np.stack([np.cos(100.0 * t), np.sin(100.0 * t), np.full_like(t, 30.0)], -1)


#: The foreign publisher's scenario: another body, another spin.
FOREIGN = Scenario(duration=5.0, inertia=(1.0, 1.2, 1.5), omega0=(3.0, 0.0, 7.0))


def test_a_foreign_scenario_description_is_counted_reported_and_left_out(tmp_path, capsys):
    """
    A foreign publisher's NaN samples and its scenario (no run id) in the run's recording.

    The foreign description, later in the file than the run's own, neither replaces the run's
    scenario nor adds a segment: one line says it was left out, the analysis goes on.
    """
    t, omega = _spinning()
    omega[[3, 50]] = np.nan
    own = Scenario(duration=0.8)
    path = write_recording(tmp_path / 'foreign.mcap', t, omega, scenario=own,
                           foreign_descriptions=[_description(FOREIGN, '', t0=0.3)])
    rec = load_recording(path)
    assert rec.scenario == own and rec.run_id == RUN_ID
    assert [s.segment_start for s in rec.segments] == [0.0]
    assert command([str(path)]) == 0
    out, err = capsys.readouterr()
    notes = [line for line in (out + err).splitlines() if 'left out' in line]
    assert notes == [
        f'WARNING: /{topics.SCENARIO}: left out 1 of 2 descriptions that are not of run {RUN_ID} '
        '(no run id: 1: a foreign publisher)',
        f'WARNING: /{topics.ANGULAR_VELOCITY}: left out 2 of 400 samples that are not finite '
        '(NaN or infinite: a foreign publisher?)'], (out, err)
    assert '398 samples' in out


def test_the_descriptions_of_two_runs_are_refused_unless_one_is_chosen(tmp_path, capsys):
    """
    Two simulators on the same topics: two run ids on /scenario, samples mixed.

    Refused in one ERROR line naming both runs and --run (exit 1); with --run the chosen run's
    descriptions are read, the other's left out, and a line says the samples are mixed.
    """
    t, omega = _spinning()
    # the second simulator ran the same scenario: its samples repeat the first run's stamps
    t2, omega2 = np.concatenate([t, t[:100]]), np.concatenate([omega, omega[:100]])
    own = Scenario(duration=0.8)
    other = 'ffffeeeedddd'
    path = write_recording(tmp_path / 'two.mcap', t2, omega2, scenario=own,
                           foreign_descriptions=[_description(FOREIGN, other, t0=0.1)])
    assert command([str(path)]) == 1
    out, err = capsys.readouterr()
    assert out == '' and err.count('\n') == 1 and err.startswith('ERROR: '), err
    assert f'{RUN_ID}: 1' in err and f'{other}: 1' in err and '--run' in err
    assert command([str(path), '--run', RUN_ID]) == 0
    out, err = capsys.readouterr()
    notes = [line for line in err.splitlines() if line.startswith('WARNING')]
    assert notes == [
        f'WARNING: /{topics.SCENARIO}: left out 1 of 2 descriptions that are not of run {RUN_ID} '
        f'({other}: 1: a foreign publisher)',
        f'WARNING: /{topics.ANGULAR_VELOCITY}: the samples of the other runs cannot be told apart '
        f"from run {RUN_ID}'s and are kept (100 samples share their stamp with another)"], err
    assert load_recording(path, run=other).scenario == FOREIGN
    assert command([str(path), '--run', 'nosuchrun']) == 1
    assert 'no run' in capsys.readouterr().err

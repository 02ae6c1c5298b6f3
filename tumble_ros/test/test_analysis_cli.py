"""The analyze command (tumble_ros.analysis.cli), the figures, and the no-ROS-runtime promise."""
from __future__ import annotations

import json
import math
from pathlib import Path
import struct
import subprocess
import sys

from cli_checks import one_error_line
import numpy as np
import pytest
from test_analysis_support import write_recording
from tumble_ros import topics
from tumble_ros.analysis import load_recording, write_figures
from tumble_ros.analysis.cli import command
from tumble_ros.analysis.figures import plot_error, plot_impacts
from tumble_ros.core import Scenario
from tumble_ros.io import McapWriter

DATA = Path(__file__).resolve().parent / 'data'
GOLDEN = DATA / 'golden.mcap'
PNG_MAGIC = b'\x89PNG\r\n\x1a\n'
#: The simulator's angular velocity in the root namespace, where the test recordings have it.
OMEGA_TOPIC = '/' + topics.ANGULAR_VELOCITY


# -- user errors --------------------------------------------------------------------------------

def _no_angular_velocity(path: Path) -> Path:
    from rclpy.serialization import serialize_message
    from tumble_ros_interfaces.msg import SimStatus
    with McapWriter(path) as writer:
        ch = writer.add_channel('/' + topics.STATUS, 'tumble_ros_interfaces/msg/SimStatus')
        writer.write(ch, serialize_message(SimStatus(state=SimStatus.FINISHED)), 1, 1)
    return path


def _empty_angular_velocity(path: Path) -> Path:
    with McapWriter(path) as writer:
        writer.add_channel(OMEGA_TOPIC, 'geometry_msgs/msg/Vector3Stamped')
    return path


def _wrong_type(path: Path) -> Path:
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64
    with McapWriter(path) as writer:
        ch = writer.add_channel(OMEGA_TOPIC, 'std_msgs/msg/Float64')
        writer.write(ch, serialize_message(Float64(data=1.0)), 1, 1)
    return path


def _bytes(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


BAD_FILES = {
    'missing': (lambda d: d / 'nope.mcap', 'no such file'),
    'empty': (lambda d: _bytes(d / 'empty.mcap', b''), 'empty file'),
    'truncated': (lambda d: _bytes(d / 'cut.mcap', GOLDEN.read_bytes()[:300]), 'truncated'),
    'magic only': (lambda d: _bytes(d / 'm.mcap', GOLDEN.read_bytes()[:5]), 'truncated'),
    'not mcap': (lambda d: _bytes(d / 'x.mcap', b'hello, not a recording\n'), 'not an MCAP file'),
    'directory': (lambda d: d, 'is a directory'),
    f'no {OMEGA_TOPIC}': (lambda d: _no_angular_velocity(d / 'status.mcap'),
                          f'no {OMEGA_TOPIC} topic'),
    f'no {OMEGA_TOPIC} messages': (lambda d: _empty_angular_velocity(d / 'e.mcap'),
                                   f'{OMEGA_TOPIC} has no messages'),
    'wrong type': (lambda d: _wrong_type(d / 'w.mcap'), 'std_msgs/msg/Float64'),
}


@pytest.mark.parametrize('kind', list(BAD_FILES))
def test_bad_file_gives_one_error_line_and_status_1(tmp_path, capsys, kind):
    make, phrase = BAD_FILES[kind]
    path = make(tmp_path)
    assert command([str(path)]) == 1
    assert phrase in one_error_line(capsys)
    assert command([str(path), '--json', '--figures', str(tmp_path / 'figs')]) == 1
    one_error_line(capsys)
    assert not (tmp_path / 'figs').exists()


@pytest.mark.parametrize('argv, phrase', [
    ([], 'required: FILE.mcap'),
    ([str(GOLDEN), '--bogus'], 'unrecognized arguments: --bogus'),
    ([str(GOLDEN), '--peaks', 'x'], 'invalid int value'),
    ([str(GOLDEN), '--peaks', '0'], '--peaks must be >= 1'),
])
def test_bad_options_giveone_error_line(capsys, argv, phrase):
    assert command(argv) == 1
    assert phrase in one_error_line(capsys)


def test_help_exits_0(capsys):
    assert command(['--help']) == 0
    assert '--figures DIR' in capsys.readouterr().out


def test_unwritable_figure_directory(tmp_path, capsys):
    blocker = tmp_path / 'file'
    blocker.write_text('x')
    assert command([str(GOLDEN), '--figures', str(blocker)]) == 1
    assert 'cannot write figures to' in one_error_line(capsys)


def test_file_truncated_after_complete_chunks_is_analysed_with_a_warning(tmp_path, capsys):
    t = np.arange(400) * 0.005
    omega = np.stack([np.cos(15 * t), np.sin(15 * t), np.full_like(t, 30.0)], -1)
    full = write_recording(tmp_path / 'full.mcap', t, omega, scenario=Scenario(), chunk_bytes=4096)
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(full.read_bytes()[: full.stat().st_size * 2 // 3])
    assert command([str(cut)]) == 2     # the summary is there, the exit status says partial
    out, err = capsys.readouterr()
    assert 'file: TRUNCATED' in out and 'WARNING: the file is truncated' in out
    n = load_recording(cut).n
    assert 50 < n < 400 and f'{n} samples of {OMEGA_TOPIC}' in out
    (line,) = err.splitlines()
    assert line.startswith(f'WARNING: {cut} is truncated (') and 'exit status 2' in line
    assert command([str(cut), '--json', '--quiet']) == 2
    assert json.loads(capsys.readouterr().out)['finalised'] is False
    assert command([str(full)]) == 0     # the whole file: success
    process = _run('-m', 'tumble_ros', 'analyze', str(cut), '--quiet')   # the process's status
    assert process.returncode == 2, process.stderr
    assert 'file: TRUNCATED' in process.stdout and 'Traceback' not in process.stderr


# -- success ------------------------------------------------------------------------------------

def test_text_summary_of_golden(capsys):
    assert command([str(GOLDEN)]) == 0
    out, err = capsys.readouterr()
    assert err == ''
    # a 0.4-yr run reads in days, as its figures do
    assert f'simulated time: 200 samples of {OMEGA_TOPIC}, t = 0 .. {0.398 * 365.25:.6g} d' in out
    assert f'delta_omega (0, {0.3 / 365.25:.6g}, 0) rad/d' in out
    assert 'figures' not in out.splitlines()[-1]


def test_json_summary_of_golden(capsys, tmp_path):
    assert command([str(GOLDEN), '--json', '--peaks', '2']) == 0
    data = json.loads(capsys.readouterr().out)
    assert data['sampling']['n'] == 200 and data['sampling']['duration'] == pytest.approx(0.398)
    assert data['topics']['/' + topics.IMPACT_EVENTS]['count'] == 1
    assert (abs(data['spectrum']['peaks'][0]['omega'] - 2 * math.pi * 15)
            <= data['spectrum']['resolution'])
    assert data['figures'] == [] and data['warnings'] == []


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and data[12:16] == b'IHDR'
    return struct.unpack('>II', data[16:24])


def test_figures_option_writes_pngs(tmp_path, capsys):
    out_dir = tmp_path / 'figs' / 'golden'
    assert command([str(GOLDEN), '--figures', str(out_dir)]) == 0
    out = capsys.readouterr().out
    names = sorted(p.name for p in out_dir.iterdir())
    assert names == ['impact_0_id1.png', 'omega.png', 'spectrum_wx.png', 'wy_vs_wx.png']
    for name in names:
        assert str(out_dir / name) in out
        width, height = _png_size(out_dir / name)
        assert width >= 500 and height >= 300
        assert (out_dir / name).stat().st_size > 20_000


def test_every_figure_with_a_comparator_and_impacts(tmp_path):
    t = np.arange(301) * 0.002
    omega = np.stack([np.cos(15 * t), np.sin(15 * t), np.full_like(t, 30.0)], -1)
    omega[t >= 0.3, 1] += 0.3
    model = omega.copy()
    model[:, 0] += 0.01 * t
    impacts = [{'id': 4, 'start': 0.3 - 3e-7, 'end': 0.3, 'torque': (0, 1e6, 0),
                'delta_omega': (0, 0.3, 0)},
               {'id': 5, 'start': 0.5, 'end': 0.5 + 3e-7, 'torque': (0, 0, 1e3),
                'delta_omega': (0, 0, 3e-4),
                'frame': topics.FRAME_ORBITAL}]
    rec = load_recording(write_recording(tmp_path / 'all.mcap', t, omega, model=model,
                                         impacts=impacts,
                                         scenario=Scenario(duration=0.6)))
    paths = write_figures(rec, tmp_path / 'out')
    assert sorted(p.name for p in paths) == ['error.png', 'impact_0_id4.png', 'impact_1_id5.png',
                                             'omega.png', 'spectrum_wx.png', 'wy_vs_wx.png']
    for path in paths:
        assert path.parent == tmp_path / 'out'
        assert _png_size(path)[0] >= 500 and path.stat().st_size > 20_000


def test_impact_figures_stop_at_their_cap(tmp_path):
    """Many impacts: the first MAX_IMPACT_FIGURES get a figure each, the rest none."""
    from tumble_ros.analysis.figures import MAX_IMPACT_FIGURES

    n = MAX_IMPACT_FIGURES + 3
    t = np.arange(401) * 0.002
    omega = np.stack([np.cos(15 * t), np.sin(15 * t), np.full_like(t, 30.0)], -1)
    impacts = [{'id': k + 1, 'start': 0.01 + 0.03 * k, 'end': 0.01 + 0.03 * k + 3e-7,
                'torque': (0, 1e3, 0), 'delta_omega': (0, 3e-4, 0)} for k in range(n)]
    rec = load_recording(write_recording(tmp_path / 'many.mcap', t, omega, impacts=impacts,
                                         scenario=Scenario(duration=0.8)))
    assert len(rec.impacts) == n
    paths = write_figures(rec, tmp_path / 'out')
    drawn = sorted(p.name for p in paths if p.name.startswith('impact_'))
    assert drawn == sorted(f'impact_{k}_id{k + 1}.png' for k in range(MAX_IMPACT_FIGURES))


def test_figures_that_need_missing_topics_write_nothing(tmp_path):
    t = np.arange(20) * 0.01
    rec = load_recording(write_recording(tmp_path / 'bare.mcap', t, np.ones((20, 3))))
    assert plot_error(rec, tmp_path / 'o') == [] and plot_impacts(rec, tmp_path / 'o') == []
    assert not (tmp_path / 'o').exists()


# -- entry points and no ROS runtime --------------------------------------------------------------

def _run(*args, timeout=120):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=timeout)


def test_python_dash_m_and_no_rclpy_is_imported(tmp_path):
    """
    Run the module entry point in one subprocess and check that no ROS module is loaded.

    Importing and running the whole analysis (figures and JSON included) loads no rclpy or
    rosidl module.
    """
    code = (
        'import sys, runpy\n'
        "sys.argv = ['analyze', sys.argv[1], '--json', '--figures', sys.argv[2]]\n"
        'try:\n'
        "    runpy.run_module('tumble_ros.analysis', run_name='__main__')\n"
        'except SystemExit as e:\n'
        '    assert e.code == 0, e.code\n'
        'import tumble_ros.analysis.figures, tumble_ros.analysis.cli, '
        'tumble_ros.analysis.summary\n'
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in "
        "('rclpy', 'rosidl_runtime_py')\n"
        "             or m.startswith('rosidl') or m.endswith('_msgs') or '_msgs.' in m)\n"
        "print('LOADED', bad, file=sys.stderr)\n"
        'sys.exit(3 if bad else 0)\n')
    done = _run('-c', code, str(GOLDEN), str(tmp_path / 'f'))
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)['sampling']['n'] == 200
    assert 'LOADED []' in done.stderr
    assert len(list((tmp_path / 'f').glob('*.png'))) == 4


def test_python_dash_m_on_a_bad_file(tmp_path):
    done = _run('-m', 'tumble_ros.analysis', str(tmp_path / 'missing.mcap'))
    assert done.returncode == 1
    assert done.stdout == ''
    assert done.stderr.splitlines() == [f'ERROR: {tmp_path / "missing.mcap"}: no such file']


def test_main_is_the_console_script_entry(monkeypatch, capsys):
    from tumble_ros.analysis import cli
    monkeypatch.setattr(sys, 'argv', ['analyze', str(GOLDEN), '--quiet'])
    assert cli.main() == 0
    assert 'dominant frequencies of wx' in capsys.readouterr().out


def test_a_long_path_is_drawn_as_a_density_that_counts_every_sample():
    """The wy-vs-wx path above PATH_POINTS_MAX samples: an occupancy image (a line took 20 s)."""
    from matplotlib.figure import Figure

    from tumble_ros.analysis import figures

    rng = np.random.default_rng(5)
    phase = np.cumsum(rng.uniform(0.2, 0.4, 50_000))
    x, y = 0.1 * np.cos(phase), 0.07 * np.sin(phase) + 0.01
    ax = Figure().add_subplot()
    figures._draw_path_density(ax, x, y)
    (image,) = ax.get_images()
    counts = 10.0 ** image.get_array()
    assert np.isclose(counts.sum(), len(x))           # every sample in one pixel
    left, right, bottom, top = image.get_extent()
    assert left <= x.min() and x.max() <= right and bottom <= y.min() and y.max() <= top
    assert np.isclose(right - left, top - bottom)     # equal axes, as the line plot
    assert len(x) > figures.PATH_POINTS_MAX


def test_the_display_envelope_keeps_every_extreme_and_few_points():
    from tumble_ros.analysis.figures import envelope

    rng = np.random.default_rng(9)
    t = np.linspace(0.0, 2000.0, 200_001)
    y = np.sin(30.0 * t) + 0.01 * rng.normal(size=t.size)
    y[123_457] = 7.0                                  # a one-sample spike
    te, ye = envelope(t, y, bins=2000)
    assert len(te) <= 3 * 2000 + 2 and np.all(np.diff(te) > 0)
    assert ye.max() == 7.0 and ye.min() == y.min()
    assert (te[0], ye[0], te[-1], ye[-1]) == (t[0], y[0], t[-1], y[-1])
    # every bin's lowest and highest samples are kept (bins of ceil(n / 2000) samples)
    size = -(-len(t) // 2000)
    blocks = y[:len(t) // size * size].reshape(-1, size)
    kept = set(zip(te.tolist(), ye.tolist()))
    starts = np.arange(len(blocks)) * size
    for index in (starts + blocks.argmax(axis=1), starts + blocks.argmin(axis=1)):
        assert all((t[i], y[i]) in kept for i in index.tolist())
    assert set(ye.tolist()) <= set(y.tolist())        # and nothing is invented
    short = np.arange(100.0)
    assert envelope(short, short)[0] is short          # short series: drawn whole


def test_the_ensemble_statistics_print_with_units_and_the_pole_in_degrees(tmp_path):
    """``python -m tumble_ros.analysis.ensemble``: every number with its unit, no raw dict."""
    from tumble_ros.core.propagation.ensemble import GaussianSpread
    from tumble_ros.ensembles import run_ensemble_to_store

    sc = Scenario(inertia=(1.0, 1.5, 2.0), orbit_rate=0.0, omega0=(2.0, 1.0, 10.0),
                  euler0=(0.3, 0.2, 0.4), duration=0.2, output_interval=0.05)
    store = tmp_path / 'ens.zarr'
    run_ensemble_to_store(sc, store, n_bodies=4, omega0=GaussianSpread(sc.omega0, 0.01, seed=1))
    done = subprocess.run([sys.executable, '-m', 'tumble_ros.analysis.ensemble', str(store)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert '{' not in out, out                        # no raw dict
    lines = dict(line.split(': ', 1) for line in out.splitlines() if ': ' in line)
    # a 0.2-yr run reads in days (73 d), as the figures' time axes do
    assert lines['time'] == f'{0.2 * 365.25:.6g} d'
    assert 'rad/d' in out and 'rad/yr' not in out
    latitude = next(v for k, v in lines.items() if k.strip().startswith('pole latitude'))
    key = next(k for k in lines if k.strip().startswith('pole latitude'))
    assert key.strip() == 'pole latitude [deg, orbital frame]'
    median = float(latitude.split('median ')[1].split(',')[0])
    from tumble_ros.core import simulate
    from tumble_ros.core.model.spinstate import spin_state
    r = simulate(sc)            # the nominal body (the spread is 0.01 rad/yr of 10)
    nominal = math.degrees(spin_state(r.omega[-1], sc.inertia, r.quaternion[-1]).pole_latitude)
    assert abs(nominal) > 5.0 and median == pytest.approx(nominal, abs=0.5), (median, nominal)

"""``analyze --animate`` and ``--still``: the frames written, their size and timing, the errors."""
from __future__ import annotations

from pathlib import Path

from cli_checks import one_error_line
from matplotlib import animation as mpl_animation
import numpy as np
from PIL import Image
import pytest
from tumble_ros.analysis import load_recording
from tumble_ros.analysis.animation import (DPI, frame_indices, recorded_scene, SIZE, Solid,
                                           STILL_DPI, STILL_SIZE)
from tumble_ros.analysis.cli import command
from tumble_ros.core import Scenario

DATA = Path(__file__).resolve().parent / 'data'
GOLDEN = DATA / 'golden.mcap'


def _pixels(size, dpi):
    return (round(size[0] * dpi), round(size[1] * dpi))


def test_the_animation_of_the_golden_recording_has_its_frames_size_and_timing(tmp_path, capsys):
    out = tmp_path / 'tumble.gif'
    assert command([str(GOLDEN), '--animate', str(out), '--frames', '7', '--fps', '5']) == 0
    captured = capsys.readouterr()
    assert f'animation: {out} (7 frames at 5 fps)' in captured.out
    assert '100% (7 of 7 frames)' in captured.err            # the progress bar
    with Image.open(out) as gif:
        assert gif.n_frames == 7
        assert gif.size == _pixels(SIZE, DPI)
        assert gif.info['duration'] == 200                  # ms a frame at 5 fps
        first = np.asarray(gif.convert('RGB'))
        gif.seek(6)
        last = np.asarray(gif.convert('RGB'))
    assert (first != last).any()                            # the body moved, the cursor too
    # the golden file has 20 attitude samples: asking for more frames gives each one once
    more = tmp_path / 'all.gif'
    assert command([str(GOLDEN), '--animate', str(more), '--frames', '500', '--quiet']) == 0
    with Image.open(more) as gif:
        assert gif.n_frames == 20


def test_frames_are_spread_evenly_with_the_first_and_last_sample():
    k = frame_indices(200_001, 120)
    assert k[0] == 0 and k[-1] == 200_000 and len(k) == 120
    assert np.ptp(np.diff(k)) <= 1
    assert frame_indices(5, 120).tolist() == [0, 1, 2, 3, 4]


def test_each_frame_shows_the_attitude_of_its_sample():
    rec = load_recording(GOLDEN)
    scenes = recorded_scene(rec, rec.quaternion_t, rec.quaternion, rec.omega[:20])
    bodies = [item for scene in scenes for item in scene if isinstance(item, Solid)]
    assert [b.quaternion for b in bodies] == [tuple(q) for q in rec.quaternion]


@pytest.mark.skipif(mpl_animation.writers.is_available('ffmpeg'), reason='ffmpeg is installed')
def test_mp4_without_ffmpeg_is_refused_in_one_line(tmp_path, capsys):
    assert command([str(GOLDEN), '--animate', str(tmp_path / 'a.mp4'), '--quiet']) == 1
    assert 'needs ffmpeg' in one_error_line(capsys)


@pytest.mark.parametrize('argv, phrase', [
    (['--animate', 'x.avi'], '.gif (Pillow) or an .mp4'),
    (['--frames', '3'], '--frames and --fps need --animate'),
    (['--animate', 'x.gif', '--frames', '0'], '--frames must be an integer in [1, 10,000]'),
    (['--at', '1.0'], '--at needs --still FILE.png or --animate FILE.png'),
])
def test_bad_options_give_one_error_line(tmp_path, capsys, argv, phrase):
    argv = [str(tmp_path / a) if a.endswith(('.avi', '.gif')) else a for a in argv]
    assert command([str(GOLDEN), '--quiet', *argv]) == 1
    assert phrase in one_error_line(capsys)


def test_an_existing_file_is_kept_without_overwrite(tmp_path, capsys):
    out = tmp_path / 'a.gif'
    out.write_bytes(b'mine')
    assert command([str(GOLDEN), '--animate', str(out), '--frames', '2', '--quiet']) == 1
    assert 'exists, not overwritten' in one_error_line(capsys)
    assert out.read_bytes() == b'mine'
    assert command([str(GOLDEN), '--animate', str(out), '--frames', '2', '--quiet',
                    '--overwrite']) == 0
    assert out.read_bytes()[:6] == b'GIF89a'
    assert not [p for p in tmp_path.iterdir() if p.name.startswith('.')]   # no temporary left


def test_the_still_draws_a_recorded_scene(tmp_path, capsys):
    from tumble_ros.runs.offline import record_offline
    result = record_offline(Scenario(duration=0.2, output_interval=0.01), tmp_path / 'r.mcap')
    out = tmp_path / 'scene.png'
    assert command([str(result.output), '--still', str(out), '--at', '0.1', '--quiet']) == 0
    # (--at is in years; the scene's time reads in the summary's display unit: a 0.2-yr run's
    # days)
    said = capsys.readouterr().out
    assert f'still: {out} (the /markers scene at t = {0.1 * 365.25:g} d)' in said
    with Image.open(out) as png:
        assert png.size == _pixels(STILL_SIZE, STILL_DPI)
    # a recording without scenes (the golden file predates them): one error line
    assert command([str(GOLDEN), '--still', str(tmp_path / 'g.png'), '--quiet']) == 1
    assert 'no /markers scenes' in one_error_line(capsys)


def test_one_frame_of_the_animation_as_a_png(tmp_path, capsys):
    out = tmp_path / 'frame.png'
    assert command([str(GOLDEN), '--animate', str(out), '--at', '0.1', '--quiet']) == 0
    assert f'animation: {out} (one frame)' in capsys.readouterr().out
    with Image.open(out) as png:
        assert png.size == _pixels(SIZE, DPI)


@pytest.mark.parametrize('argv, phrase', [
    (['--animate', 'x.gif', '--fps', '1e-9'], '--fps must be in [0.1, 100], got 1e-09'),
    (['--animate', 'x.gif', '--fps', 'nan'], '--fps must be in [0.1, 100], got nan'),
    (['--animate', 'x.gif', '--frames', '1000000000'],
     '--frames must be an integer in [1, 10,000] (MAX_FRAMES), got 1000000000'),
    (['--animate', 'x.png', '--at', 'nan'], "--at: 'nan' is not a time: a number in the run's "
     'time_unit or a number and its unit, one of yr, d, h, min, s: 12h, 3d, 30min, 90s, 2yr'),
    (['--animate', 'x.png', '--at', 'inf'], "--at: 'inf' is not a time"),
    (['--still', 'x.png', '--at=-inf'], "--at: '-inf' is not a time"),
    (['--still', 'x.png', '--at', '1e999h'], "--at: must be a finite time, got '1e999h'"),
    (['--still', 'x.png', '--at', '3 days'], "--at: '3 days' is not a time"),
    (['--animate', 'x.png', '--at', '99'], '--at 99 yr: outside the attitude samples, [0, '),
    (['--still', 'x.png', '--at=-5'], '--at -5 yr: outside the run, [0, '),
])
def test_frames_fps_and_times_out_of_bounds_are_refused_in_one_line(
        tmp_path, capsys, argv, phrase):
    """--fps 1e-9 ended in OverflowError; --at nan / inf / beyond the run drew t = 0 silently."""
    argv = [str(tmp_path / a) if a.endswith(('.gif', '.png')) else a for a in argv]
    assert command([str(GOLDEN), '--quiet', *argv]) == 1
    assert phrase in one_error_line(capsys)
    assert not list(tmp_path.iterdir())


def test_the_gif_is_written_frame_by_frame(tmp_path, monkeypatch):
    """
    The GIF is written as it is drawn (PillowWriter kept every frame, 0.92 MB each, to the end).

    While the animation is written, the frames already drawn are on disk, not in memory: the
    number of PIL images alive does not grow with the frames written.
    """
    import gc

    from tumble_ros.analysis import animation

    alive = []

    def count(done, total):
        gc.collect()
        alive.append(sum(isinstance(o, Image.Image) for o in gc.get_objects()))

    out = tmp_path / 'a.gif'
    # six frames: kept, they would be alive[0] + 5 at the end (a full collection a frame: in a
    # test worker holding the whole suite's objects, 0.3 s each)
    animation.write_animation(load_recording(GOLDEN), out, frames=6, progress=count)
    assert len(alive) == 6 and max(alive) <= alive[0] + 1, alive
    with Image.open(out) as gif:
        assert gif.n_frames == 6 and gif.info['loop'] == 0

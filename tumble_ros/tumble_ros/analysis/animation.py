"""
The asteroid tumbling, drawn offline: an animation of a recording, a still of its 3D scene.

    python -m tumble_ros analyze RUN.mcap --animate tumble.gif [--frames 120] [--fps 12]
    python -m tumble_ros analyze RUN.mcap --animate frame.png [--at 1.0]    # one frame
    python -m tumble_ros analyze RUN.mcap --still scene.png [--at 0.5]

:func:`write_animation` draws, frame by frame, the body (the shape of
:func:`tumble_ros.core.model.shape.body_shape`), its principal axes, the direction of its angular
momentum L = C(q) I w and of the torquing body, in the orbital frame, at the attitude of the
recorded samples; beside it w against t (the whole run, scaled on the numeric solution, with the
model as in ``omega.png``) and the comparator's |error|, a cursor at the frame's time. Frames
are spread evenly over the recorded samples (``frames``, default :data:`FRAMES`): a 2-yr run of
1,001 samples shows every 8th sample (the body turns by ~30 degrees a frame at w = 30 rad/yr),
a 2,000-yr run one sample every ~17 yr (a stroboscope: the title says which samples). GIF
through Pillow, written frame by frame (memory does not grow with the number of frames), MP4
through ffmpeg where it is installed. Bounds: :data:`MAX_FRAMES` frames, :data:`MIN_FPS` to
:data:`MAX_FPS` frames per second, ``at`` a finite time within the run.

:func:`write_still` draws one recorded ``markers`` scene (``visualization_msgs/MarkerArray``,
what RViz and Foxglove show) with matplotlib's 3D axes: the SPHERE, CUBE and ARROW markers as
they are in the file. It stands in for a screenshot of Foxglove's 3D panel where no viewer runs.

Both draw the same primitives (:class:`Solid`, :class:`Arrow`), in display units (the longest
semi-axis 1; the inertia is normalised). Files: never written through a symbolic link; an
existing one only with ``overwrite`` (the file is written beside it, then renamed over it).
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
import io
import os
from pathlib import Path
import struct
import sys
from typing import Any, Callable, Iterator, TextIO

from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
import numpy as np

from tumble_ros.core.model.dynamics import angular_momentum_orbital
from tumble_ros.core.model.rotation import quaternion_multiply, quaternions_to_matrices
from tumble_ros.core.model.shape import (AXIS_LENGTH, body_shape, BOX, COLORS, ELLIPSOID,
                                         MOMENTUM_LENGTH, PERTURBER_LENGTH,
                                         torquing_body_direction)
from tumble_ros.core.units import from_years
from tumble_ros.errors import AnalysisError
from tumble_ros.io import read_messages
from tumble_ros.topics import (BODY_MARKERS, FRAME_BODY, MARKER_AXES, MARKER_MOMENTUM,
                               MARKER_PERTURBER, MARKER_SUN, MARKERS)

from .display import recording_units, run_time_unit
from .figures import envelope, numeric_limits, time_axis
from .recording import Recording

__all__ = ['Solid', 'Arrow', 'FRAMES', 'FPS', 'SIZE', 'DPI', 'STILL_SIZE', 'STILL_DPI',
           'frame_indices', 'recorded_scene',
           'marker_scene', 'write_animation', 'write_still', 'stderr_bar', 'MAX_FRAMES',
           'MIN_FPS', 'MAX_FPS', 'check_frames_fps', 'check_time']

#: Default number of frames and frames per second (10 s).
FRAMES = 120
FPS = 12
#: Most frames of an animation (a frame takes ~0.1 s to draw: ~20 min at the bound; the file
#: is written frame by frame, so memory does not grow with it).
MAX_FRAMES = 10_000
#: Frames per second allowed: a GIF holds a frame's delay in hundredths of a second up to
#: 655.35 s; 0.1 fps (10 s a frame) to 100 fps (the GIF's shortest delay, 0.01 s).
MIN_FPS, MAX_FPS = 0.1, 100.0
#: Figure size [inch] and resolution [dpi] of the animation: 720 x 324 pixels; of the still:
#: 600 x 550 pixels.
SIZE = (10.0, 4.5)
DPI = 72
STILL_SIZE = (6.0, 5.5)
STILL_DPI = 100
#: Half the side of the 3D box shown [display units].
EXTENT = 2.6
#: Marker types of visualization_msgs/Marker drawn by the still.
_ARROW, _CUBE, _SPHERE = 0, 1, 2
#: Labels of the arrows: body axes, angular momentum, torquing body.
_LABELS = {MARKER_MOMENTUM: 'L', MARKER_SUN: 'Sun', MARKER_PERTURBER: 'orbiting body'}


@dataclass(frozen=True)
class Solid:
    """The body: ``kind`` ellipsoid or box, its attitude (w, x, y, z) and semi-axes."""

    kind: str
    quaternion: tuple[float, float, float, float]
    semi_axes: tuple[float, float, float]
    color: tuple[float, float, float, float]


@dataclass(frozen=True)
class Arrow:
    """An arrow from ``start`` to ``end`` (orbital frame, display units)."""

    start: tuple[float, float, float]
    end: tuple[float, float, float]
    color: tuple[float, float, float, float]
    label: str = ''


Scene = list  # [Solid | Arrow]


def frame_indices(n: int, frames: int) -> np.ndarray:
    """Return up to ``frames`` sample indices spread evenly over n samples, first and last in."""
    if n <= 0:
        return np.zeros(0, dtype=int)
    return np.unique(np.linspace(0, n - 1, max(1, min(frames, n))).round().astype(int))


def _attitude_samples(rec: Recording):
    """Return (t, quaternion, omega) at the attitude's stamps (omega at the nearest stamp)."""
    if not len(rec.quaternion_t):
        raise AnalysisError(f'{rec.path}: no {rec.topic("attitude")} samples: nothing to '
                            'animate')
    k = np.clip(np.searchsorted(rec.t, rec.quaternion_t), 0, rec.n - 1)
    before = np.clip(k - 1, 0, rec.n - 1)
    nearer = np.abs(rec.t[before] - rec.quaternion_t) < np.abs(rec.t[k] - rec.quaternion_t)
    k = np.where(nearer, before, k)
    return rec.quaternion_t, rec.quaternion, rec.omega[k]


def recorded_scene(rec: Recording, t: np.ndarray, quaternion: np.ndarray,
                   omega: np.ndarray) -> list[Scene]:
    """
    Return the scenes of samples: body, axes, L and the torquing body, from the recording.

    ``t`` (n,) [yr], ``quaternion`` (n, 4) body -> orbital, ``omega`` (n, 3) [rad/yr].
    """
    inertia = rec.scenario.inertia if rec.scenario is not None else (1.0, 1.0, 1.0)
    shape = body_shape(inertia)
    c = quaternions_to_matrices(quaternion)
    momentum = angular_momentum_orbital(omega, c, inertia)
    perturber = (torquing_body_direction(rec.scenario, t) if rec.scenario is not None
                 else None)
    scenes = []
    for j in range(len(t)):
        scene: Scene = [Solid(shape.kind, tuple(quaternion[j]), shape.semi_axes,
                              COLORS[shape.kind])]
        for i, axis in enumerate('xyz'):
            scene.append(Arrow((0.0, 0.0, 0.0), tuple(AXIS_LENGTH * c[j][:, i]), COLORS[axis],
                               axis))
        norm = np.linalg.norm(momentum[j])
        if norm > 0:
            scene.append(Arrow((0.0, 0.0, 0.0), tuple(MOMENTUM_LENGTH * momentum[j] / norm),
                               COLORS['momentum'], _LABELS[MARKER_MOMENTUM]))
        if perturber is not None:
            bodies = rec.scenario.all_perturbers if rec.scenario is not None else ()
            name = MARKER_PERTURBER if bodies else MARKER_SUN
            scene.append(Arrow((0.0, 0.0, 0.0), tuple(PERTURBER_LENGTH * perturber[j]),
                               COLORS['torquing_body'], _LABELS[name]))
        scenes.append(scene)
    return scenes


def _rgba(color) -> tuple[float, float, float, float]:
    return (float(color.r), float(color.g), float(color.b), float(color.a))


def _xyz(v) -> np.ndarray:
    return np.array([float(v.x), float(v.y), float(v.z)])


def marker_scene(array: Any, attitude: Any = None) -> Scene:
    """
    Return the primitives of a decoded visualization_msgs/MarkerArray (SPHERE, CUBE, ARROW).

    Markers in the frame ``body`` (``body_markers``: the shape, its axes) are posed in the
    orbital frame by ``attitude`` (w, x, y, z; body -> orbital), as a viewer's TF does; the
    others are drawn as they are (the frame ``orbital``).
    """
    scene: Scene = []
    for m in array.markers:
        label = 'xyz'[m.id] if m.ns == MARKER_AXES and 0 <= m.id < 3 else _LABELS.get(m.ns, m.ns)
        o = m.pose.orientation
        q = (float(o.w), float(o.x), float(o.y), float(o.z))
        position = _xyz(m.pose.position)
        turn = np.eye(3)
        if attitude is not None and m.header.frame_id.rsplit('/', 1)[-1] == FRAME_BODY:
            w, x, y, z = (float(v) for v in quaternion_multiply(attitude, q))
            q = (w, x, y, z)
            turn = quaternions_to_matrices(np.asarray(attitude, dtype=float))
            position = turn @ position
        if m.type in (_SPHERE, _CUBE):
            scene.append(Solid(ELLIPSOID if m.type == _SPHERE else BOX, q,
                               tuple(_xyz(m.scale) / 2.0), _rgba(m.color)))
        elif m.type == _ARROW and len(m.points) >= 2:
            scene.append(Arrow(tuple(turn @ _xyz(m.points[0]) + position),
                               tuple(turn @ _xyz(m.points[1]) + position), _rgba(m.color),
                               label))
        elif m.type == _ARROW:
            c = quaternions_to_matrices(np.array(q))
            scene.append(Arrow(tuple(position), tuple(position + m.scale.x * c[:, 0]),
                               _rgba(m.color), label))
    return scene


def _recorded_body(rec: Recording, t: float) -> Scene:
    """
    Return the body and its axes (``body_markers``) posed by the attitude sample at ``t`` [yr].

    Empty for a recording without them (made before they were split from ``markers``, whose
    every scene then holds the body).
    """
    topic = rec.topic(BODY_MARKERS)
    if topic not in rec.topics or rec.topics[topic][1] == 0 or not len(rec.quaternion_t):
        return []
    body = next(iter(read_messages(rec.path, topics=[topic]))).message
    k = int(np.argmin(np.abs(rec.quaternion_t - t)))
    return marker_scene(body, rec.quaternion[k])


# -- drawing ------------------------------------------------------------------------------------

_U, _V = np.meshgrid(np.linspace(0.0, 2.0 * np.pi, 25), np.linspace(0.0, np.pi, 13))
_SPHERE_POINTS = np.stack([np.cos(_U) * np.sin(_V), np.sin(_U) * np.sin(_V), np.cos(_V)])
_CUBE_FACES = [[(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1)],
               [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],
               [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)],
               [(-1, 1, -1), (1, 1, -1), (1, 1, 1), (-1, 1, 1)],
               [(-1, -1, -1), (-1, 1, -1), (-1, 1, 1), (-1, -1, 1)],
               [(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)]]


def _draw_scene(ax, scene: Scene) -> list:
    """Draw the primitives on a 3D axes (orbital frame, display units); return the artists."""
    artists = []
    for item in scene:
        if isinstance(item, Solid):
            c = quaternions_to_matrices(np.array(item.quaternion))
            semi = np.array(item.semi_axes)
            if item.kind == BOX:
                faces = [[c @ (semi * np.array(p)) for p in face] for face in _CUBE_FACES]
                artists.append(ax.add_collection3d(Poly3DCollection(
                    faces, facecolor=item.color, edgecolor=(0.3, 0.3, 0.3, 0.6), lw=0.5)))
            else:
                points = np.einsum('ij,j...->i...', c, semi[:, None, None] * _SPHERE_POINTS)
                artists.append(ax.plot_surface(*points, color=item.color, linewidth=0,
                                               shade=True))
        else:
            start, end = np.array(item.start), np.array(item.end)
            artists.append(ax.quiver(*start, *(end - start), color=item.color, lw=2.0,
                                     arrow_length_ratio=0.12))
            if item.label:
                artists.append(ax.text(*(end * 1.1), item.label, color=item.color[:3],
                                       fontsize=8))
    return artists


def _set_up_3d(ax) -> None:
    """Fix the 3D axes: the orbital frame's X' Y' Z', +-EXTENT, equal scales."""
    ax.set_xlim(-EXTENT, EXTENT)
    ax.set_ylim(-EXTENT, EXTENT)
    ax.set_zlim(-EXTENT, EXTENT)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("X'", fontsize=8, labelpad=-8)
    ax.set_ylabel("Y'", fontsize=8, labelpad=-8)
    ax.set_zlabel("Z'", fontsize=8, labelpad=-8)
    ax.tick_params(labelsize=6, pad=-2)


def _figure(with_plots: bool):
    """Return (figure, 3D axes, [the plots' axes]): the still's, or the animation's."""
    if not with_plots:
        fig = Figure(figsize=STILL_SIZE, dpi=STILL_DPI)
        FigureCanvasAgg(fig)
        return fig, fig.add_subplot(projection='3d'), []
    fig = Figure(figsize=SIZE, dpi=DPI)
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(3, 2, width_ratios=(1.0, 1.25), left=0.0, right=0.97, bottom=0.11,
                            top=0.91, wspace=0.14, hspace=0.15)
    ax3d = fig.add_subplot(grid[:, 0], projection='3d')
    first = fig.add_subplot(grid[0, 1])
    return fig, ax3d, [first, fig.add_subplot(grid[1, 1], sharex=first),
                       fig.add_subplot(grid[2, 1], sharex=first)]


def _draw_plots(rec: Recording, axes: list) -> list:
    """
    Draw (wx, wy), wz and |error| against t on three axes; return their cursors.

    w is scaled on the numeric solution (the model is not drawn here: omega.png has it).
    """
    ax_xy, ax_z, ax_e = axes
    u = recording_units(rec)     # rates drawn in it; times stay years, ticked in it
    omega = u.w(rec.omega)
    for ax, components in ((ax_xy, (0, 1)), (ax_z, (2,))):
        limits = []
        for i in components:
            name = 'xyz'[i]
            ax.plot(*envelope(rec.t, omega[:, i]), lw=0.6, color=COLORS[name][:3],
                    label=f'$\\omega_{name}$')
            limits.append(numeric_limits(omega[:, i]))
        ax.set_ylim(min(lo for lo, _ in limits), max(hi for _, hi in limits))
        ax.legend(loc='upper right', fontsize=6, ncol=2)
        ax.set_ylabel(u.rate, fontsize=7)
    if len(rec.norm_t):
        ax_e.plot(*envelope(rec.norm_t, u.w(rec.error_norm)), lw=0.6, color='black',
                  label='$|\\omega - \\omega_{model}|$')
        ax_e.legend(loc='upper left', fontsize=6)
        ax_e.set_ylabel(u.rate, fontsize=7)
        if np.nanmax(rec.error_norm) > 0:
            ax_e.set_yscale('log')
    else:
        ax_e.text(0.5, 0.5, 'no comparator in the recording', ha='center', va='center',
                  transform=ax_e.transAxes, fontsize=8)
    time_axis(axes, u)
    ax_e.xaxis.label.set_fontsize(8)
    cursors = []
    for ax in axes:
        ax.set_xlim(rec.t[0], rec.t[-1] if rec.t[-1] > rec.t[0] else rec.t[0] + 1.0)
        ax.grid(True, lw=0.3)
        ax.tick_params(labelsize=7)
        cursors.append(ax.axvline(rec.t[0], color='tab:red', lw=1.0))
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    return cursors


# -- files --------------------------------------------------------------------------------------

def _target(path, overwrite: bool) -> Path:
    path = Path(path)
    if path.is_symlink():
        raise AnalysisError(f'{path}: is a symbolic link: not written through links')
    if path.exists() and not (overwrite and path.is_file()):
        raise AnalysisError(f'{path}: exists, not overwritten (--overwrite replaces it)'
                            if path.is_file() else f'{path}: exists and is not a file')
    if not path.parent.is_dir():
        raise AnalysisError(f'{path.parent}: no such directory')
    return path


@contextmanager
def _written_as(path: Path, suffix: str) -> Iterator[Path]:
    """
    Yield a temporary name beside ``path``: renamed to ``path`` if the block ends normally.

    Removed otherwise, whatever ends the block (an error, a stop signal's
    :class:`~tumble_ros.exits.Interrupted`): no ``.NAME.PID.tmpSUFFIX`` is left behind.
    """
    temporary = path.with_name(f'.{path.stem}.{os.getpid()}.tmp{suffix}')
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def stderr_bar(name: str, stream: TextIO | None = None) -> Callable[[int, int], None]:
    """Return a progress callback drawing ``name: [#####     ] 50% (60 of 120 frames)``."""
    def report(done: int, total: int) -> None:
        out = stream or sys.stderr
        filled = int(20 * done / max(1, total))
        out.write(f'\r{name}: [{"#" * filled}{" " * (20 - filled)}] '
                  f'{100 * done / max(1, total):3.0f}% ({done} of {total} frames)')
        if done >= total:
            out.write('\n')
        out.flush()
    return report


def check_frames_fps(frames: int, fps: float) -> None:
    """Refuse a frame count outside [1, MAX_FRAMES] or a rate outside [MIN_FPS, MAX_FPS]."""
    if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) \
            or not 1 <= frames <= MAX_FRAMES:
        raise AnalysisError(f'--frames must be an integer in [1, {MAX_FRAMES:,}] (MAX_FRAMES), '
                            f'got {frames!r}')
    if not (isinstance(fps, (int, float, np.floating)) and MIN_FPS <= fps <= MAX_FPS):
        raise AnalysisError(f'--fps must be in [{MIN_FPS:g}, {MAX_FPS:g}], got {fps!r}')


def check_time(at: float | None, t: np.ndarray, what: str = 'the attitude samples',
               unit: str = 'yr') -> None:
    """
    Refuse a time ``at`` [yr] that is not finite or outside [t[0], t[-1]] (None passes).

    The refusal states the times in ``unit`` (the run's time_unit, the unit --at is read in).
    """
    if at is None:
        return
    if not np.isfinite(at):
        raise AnalysisError(f'--at must be a finite time, got {at!r}')
    if not t[0] <= at <= t[-1]:
        def text(years: float) -> str:
            return f'{from_years(float(years), unit):g}'
        raise AnalysisError(f'--at {text(at)} {unit}: outside {what}, [{text(t[0])}, '
                            f'{text(t[-1])}] {unit}')


class _GifStream:
    """
    A GIF written frame by frame: each frame is quantised and appended at once.

    matplotlib's PillowWriter keeps every frame (0.92 MB each at 720 x 324) until the end;
    this writer holds one, whatever the number of frames. Each frame has its own palette (a
    local colour table of up to 256 colours) and a delay of 1/fps s, and the file loops.
    """

    def __init__(self, fps: float) -> None:
        self.delay = max(1, min(65535, round(100.0 / fps)))   # hundredths of a second
        self.fig: Any = None      # the matplotlib Figure, while saving
        self.stream: Any = None   # the open GIF file, while saving

    @contextmanager
    def saving(self, fig, outfile: str, dpi: float):
        """Open ``outfile``, yield, then end the GIF (matplotlib's MovieWriter interface)."""
        self.fig, self.dpi = fig, dpi
        with open(outfile, 'wb') as self.stream:
            width, height = (int(round(v)) for v in fig.get_size_inches() * dpi)
            self.size = (width, height)
            self.stream.write(b'GIF89a' + struct.pack('<HHBBB', width, height, 0, 0, 0)
                              + b'!\xff\x0bNETSCAPE2.0\x03\x01' + struct.pack('<H', 0) + b'\x00')
            yield self
            self.stream.write(b';')

    def grab_frame(self) -> None:
        """Draw the figure and append it as the next frame."""
        from PIL import GifImagePlugin, Image

        buffer = io.BytesIO()
        self.fig.savefig(buffer, format='rgba', dpi=self.dpi)
        frame = Image.frombuffer('RGBA', self.size, buffer.getbuffer(),  # type: ignore[arg-type]
                                 'raw', 'RGBA', 0, 1)  # (Pillow takes any buffer)
        frame = frame.convert('RGB').quantize(256)
        for part in GifImagePlugin.getdata(frame, include_color_table=True,
                                           duration=self.delay * 10):
            self.stream.write(part)


def _writer(path: Path, fps: float):
    suffix = path.suffix.lower()
    if suffix == '.gif':
        return _GifStream(fps)
    if suffix == '.mp4':
        if not animation.writers.is_available('ffmpeg'):
            raise AnalysisError(f'{path}: MP4 needs ffmpeg, which is not installed here; '
                                'write a .gif (Pillow) instead')
        return animation.FFMpegWriter(fps=fps, bitrate=1800)  # type: ignore[arg-type]  # a float
    raise AnalysisError(f'{path}: the animation is a .gif (Pillow) or an .mp4 (ffmpeg), or '
                        'one frame of it a .png')


def write_animation(rec: Recording, path: str | os.PathLike[str], *, frames: int = FRAMES,
                    fps: float = FPS,
                    at: float | None = None, overwrite: bool = False,
                    progress: Callable[[int, int], None] | None = None) -> tuple[Path, int]:
    """
    Write the animation of ``rec`` to ``path`` (.gif or .mp4); return (path, frames written).

    ``frames`` frames spread evenly over the attitude samples, ``fps`` frames per second;
    ``progress(done, total)`` after each frame. A ``.png`` path gets one frame: the attitude
    sample nearest ``at`` [yr] (default: the middle of the run). AnalysisError for a
    recording without attitude samples, a refused path or format, bad options.
    """
    check_frames_fps(frames, fps)
    path = _target(path, overwrite)
    single = path.suffix.lower() == '.png'
    writer = None if single else _writer(path, fps)
    t, quaternion, omega = _attitude_samples(rec)
    check_time(at, t, unit=run_time_unit(rec))
    if single:
        target = (t[0] + t[-1]) / 2 if at is None else at
        chosen = np.array([int(np.argmin(np.abs(t - target)))])
    else:
        chosen = frame_indices(len(t), frames)
    scenes = recorded_scene(rec, t[chosen], quaternion[chosen], omega[chosen])
    fig, ax3d, plots = _figure(with_plots=True)
    cursors = _draw_plots(rec, plots)
    units = recording_units(rec)
    step = int(np.median(np.diff(chosen))) if len(chosen) > 1 else 1
    title = fig.suptitle('', fontsize=9)

    _set_up_3d(ax3d)
    drawn: list = []

    def draw(j: int) -> None:
        for artist in drawn:
            artist.remove()
        drawn[:] = _draw_scene(ax3d, scenes[j])
        for cursor in cursors:
            cursor.set_xdata([t[chosen[j]]] * 2)
        now = units.time_text(t[chosen[j]], 5)
        title.set_text(f'{rec.path.name}: t = {now} (frame {j + 1} of '
                       f'{len(chosen)}, every {step}th attitude sample)' if not single else
                       f'{rec.path.name}: t = {now} (attitude sample '
                       f'{chosen[j]} of {len(t)})')

    if single:
        draw(0)
        with _written_as(path, '.png') as temporary:
            fig.savefig(temporary, format='png', dpi=DPI)
        return path, 1
    # The writer driven directly (not FuncAnimation.save, which draws every frame twice),
    # frame by frame: a stop signal is served between two frames' C calls (drawing, saving).
    assert writer is not None  # (not single)
    with _written_as(path, path.suffix) as temporary, \
            writer.saving(fig, str(temporary), DPI):
        for j in range(len(chosen)):
            draw(j)
            writer.grab_frame()
            if progress is not None:
                progress(j + 1, len(chosen))
    return path, len(chosen)


def write_still(rec: Recording, path: str | os.PathLike[str], *, at: float | None = None,
                overwrite: bool = False) -> tuple[Path, float]:
    """
    Draw the recorded ``markers`` scene at ``at`` [yr] (default: the first) into ``path`` (PNG).

    The scene shown is the first whose stamp is at or after ``at`` (the last one if none is).
    Returns (path, the scene's time [yr]). AnalysisError when the recording has no scene.
    """
    path = _target(path, overwrite)
    check_time(at, rec.t if rec.n else np.zeros(1), 'the run', run_time_unit(rec))
    topic = rec.topic(MARKERS)
    if topic not in rec.topics or rec.topics[topic][1] == 0:
        raise AnalysisError(f'{rec.path}: no {topic} scenes (recorded before the 3D scene '
                            'existed, or with markers:=false)')
    chosen: Any = None
    t_chosen = 0.0
    for record in read_messages(rec.path, topics=[topic]):
        markers = record.message.markers
        if not markers:
            continue
        stamp = markers[0].header.stamp
        t_scene = (int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)) / (
            1e9 * rec.seconds_per_year)
        chosen, t_chosen = record.message, t_scene
        if at is None or t_scene >= at:
            break
    if chosen is None:
        raise AnalysisError(f'{rec.path}: {topic} holds no markers')
    fig, ax3d, _ = _figure(with_plots=False)
    _set_up_3d(ax3d)
    _draw_scene(ax3d, _recorded_body(rec, t_chosen) + marker_scene(chosen))
    ax3d.set_title(f'{rec.path.name}: {topic} at t = {recording_units(rec).time_text(t_chosen)}, '
                   'frame orbital',
                   fontsize=9)
    with _written_as(path, '.png') as temporary:
        fig.savefig(temporary, format='png')
    return path, t_chosen

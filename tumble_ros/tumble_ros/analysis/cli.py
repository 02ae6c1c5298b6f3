"""
The ``analyze`` command: summarise a tumble_ros MCAP recording, optionally write figures.

    python -m tumble_ros.analysis RUN.mcap                     # text summary on stdout
    python -m tumble_ros.analysis RUN.mcap --json              # the same as JSON
    python -m tumble_ros.analysis RUN.mcap --figures figs/     # and PNG figures into figs/
    python -m tumble_ros.analysis RUN.mcap --namespace /ast1   # the simulator of /ast1
    python -m tumble_ros.analysis RUN.mcap --run 0a1b2c3d4e5f  # one run of several (run_id)
    python -m tumble_ros.analysis RUN.mcap --animate run.gif   # the body tumbling (GIF / MP4)
    python -m tumble_ros.analysis RUN.mcap --still scene.png   # the recorded 3D scene, one frame
    python -m tumble_ros.analysis --photometry obs.csv         # periods of a user's lightcurve
    python -m tumble_ros.analysis RUN.mcap --lightcurve        # periods of the recorded one

Exit status: 0 on success (warnings included), :data:`EXIT_TRUNCATED` (2) when the file is
truncated or damaged after some complete chunks (a recorder killed mid-run: the summary, figures
and pictures of what it holds are written, with one ``WARNING: ...`` line on stderr: the result
is partial), 1 on a user error (a missing, empty,
truncated-before-any-chunk or non-MCAP file, a path that is not a regular file, a damaged
chunk, a recording without /angular_velocity, the tumble topics in several namespaces and no
--namespace, the descriptions of several runs (two simulators on the same topics) and no
--run, a figure that exists (without --overwrite) or a symbolic link in the way, a figure
directory that cannot be written, bad options), reported as one ``ERROR: ...`` line on
stderr, never a traceback. Progress for big files (>= 100,000 messages) goes to stderr
(``--quiet`` turns it off).
"""
from __future__ import annotations

import argparse
from collections.abc import Iterable
import json
import math
from pathlib import Path
import sys
from typing import NoReturn

from tumble_ros.core.units import parse_time, TIME_INPUT_HELP, time_parts
from tumble_ros.errors import AnalysisError
from tumble_ros.exits import Interrupted, interrupts
from tumble_ros.io import McapError, WrittenMessages
from tumble_ros.topics import MARKERS

from .display import recording_units, run_time_unit
from .figure_files import FigureExistsError
from .figure_pool import FigurePool, PendingFigures
from .recording import load_recording, normalize_namespace, stderr_progress
from .report import format_summary, summary_to_dict
from .summary import analyze, SummaryParts
from .viewer_layouts import layout_line

__all__ = ['command', 'main', 'EXIT_TRUNCATED']

PROG = 'analyze'
#: Exit status of an analysis of a file truncated (or damaged) after complete chunks: the output
#: is complete for what the file holds, but the file is not the whole run.
EXIT_TRUNCATED = 2


class _UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    # argparse hook: one ERROR line instead of usage+exit 2
    def error(self, message: str) -> NoReturn:  # noqa: D102
        raise _UsageError(f'{message} (see {self.prog} --help)')


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description='Summarise a tumble_ros MCAP recording: topics and counts, simulated '
                    'duration, comparator error, Jacobi-integral drift per segment, impacts, '
                    'dominant frequencies of wx against the theory, and an aliasing check '
                    '(docs/analysis.md).')
    parser.add_argument('file', metavar='FILE.mcap', nargs='?', default=None,
                        help='the recording (optional with --photometry)')
    parser.add_argument('--photometry', metavar='FILE.csv', default=None,
                        help='search a photometry CSV (time, magnitude, optional error and '
                             'geometry: with r, delta or the Sun and observer vectors, '
                             'reduced magnitudes are searched; docs/analysis.md, "Periods '
                             'from a lightcurve") for one or two periods and print them')
    parser.add_argument('--lightcurve', action='store_true',
                        help='also search the recorded lightcurve topic for its periods and '
                             'print them; with --figures also draw lightcurve.png')
    parser.add_argument('--period-range', type=float, nargs=2, default=None,
                        metavar=('MIN', 'MAX'),
                        help='with --photometry or --lightcurve: the periods searched [h] '
                             '(default: from the sampling: 4 median sampling steps to the '
                             'data span, the short end raised to bound the search; the output '
                             'says which)')
    parser.add_argument('--figures', metavar='DIR', default=None,
                        help='also write the figures (PNG) into DIR, created if needed '
                             '(default: no figures); existing files are not overwritten and '
                             'symbolic links are refused')
    parser.add_argument('--overwrite', action='store_true',
                        help='with --figures: replace figure files that exist (links are '
                             'still refused)')
    parser.add_argument('--namespace', metavar='NS', default=None,
                        help='the ROS namespace of the simulator to analyse, e.g. /ast1 '
                             '("/" for none); default: the only one in the file')
    parser.add_argument('--run', metavar='ID', default=None,
                        help='the run to analyse (the run_id of its /scenario descriptions), '
                             'when the recording holds several; default: the only one')
    parser.add_argument('--json', action='store_true',
                        help='print the summary as JSON instead of text')
    parser.add_argument('--peaks', type=int, default=5, metavar='N',
                        help='number of spectral peaks to report (default: %(default)s)')
    parser.add_argument('--animate', metavar='FILE', default=None,
                        help='also write an animation of the body tumbling, with w and the '
                             'error beside it: FILE.gif (Pillow) or FILE.mp4 (needs ffmpeg); '
                             'FILE.png: one frame of it (see --at)')
    parser.add_argument('--frames', type=int, default=None, metavar='N',
                        help='with --animate: frames, spread evenly over the run (default: '
                             'analysis.animation.FRAMES, 120)')
    parser.add_argument('--fps', type=float, default=None, metavar='F',
                        help='with --animate: frames per second (default: '
                             'analysis.animation.FPS, 12)')
    parser.add_argument('--still', metavar='FILE.png', default=None,
                        help='also draw one recorded 3D scene (the markers topic: what RViz and '
                             'Foxglove show) with matplotlib')
    parser.add_argument('--at', default=None, metavar='T',
                        help='with --still: the first scene at or after T (default: the first '
                             'scene); with --animate FILE.png: the sample nearest T (default: '
                             f'the middle of the run). T: {TIME_INPUT_HELP}')
    parser.add_argument('--quiet', action='store_true',
                        help='no progress messages on stderr')
    return parser


def _error(text: object) -> int:
    print(f'ERROR: {" ".join(str(text).split())}', file=sys.stderr)
    return 1


def _figures(rec, summary, args, pool: FigurePool | None = None,
             pending: PendingFigures | None = None) -> list:
    """
    Write the figures (in ``pool``'s workers if given); failures are one-line AnalysisErrors.

    ``pending``: the figures ``pool`` started drawing (:meth:`FigurePool.begin`).
    """
    try:
        if pool is not None and pending is not None:
            return pool.finish(pending, args.figures, overwrite=args.overwrite)
        if pool is not None:        # no matplotlib here: the workers have it
            return pool.write_figures(rec, args.figures, summary, overwrite=args.overwrite)
        from .figures import write_figures   # matplotlib only when asked for
        return write_figures(rec, args.figures, summary, overwrite=args.overwrite)
    except FigureExistsError as err:
        raise AnalysisError(f'{err} (--overwrite replaces existing figures)') from None
    except OSError as err:
        raise AnalysisError(f'cannot write figures to {args.figures}: {err.strerror or err}'
                            + (f': {err.filename}' if err.filename else '')) from None


def _check_options(args) -> str | None:
    """Why the options are wrong, or None."""
    if args.file is None and args.photometry is None:
        return 'the following arguments are required: FILE.mcap (or --photometry FILE.csv)'
    if args.period_range is not None and args.photometry is None and not args.lightcurve:
        return '--period-range needs --photometry FILE.csv or --lightcurve'
    if args.lightcurve and args.file is None:
        return '--lightcurve needs FILE.mcap (--photometry FILE.csv searches a CSV)'
    if args.photometry is not None and args.file is not None:
        return '--photometry FILE.csv analyses the CSV alone: drop FILE.mcap'
    if args.period_range is not None and not 0.0 < args.period_range[0] < args.period_range[1]:
        return f'--period-range needs 0 < MIN < MAX [h], got {args.period_range}'
    if args.peaks < 1:
        return f'--peaks must be >= 1, got {args.peaks}'
    if args.overwrite and args.figures is None and args.animate is None and args.still is None:
        return '--overwrite needs --figures DIR, --animate FILE or --still FILE'
    if (args.frames is not None or args.fps is not None) and args.animate is None:
        return '--frames and --fps need --animate FILE'
    if args.at is not None and args.still is None and not str(args.animate).endswith('.png'):
        return '--at needs --still FILE.png or --animate FILE.png'
    if args.at is not None:
        try:
            time_parts(args.at, '--at')
        except ValueError as err:
            return str(err)
    if args.animate is not None:
        from . import animation   # matplotlib only when asked for
        try:
            animation.check_frames_fps(
                animation.FRAMES if args.frames is None else args.frames,
                animation.FPS if args.fps is None else args.fps)
        except AnalysisError as err:
            return str(err)
    if args.namespace is not None:
        try:
            args.namespace = normalize_namespace(args.namespace)
        except AnalysisError as err:
            return f'--namespace: {err}'
    return None


def command(argv: Iterable[str] | None = None, written: WrittenMessages | None = None,
            pool: FigurePool | None = None) -> int:
    """
    Run the command on ``argv`` (without the program name); returns the exit status.

    For the main job: ``written``, the messages of FILE.mcap as its writer in this process kept
    them (:func:`~.recording.load_recording` takes them instead of reading the file back);
    ``pool``, worker processes started earlier that draw the figures (:mod:`.figure_pool`),
    from the recording as soon as it is loaded, while this process analyses it.

    SIGINT, SIGTERM and SIGHUP stop it wherever it is (:func:`tumble_ros.exits.interrupts`):
    one line on stderr, exit 128 + the signal (130, 143, 129); the file being written (an
    animation, a still) is removed, and the drawing ``pool`` was given is abandoned (its
    owner's close ends the workers).
    """
    try:
        with interrupts():
            return _command(argv, written, pool)
    except Interrupted as stop:
        print(f'{PROG}: stopped by {stop.name}', file=sys.stderr)
        return stop.exit_code


def _command(argv: Iterable[str] | None, written: WrittenMessages | None,
             pool: FigurePool | None) -> int:
    """:func:`command` without its handling of the stop signals."""
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = _parser().parse_args(argv)
    except _UsageError as err:
        return _error(str(err))
    except SystemExit as exit_:          # --help
        return int(exit_.code or 0)
    problem = _check_options(args)
    if problem:
        return _error(problem)
    if args.photometry is not None:
        return _photometry(args)
    try:
        progress = None if args.quiet else stderr_progress()
        rec = load_recording(args.file, namespace=args.namespace, run=args.run,
                             progress=progress, written=written)
        for line in rec.left_out:
            print(f'WARNING: {line}', file=sys.stderr)
        # the figures drawn in the pool while this process analyses: what they take from the
        # summary the drawing processes compute as analyze does (the same bytes)
        pending = (pool.begin(rec, SummaryParts(rec, args.peaks))
                   if pool is not None and args.figures is not None else None)
        summary = analyze(rec, n_peaks=args.peaks)
        periods = _recorded_periods(rec, args)      # before the figures are written: its check
        figures = [] if args.figures is None else _figures(rec, summary, args, pool, pending)
        extra = _pictures(rec, args)
    except (McapError, AnalysisError) as err:
        return _error(err)
    except KeyboardInterrupt:
        return _error('interrupted')
    if args.json:
        data = summary_to_dict(summary)
        data['figures'] = [str(p) for p in figures]
        data.update({key: str(value) for key, (value, _) in extra.items()})
        if periods is not None:
            data['lightcurve_periods'] = _solution_dict(periods[0])
            data['figures'] += [str(p) for p in periods[1:]]
        print(json.dumps(data, indent=1, allow_nan=False))
    else:
        print(format_summary(summary))
        if args.figures is not None:
            print(f'figures: {len(figures)} written to {args.figures}')
            for path in figures:
                print(f'  {path}')
        for key, (path, what) in extra.items():
            print(f'{key}: {path} ({what})')
        if periods is not None:
            from .periods import format_periods
            print('periods of the recorded lightcurve topic (t in hours):')
            print(format_periods(periods[0]))
            for path in periods[1:]:
                print(f'lightcurve: {path}')
        print(layout_line(rec.seconds_per_year))    # the viewer layout made for its timeline
    if periods is not None:
        _period_warnings(periods[0])
    return _partial(summary)


def _recorded_periods(rec, args) -> tuple | None:
    """Return None, or with --lightcurve (the recorded lightcurve's solution, figure paths)."""
    if not args.lightcurve:
        return None
    from .lightcurve import FIGURE_NAME, recorded_periods, write_lightcurve_figure
    if args.figures is not None and not args.overwrite and (Path(args.figures)
                                                            / FIGURE_NAME).exists():
        raise AnalysisError(f'{Path(args.figures) / FIGURE_NAME} exists (--overwrite '
                            f'replaces existing figures)')
    low, high = args.period_range if args.period_range is not None else (None, None)
    t, mag, sol = recorded_periods(rec, low, high, progress=_search_progress(args))
    if args.figures is None:
        return (sol,)
    try:
        return (sol, write_lightcurve_figure(Path(args.figures) / FIGURE_NAME, t, mag, sol,
                                             overwrite=args.overwrite))
    except OSError as err:
        raise AnalysisError(f'cannot write {FIGURE_NAME} to {args.figures}: '
                            f'{err.strerror or err}') from None


def _solution_dict(sol) -> dict:
    """Return the PeriodSolution as JSON-ready values (NaN, p2 for one period: None)."""
    from dataclasses import asdict

    def plain(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {key: plain(item) for key, item in value.items()}
        if isinstance(value, (list, tuple)):
            return [plain(item) for item in value]
        return value
    out = plain(asdict(sol))
    out['unit'] = 'h'
    return out


def _search_progress(args):
    """Return the period search's progress on stderr (after 2 s), or None with --quiet."""
    from .periods import stderr_search_progress
    return None if args.quiet else stderr_search_progress()


def _photometry(args) -> int:
    """Search a photometry CSV for its periods; print them (text or JSON), warnings on stderr."""
    from dataclasses import replace

    from .periods import DAYS_IN_HOURS, format_periods, search_periods
    from .photometry_file import read_photometry, reduced_photometry
    try:
        data = read_photometry(args.photometry)
        magnitude, reduction = reduced_photometry(data)    # with the CSV's geometry, reduced
        low, high = args.period_range if args.period_range is not None else (None, None)
        try:
            sol = search_periods(data.t, magnitude, data.sigma, low, high,
                                 named_periods=DAYS_IN_HOURS, unit=' h',
                                 progress=_search_progress(args))
        except ValueError as err:
            raise AnalysisError(f'{args.photometry}: {err}') from None
        if reduction is not None:
            sol = replace(sol, reduction=reduction)
    except AnalysisError as err:
        return _error(err)
    except KeyboardInterrupt:
        return _error('interrupted')
    if args.json:
        print(json.dumps(_solution_dict(sol), indent=1, allow_nan=False))
    else:
        print(f'photometry: {args.photometry} (time column {data.time_column}, hours)')
        print(format_periods(sol))
    _period_warnings(sol)
    return 0


def _period_warnings(sol) -> None:
    """Each of the period search's warnings as one ``WARNING:`` line on stderr."""
    for text in sol.warnings:
        print(f'WARNING: period search: {text}', file=sys.stderr)


def _partial(summary) -> int:
    """0 for a finalised file; for a truncated one, say so on stderr and return EXIT_TRUNCATED."""
    if summary.finalised:
        return 0
    print(f'WARNING: {summary.path} is truncated ({" ".join(str(summary.problem).split())}): '
          f'analysed its complete chunks only (exit status {EXIT_TRUNCATED})', file=sys.stderr)
    return EXIT_TRUNCATED


def _at(rec, text: str | None) -> float | None:
    """Return --at in years: a bare number in the recording's time_unit, else its own unit."""
    if text is None:
        return None
    try:
        return parse_time(text, run_time_unit(rec), '--at')
    except ValueError as err:
        raise AnalysisError(str(err)) from None


def _pictures(rec, args) -> dict[str, tuple]:
    """Write the animation and the still asked for: {'animation'|'still': (path, what)}."""
    if args.animate is None and args.still is None:
        return {}
    from . import animation   # matplotlib only when asked for
    out = {}
    at = _at(rec, args.at)
    if args.animate is not None:
        frames = args.frames or animation.FRAMES
        fps = args.fps or animation.FPS
        bar = None if args.quiet else animation.stderr_bar(f'animating {args.animate}')
        path, count = animation.write_animation(rec, args.animate, frames=frames, fps=fps,
                                                at=at, overwrite=args.overwrite,
                                                progress=bar)
        out['animation'] = (path, f'{count} frames at {fps:g} fps' if count > 1 else 'one frame')
    if args.still is not None:
        path, t = animation.write_still(rec, args.still, at=at, overwrite=args.overwrite)
        out['still'] = (path, f'the {rec.topic(MARKERS)} scene at t = '
                              f'{recording_units(rec).time_text(t)}')
    return out


def main(args: list[str] | None = None) -> int:
    """
    Run the console-script entry point (``analyze = tumble_ros.analysis.cli:main``).

    ``args`` is as sys.argv (program name first); None means sys.argv.
    """
    return command(list(sys.argv if args is None else args)[1:])


if __name__ == '__main__':
    from tumble_ros.exits import call_closing_quietly, end_if_stopped  # a closed pipe: 141

    sys.exit(end_if_stopped(call_closing_quietly(main, sys.argv)))   # stopped: no teardown

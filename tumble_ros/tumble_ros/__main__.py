"""
``python -m tumble_ros``: the project's own entry point (the pip-only path has no ``ros2``).

    python -m tumble_ros [SCENARIO] [--live]       the main job (default: the default scenario)
    python -m tumble_ros <executable> [args ...]   run an executable, as `ros2 run tumble_ros` does
    python -m tumble_ros --help                    the usage (USAGE); <executable> --help: its own

Executables: sim, comparator, recorder, bringup, analyze, ensemble, encounter, invert. SCENARIO
is a params file or the name of a shipped one (``fig10``: config/fig10.yaml).

The main job simulates the scenario, compares it with the paper's analytic solution and records
everything to ``recordings/<scenario>_<UTC time>.mcap`` (``bringup --offline``: the recording is
written straight from the simulation; ``--live`` runs the three nodes over the ROS graph
instead, as ``bringup`` does), then analyses the file. Offline, the analysis takes the messages
from memory (the writer kept them: :class:`tumble_ros.io.WrittenMessages`, the same Recording as
reading the file back), and the figures are drawn by a worker process forked before the
recording, which loads matplotlib while it runs, and a helper it forks
(:mod:`tumble_ros.analysis.figure_pool`, the same PNG bytes); this process never imports
matplotlib.

Every executable, here and as installed for ``ros2 run`` (setup.py points them all to
:func:`entry`), starts under :class:`~tumble_ros.nodes.shutdown.StopSignals`: a SIGINT, SIGTERM
or SIGHUP while it is still importing ends it quietly (nothing is compiled at import: numba
compiles a loop on its first use), with the exit code it gives when stopped later (0 for a
node, 128 + the signal otherwise). A closed stdout or stderr (``bringup | head -1``) ends it
quietly too, as Unix tools do: exit 141 (128 + SIGPIPE), the recording finalised. The offline
commands (analyze, ensemble, encounter, invert) serve a stop where they are
(:func:`tumble_ros.exits.interrupts`, taking over one the early handler recorded) and, stopped,
end without the interpreter's teardown (:func:`~tumble_ros.exits.end_if_stopped`).

The main job imports with the garbage collector off until its figure worker is forked (the
imports free nothing; :func:`_figure_pool`), numba without coverage and rosidl_generator_py
without its code generator (:func:`numba_without_coverage`, :func:`rosidl_without_generator`),
and its figures are drawn while it analyses the recording.

The main job ends its process as soon as it is done (:func:`quick_exit`): the atexit handlers
run and the standard streams are flushed, but the interpreter's teardown (clearing ~1,200
modules and collecting what they hold: 0.2-0.35 s of a 4-s Fig 9 run) is left to the OS.
"""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
import gc
import importlib
from pathlib import Path
import signal
import sys
from typing import Any

from tumble_ros.exits import (BROKEN_PIPE_EXIT, call_closing_quietly, end_if_stopped,
                              quick_exit)

#: Executables: name -> "module:function", as in setup.py's console_scripts.
EXECUTABLES = {
    'sim': 'tumble_ros.nodes.sim:main',
    'comparator': 'tumble_ros.nodes.comparator:main',
    'recorder': 'tumble_ros.nodes.recorder:main',
    'bringup': 'tumble_ros.nodes.bringup:main',
    'analyze': 'tumble_ros.analysis.cli:main',
    'ensemble': 'tumble_ros.cli.ensemble:main',
    'encounter': 'tumble_ros.cli.encounter:main',
    'invert': 'tumble_ros.cli.invert:main',
}
#: What each executable does, in one line of ``--help``.
SUMMARIES = {
    'sim': 'the simulator node: publishes omega, the attitude, /clock; the apply_impact service',
    'comparator': "the paper's analytic solution beside the simulator's, and the error",
    'recorder': 'every topic to an MCAP file',
    'bringup': 'the three nodes in one process (--offline: the recording without a ROS graph)',
    'analyze': "a recording's summary and figures, offline",
    'ensemble': 'N bodies (impacts, spread spin states), on Dask, into a Zarr store',
    'encounter': 'an ensemble through a flyby: the spin state before and after',
    'invert': "a tumbler's spin state and shape fitted to photometry (docs/inversion.md)",
}
#: ``python -m tumble_ros --help``: the usage, not the module's notes (and kept under -OO).
USAGE = """usage: python -m tumble_ros [SCENARIO] [--live]
       python -m tumble_ros EXECUTABLE [ARGS ...]

Without an executable, the main job: simulate SCENARIO, compare it with the paper's analytic
solution, record everything to recordings/<scenario>_<UTC time>.mcap and analyse it (a summary
on stdout, the figures in recordings/<scenario>_<UTC time>_figures/). SCENARIO is a params file
or a shipped scenario's name (default, fig3 ... fig10, apophis_2029, apophis_2029_shape_degree4,
apophis_2029_moon_sun, photometric_campaign, tumbling_from_observables); without one: default.
Times, rates and periods are printed in the scenario's time_unit (periods also in hours).

  --live      run the three nodes over the ROS graph (default: the recording written offline)
  -h, --help  this text

Executables (EXECUTABLE --help: its own options; as `ros2 run tumble_ros EXECUTABLE`):
""" + '\n'.join(f'  {name:<11} {text}' for name, text in SUMMARIES.items()) + """

Examples:
  python -m tumble_ros fig9
  python -m tumble_ros analyze recordings/run.mcap --figures figs/
Docs: README.md; the nodes, topics and parameters: docs/ros.md."""
#: The executables whose ``main`` takes the arguments without the program name.
BARE_ARGV = frozenset({'ensemble', 'encounter', 'invert'})
#: The nodes: they exit 0 when a signal stops them.
NODES = frozenset({'sim', 'comparator', 'recorder'})
#: The executables that import no numba (a recording needs none): their start imports none.
WITHOUT_NUMBA = frozenset({'recorder'})


def run_executable(name: str, args: list[str], **options: Any) -> int:
    """
    Run an executable's ``main`` with ``args`` (its sys.argv without the program name).

    ``options``: keyword arguments of that ``main`` (the main job's ``keep`` for bringup).
    """
    try:
        from tumble_ros.nodes.shutdown import StopSignals   # light: no rclpy, no numba
    except KeyboardInterrupt:       # a SIGINT before the handler (Python's own start-up)
        return 0 if name in NODES else 128 + signal.SIGINT
    with StopSignals(name) as early:
        try:
            module, function = EXECUTABLES[name].split(':')
            target = getattr(_imported(name, module), function)
        except KeyboardInterrupt:   # a SIGINT before the handler (Python's own start-up)
            return 0 if name in NODES else 128 + signal.SIGINT
        if early.requested:         # stopped while importing: nothing was started
            return 0 if name in NODES else early.exit_code
        return call_closing_quietly(target, args if name in BARE_ARGV else [name, *args],
                                    **options)


def _imported(name: str, module: str) -> Any:
    """
    Import executable ``name``'s module as the main job does: no collector, no unused imports.

    The collector is off during the imports (they free nothing), numba comes without
    ``coverage`` (but for the executables in :data:`WITHOUT_NUMBA`, which import no numba) and
    ``rosidl_generator_py`` without its code generator: ~0.06-0.09 s of a node's ~0.6-s import
    (benchmarks/HISTORY.md, "Node start-up").
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        if name not in WITHOUT_NUMBA:
            numba_without_coverage()
        rosidl_without_generator()
        return importlib.import_module(module)
    finally:
        if enabled:
            gc.enable()


def entry() -> int:
    """
    Console-script entry of every executable: the name is the installed script's.

    A node's process ends by :func:`~tumble_ros.exits.quick_exit` once its ``main`` returned
    (its files finalised, its goodbyes sent, its context shut down): the interpreter's teardown
    (clearing ~1,200 modules, numba's among them) took 1.5-2.5 s of a node's stop on a loaded
    machine, against ``ros2 launch``'s 5-s limit (docs/ros.md, "Signals and exit codes"). A
    command a stop signal ended (:func:`tumble_ros.exits.interrupts`) ends at once too
    (:func:`~tumble_ros.exits.end_if_stopped`).
    """
    name = Path(sys.argv[0]).name
    code = run_executable(name, sys.argv[1:])
    if name in NODES:
        quick_exit(code)
    return end_if_stopped(code)


def numba_without_coverage() -> None:
    """
    Import numba without ``coverage`` when no coverage is measured in this process (~0.05 s).

    numba imports ``coverage`` whenever it is installed (the test environment's), only to
    report to a running coverage measurement the lines its compiled code covered. When
    ``coverage`` is not imported yet, no measurement runs: numba's coverage support is imported
    with ``coverage`` hidden (``sys.modules['coverage'] = None`` for that import only), and a
    later ``import coverage`` works as usual. With ``coverage`` imported (a run measuring
    coverage) or without numba, nothing changes.
    """
    if 'coverage' in sys.modules:
        return
    sys.modules['coverage'] = None      # type: ignore[assignment]  # ImportError for numba
    try:
        importlib.import_module('numba.misc.coverage_support')
    except ImportError:
        pass
    finally:
        if 'coverage' in sys.modules and sys.modules['coverage'] is None:
            del sys.modules['coverage']


#: What ``import rosidl_generator_py`` imports only for its code generator (``generate_py``,
#: used when messages are built, never at run time): lark, rosidl_parser, empy.
ROSIDL_GENERATOR = 'rosidl_generator_py.generate_py_impl'


def rosidl_without_generator() -> None:
    """
    Import ``rosidl_generator_py`` without its code generator (~0.05 s of the main job).

    Every ROS message module imports ``rosidl_generator_py`` for its ``import_type_support``
    when a publisher or a service is made (the offline run's nodes, built for their
    parameters, make some), and the package's ``__init__`` also imports its message code
    generator (``generate_py``: lark's grammar, rosidl_parser, empy), which it leaves out with
    a debug log when that import fails. Here the generator is hidden for that import
    (``sys.modules[ROSIDL_GENERATOR] = None``): the package has ``import_type_support`` as
    before and no ``generate_py``; a later ``import rosidl_generator_py.generate_py_impl``
    works. Once the package is imported, or without it, nothing changes.
    """
    if 'rosidl_generator_py' in sys.modules or ROSIDL_GENERATOR in sys.modules:
        return
    sys.modules[ROSIDL_GENERATOR] = None    # type: ignore[assignment]  # ImportError there
    try:
        importlib.import_module('rosidl_generator_py')
    except ImportError:
        pass
    finally:
        if ROSIDL_GENERATOR in sys.modules and sys.modules[ROSIDL_GENERATOR] is None:
            del sys.modules[ROSIDL_GENERATOR]


def main_job(argv: list[str]) -> int:
    """Bringup on a scenario file (or the default scenario), then the analysis of the recording."""
    live = '--live' in argv
    argv = [a for a in argv if a != '--live']
    if len(argv) > 1 or (argv and argv[0].startswith('-')):
        print(f'python -m tumble_ros: unknown arguments {argv}; executables: '
              f"{', '.join(EXECUTABLES)} (python -m tumble_ros --help)", file=sys.stderr)
        return 2
    gc.disable()    # during the imports (see _figure_pool, which turns it on again)
    try:
        numba_without_coverage()
        rosidl_without_generator()
        from tumble_ros.io import gather_in_background, WrittenMessages
        from tumble_ros.nodes.recorder import default_output

        output = default_output(Path(argv[0]).stem if argv else 'default')
        mode = [] if live else ['--offline']
        # offline, the messages written stay in memory for the analysis (not read back)
        written = None if live else WrittenMessages()
    except BaseException:
        gc.enable()
        raise
    with _figure_pool() as pool:    # workers warm up for the figures while the run records
        # the columns gathered in a thread as they are written (the other core, while the
        # run simulates): none left to gather after the recording
        background = None if written is None else gather_in_background(written)
        try:
            code = run_executable('bringup', [*argv, *mode, '--output', str(output)],
                                  keep=written)
            if code == BROKEN_PIPE_EXIT:
                return code
            if code != 0 or not output.exists() or output.stat().st_size == 0:
                _release(output)
                return code or 1
            return analyse(output, written, pool)
        finally:
            if background is not None:
                background.close()


@contextmanager
def _figure_pool() -> Iterator[Any]:
    """
    Yield a started FigurePool (tumble_ros.analysis.figure_pool), or None; close it after.

    The garbage collector, off since the main job started (:func:`main_job`), is turned on
    again once the pool's worker is forked: the imports before it (~1,000 modules: functions,
    classes, module dicts, nothing to free) ran ~200 young and ~20 older collections over
    what they made, ~0.08 s of the main process's path at load 3. The worker, forked with the
    collector off, keeps it off and collects when it draws (:mod:`.analysis.figure_pool`).
    """
    try:
        try:
            from tumble_ros.analysis.figure_pool import FigurePool
        except ImportError:             # no analysis available: the recording alone
            pool = None
        else:
            gc.freeze()     # what is loaded stays shared with the workers (no collector writes)
            pool = FigurePool.start()
    finally:
        gc.enable()
    if pool is None:
        yield None
        return
    with pool:
        yield pool


def _release(claimed: Path) -> None:
    """Remove the name default_output claimed if the run left it empty (it recorded nothing)."""
    try:
        if claimed.stat().st_size == 0:
            claimed.unlink()
    except OSError:
        pass


def analyse(recording: Path, written: Any = None, pool: Any = None) -> int:
    """
    Summary and figures of a recording (figures beside it, in <name>_figures/).

    ``written``: its messages as the writer kept them (:class:`tumble_ros.io.WrittenMessages`),
    analysed instead of reading the file back (the same Recording); ``pool``: a started
    :class:`tumble_ros.analysis.figure_pool.FigurePool` that draws the figures.
    """
    try:
        cli = importlib.import_module('tumble_ros.analysis.cli')
    except ImportError:
        print(f'recorded {recording} (no analysis available)')
        return 0
    return cli.command([str(recording), '--figures', str(recording.with_suffix('')) + '_figures'],
                       written=written, pool=pool)


def is_main_job(argv: list[str]) -> bool:
    """Tell whether :func:`main` runs the main job on ``argv`` (not an executable, not --help)."""
    return not (argv and (argv[0] in EXECUTABLES or argv[0] in ('-h', '--help')))


def ends_quickly(argv: list[str]) -> bool:
    """Tell whether ``python -m tumble_ros`` ends by ``quick_exit``: the main job, a node."""
    return is_main_job(argv) or argv[0] in NODES


#: What a module missing from the environment comes with, by its top-level name: a pip install
#: of the repository root has no ROS, and the ensembles' stack is an extra (docs/setup.md).
MISSING_MODULES = {
    **dict.fromkeys(('dask', 'distributed', 'xarray', 'zarr'),
                    "the ensembles' extra: pip install 'tumble_ros[ensembles]'"),
    'rclpy': 'ROS 2 Jazzy (make setup, or a ROS install: docs/setup.md); without ROS, '
             'analyze, ensemble and encounter run',
}
#: Top-level names of the ROS packages besides rclpy (the message and interface packages).
ROS_SUFFIXES = ('_msgs', '_srvs', '_interfaces', '_python', '_runtime_py')


def missing_module_line(program: str, err: ModuleNotFoundError) -> str:
    """Return the one line saying which module ``program`` misses and what provides it."""
    top = (err.name or '').split('.')[0]
    if top.startswith(('rosidl', 'launch')) or top.endswith(ROS_SUFFIXES):
        top = 'rclpy'
    where = MISSING_MODULES.get(top, 'a dependency the installation lacks')
    return f'{program}: no module named {err.name!r}: it comes with {where}'


def main(argv: list[str] | None = None) -> int:
    """Run ``python -m tumble_ros``: an executable, the main job, or this usage (--help)."""
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in ('-h', '--help'):
        return call_closing_quietly(_usage, argv)   # `tumble_ros --help | head -3`: 141
    try:
        if argv and argv[0] in EXECUTABLES:
            return run_executable(argv[0], argv[1:])
        return main_job(argv)
    except ModuleNotFoundError as err:
        if (err.name or '').split('.')[0] == 'tumble_ros':
            raise                   # not the environment's: a bug of this package
        program = ' '.join(['tumble_ros', *argv[:1]])
        print(missing_module_line(program, err), file=sys.stderr)
        return 1


def _usage(argv: list[str]) -> int:
    """Print the usage (:data:`USAGE`, kept under ``python -OO``)."""
    print(USAGE)
    return 0


def console() -> int:
    """
    Run the ``tumble_ros`` command a pip install makes (pyproject.toml): ``python -m tumble_ros``.

    The same arguments and exit codes; the main job and the nodes end at once
    (:func:`~tumble_ros.exits.quick_exit`, :func:`ends_quickly`), and so does a command a stop
    signal ended (:func:`~tumble_ros.exits.end_if_stopped`).
    """
    code = main()
    if ends_quickly(sys.argv[1:]):
        quick_exit(code)
    return end_if_stopped(code)


if __name__ == '__main__':
    raise SystemExit(console())

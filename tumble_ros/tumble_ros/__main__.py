"""
``python -m tumble_ros``: the project's own entry point (the pip-only path has no ``ros2``).

    python -m tumble_ros [SCENARIO.yaml] [--live]  the main job (default: the default scenario)
    python -m tumble_ros <executable> [args ...]   run an executable, as `ros2 run tumble_ros` does

The main job simulates the scenario, compares it with the paper's analytic solution and records
everything to ``recordings/<scenario>_<UTC time>.mcap`` (``bringup --offline``: the recording is
written straight from the simulation; ``--live`` runs the three nodes over the ROS graph
instead, as ``bringup`` does), then analyses the file.
"""
from __future__ import annotations

import importlib
from pathlib import Path
import sys

#: Executables: name -> "module:function", as in setup.py's console_scripts.
EXECUTABLES = {
    'sim': 'tumble_ros.nodes.sim:main',
    'comparator': 'tumble_ros.nodes.comparator:main',
    'recorder': 'tumble_ros.nodes.recorder:main',
    'bringup': 'tumble_ros.nodes.bringup:main',
    'analyze': 'tumble_ros.analysis.cli:main',
}


def run_executable(name: str, args: list[str]) -> int:
    """Run an executable's ``main`` with ``args`` (its sys.argv without the program name)."""
    module, function = EXECUTABLES[name].split(':')
    return getattr(importlib.import_module(module), function)([name, *args]) or 0


def main_job(argv: list[str]) -> int:
    """Bringup on a scenario file (or the default scenario), then the analysis of the recording."""
    live = '--live' in argv
    argv = [a for a in argv if a != '--live']
    if len(argv) > 1 or (argv and argv[0].startswith('-')):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    from tumble_ros.nodes.recorder import default_output

    output = default_output(Path(argv[0]).stem if argv else 'default')
    mode = [] if live else ['--offline']
    code = run_executable('bringup', [*argv, *mode, '--output', str(output)])
    if code != 0 or not output.exists() or output.stat().st_size == 0:
        _release(output)
        return code or 1
    return analyse(output)


def _release(claimed: Path) -> None:
    """Remove the name default_output claimed if the run left it empty (it recorded nothing)."""
    try:
        if claimed.stat().st_size == 0:
            claimed.unlink()
    except OSError:
        pass


def analyse(recording: Path) -> int:
    """Summary and figures of a recording (figures beside it, in <name>_figures/)."""
    try:
        cli = importlib.import_module('tumble_ros.analysis.cli')
    except ImportError:
        print(f'recorded {recording} (no analysis available)')
        return 0
    return cli.command([str(recording), '--figures', str(recording.with_suffix('')) + '_figures'])


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in EXECUTABLES:
        return run_executable(argv[0], argv[1:])
    return main_job(argv)


if __name__ == '__main__':
    raise SystemExit(main())

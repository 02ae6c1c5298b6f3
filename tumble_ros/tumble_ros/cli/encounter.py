r"""
The encounter command line: a tumbler's spin state through a flyby, over what is uncertain.

    python -m tumble_ros.cli.encounter tumble_ros/config/apophis_2029.yaml --bodies 1000 \
        --inertia-draws 10 --inertia-spread 0.03 0.015 --seed 1 --out docs/figures/apophis
    ... --workers 2                 # the bodies as chunks on a local Dask cluster
    ... --scheduler tcp://HEAD:8786 # or on a cluster (docs/python.md: Running on a cluster)

(``ros2 run tumble_ros encounter ...`` on a ROS 2 install.) Writes ``encounter.png`` (the
distributions after the encounter), ``summary.txt`` (the report printed on stdout) and
``encounter.npz`` (every body's inputs and states) to ``--out``: checked before the run (a
file there is refused unless ``--overwrite``, a symbolic link always), written at the end, each
file whole or not at all. Exit status: 0 every body succeeded, 1 some failed, 2 refused input
(one ``error:`` line), 130 / 143 / 129 stopped by SIGINT / SIGTERM / SIGHUP (nothing
written). The work is
:func:`tumble_ros.analysis.encounter.encounter_ensemble`; this module only parses and reports.
"""
from __future__ import annotations

import argparse
from functools import partial
import io
from pathlib import Path
import sys
import time
from typing import Sequence

import numpy as np

from tumble_ros.analysis.figure_files import check_outputs, write_files
from tumble_ros.cli.engine import add_engine_arguments, engine
from tumble_ros.core import load_scenario, ScenarioError
from tumble_ros.errors import TumbleRosError
from tumble_ros.exits import Interrupted, interrupts
from tumble_ros.topics import SIM_NODE_PARAMETERS

__all__ = ['main']


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog='python -m tumble_ros.cli.encounter',
        description="Run N tumblers with a scenario's observed spin state (its periods and "
                    'pole) through its flyby, drawing the tumbling phase, the turn about L and '
                    'the moments of inertia; report the spin state after.')
    p.add_argument('config', help='scenario params file with an orbit.kind: flyby (e.g. '
                                  'tumble_ros/config/apophis_2029.yaml)')
    p.add_argument('--bodies', '-n', type=int, default=1000, help='bodies (default 1000)')
    p.add_argument('--inertia-draws', type=int, default=10,
                   help='moments of inertia drawn (the first is the nominal; default 10)')
    p.add_argument('--inertia-spread', type=float, nargs=2, default=(0.03, 0.015),
                   metavar=('DA', 'DB'),
                   help='half-widths of the uniform spread of I_a/I_c and I_b/I_c '
                        '(default 0.03 0.015)')
    p.add_argument('--seed', type=int, default=1, help='random seed (default 1)')
    p.add_argument('--out', type=Path, help='folder for encounter.png, summary.txt, '
                                            'encounter.npz')
    p.add_argument('--no-arrays', action='store_true', help='do not write encounter.npz')
    p.add_argument('--overwrite', action='store_true',
                   help='replace files of --out that exist (symbolic links are still refused)')
    add_engine_arguments(p)
    p.add_argument('--quiet', '-q', action='store_true', help='no progress lines')
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    start = time.perf_counter()

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            print(f'encounter: inertia draw {done}/{total} done, '
                  f'{time.perf_counter() - start:.1f} s', file=sys.stderr)

    names = ['encounter.png', 'summary.txt'] + ([] if args.no_arrays else ['encounter.npz'])
    try:
        if args.overwrite and args.out is None:
            raise ScenarioError('--overwrite: needs --out DIR')
        if args.out is not None:     # refused now, not after the run
            check_outputs(args.out, names, args.overwrite)
        sc = load_scenario(args.config, ignore=frozenset(SIM_NODE_PARAMETERS))
        if sc.primary_orbit is None or sc.primary_orbit.e <= 1.0:
            raise ScenarioError(f'{args.config}: needs an orbit.kind: flyby (a hyperbolic '
                                'orbit); this scenario has none')
        # imported once the input is accepted: a refusal does not wait for matplotlib
        from tumble_ros.analysis.encounter import (draw_encounter, encounter_ensemble,
                                                   format_encounter)
        from tumble_ros.ensembles import run_ensemble
        with interrupts():
            with engine(args) as client:
                result = encounter_ensemble(sc, args.bodies, seed=args.seed,
                                            inertia_spread=tuple(args.inertia_spread),
                                            n_inertia=args.inertia_draws, progress=progress,
                                            run=partial(run_ensemble, client=client))
            report = (f'scenario: {Path(args.config).name}\n'
                      f'draws: {args.inertia_draws} inertia (+- {args.inertia_spread[0]:g} in '
                      f'I_a/I_c, +- {args.inertia_spread[1]:g} in I_b/I_c), phase and turn '
                      f'about L uniform, seed {args.seed}\n' + format_encounter(result)
                      + f'\nwall time: {time.perf_counter() - start:.1f} s')
            print(report)
            if args.out:
                files = [('encounter.png', draw_encounter(
                             result, title=f'{Path(args.config).stem}: {args.bodies} tumblers '
                                           'through the flyby')),
                         ('summary.txt', (report + '\n').encode())]
                if not args.no_arrays:
                    files.append(('encounter.npz', _arrays(result)))
                write_files(files, args.out, args.overwrite)
                print(f'wrote {args.out}/' + ', '.join(names))
    except (TumbleRosError, ValueError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 2
    except BrokenPipeError:
        raise                   # stdout's reader has gone: the caller ends quietly (141)
    except OSError as err:
        print(f'error: cannot write to {args.out}: {err.strerror or err}', file=sys.stderr)
        return 2
    except Interrupted as stop:
        print(f'encounter: stopped by {stop.name}; nothing written', file=sys.stderr)
        return stop.exit_code
    return 0 if bool(np.all(result.success)) else 1


def _arrays(result) -> bytes:
    """Return every body's inputs and states as the bytes of a numpy .npz."""
    buffer = io.BytesIO()
    np.savez_compressed(
        buffer, inertia=result.inertia, phase=result.phase,
        turn=result.turn, mode_before=result.mode_before, mode_after=result.mode_after,
        precession_before=result.precession_before,
        precession_after=result.precession_after, rotation_before=result.rotation_before,
        rotation_after=result.rotation_after, spin_rate_before=result.spin_rate_before,
        spin_rate_after=result.spin_rate_after, pole_before=result.pole_before,
        pole_after=result.pole_after, success=result.success)
    return buffer.getvalue()


if __name__ == '__main__':  # pragma: no cover
    from tumble_ros.exits import call_closing_quietly, end_if_stopped  # a closed pipe: 141

    sys.exit(end_if_stopped(call_closing_quietly(main, sys.argv[1:])))   # stopped: no teardown

r"""
The encounter command line: a tumbler's spin state through a flyby, over what is uncertain.

    python -m tumble_ros.cli.encounter tumble_ros/config/apophis_2029.yaml --bodies 1000 \
        --inertia-draws 10 --inertia-spread 0.03 0.015 --seed 1 --out docs/figures/apophis
    ... --workers 2                 # the bodies as chunks on a local Dask cluster
    ... --scheduler tcp://HEAD:8786 # or on a cluster (README: Running on a cluster)

(``ros2 run tumble_ros encounter ...`` on a ROS 2 install.) Writes ``encounter.png`` (the
distributions after the encounter), ``summary.txt`` (the report printed on stdout) and
``encounter.npz`` (every body's inputs and states) to ``--out``. The work is
:func:`tumble_ros.analysis.encounter.encounter_ensemble`; this module only parses and reports.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import sys
import time
from typing import Sequence

import numpy as np

from tumble_ros.analysis.encounter import (encounter_ensemble, encounter_figure,
                                           format_encounter)
from tumble_ros.cli.engine import add_engine_arguments, engine
from tumble_ros.core import load_scenario, ScenarioError
from tumble_ros.ensembles import EnsembleRunError
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

    try:
        sc = load_scenario(args.config, ignore=frozenset(SIM_NODE_PARAMETERS))
        if sc.orbit is None or sc.orbit.e <= 1.0:
            raise ScenarioError(f'{args.config}: needs an orbit.kind: flyby (a hyperbolic '
                                'orbit); this scenario has none')
        if any(d < 0 for d in args.inertia_spread):
            raise ScenarioError(f'--inertia-spread: must be >= 0, got {args.inertia_spread}')
        with engine(args) as client:
            result = encounter_ensemble(sc, args.bodies, seed=args.seed,
                                        inertia_spread=tuple(args.inertia_spread),
                                        n_inertia=args.inertia_draws, progress=progress,
                                        client=client)
    except (ScenarioError, EnsembleRunError, ValueError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 2
    report = (f'scenario: {Path(args.config).name}\n'
              f'draws: {args.inertia_draws} inertia (+- {args.inertia_spread[0]:g} in I_a/I_c, '
              f'+- {args.inertia_spread[1]:g} in I_b/I_c), phase and turn about L uniform, '
              f'seed {args.seed}\n' + format_encounter(result)
              + f'\nwall time: {time.perf_counter() - start:.1f} s')
    print(report)
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        encounter_figure(result, args.out / 'encounter.png',
                         title=f'{Path(args.config).stem}: {args.bodies} tumblers through the '
                               'flyby')
        (args.out / 'summary.txt').write_text(report + '\n')
        if not args.no_arrays:
            _save_arrays(args.out / 'encounter.npz', result)
        print(f'wrote {args.out}/encounter.png, summary.txt'
              + ('' if args.no_arrays else ', encounter.npz'))
    return 0 if bool(np.all(result.success)) else 1


def _save_arrays(path: Path, result) -> None:
    """Write every body's inputs and states (numpy .npz)."""
    np.savez_compressed(
        path, inertia=result.inertia, phase=result.phase,
        turn=result.turn, mode_before=result.mode_before, mode_after=result.mode_after,
        precession_before=result.precession_before,
        precession_after=result.precession_after, rotation_before=result.rotation_before,
        rotation_after=result.rotation_after, spin_rate_before=result.spin_rate_before,
        spin_rate_after=result.spin_rate_after, pole_before=result.pole_before,
        pole_after=result.pole_after, success=result.success)


if __name__ == '__main__':  # pragma: no cover
    sys.exit(main())

r"""
The ensemble command line: N copies of a scenario at once, progress on stderr, a summary.

    python -m tumble_ros.cli.ensemble tumble_ros/config/fig9.yaml --bodies 10000 \
        --duration 20 --output-interval 1 --impact-rate 0.5 --impact-torque 1e6 \
        --method splitting6 --step 0.01 --out ensemble.npz
    python -m tumble_ros.cli.ensemble ... --bodies 1000000 --workers 2 --out ens.zarr
    python -m tumble_ros.cli.ensemble ... --scheduler tcp://head:8786 --out ens.zarr
    python -m tumble_ros.cli.ensemble ... --no-euler-angles --out ens.zarr   # no euler array

(``ros2 run tumble_ros ensemble ...`` on a ROS 2 install.) The work is
:func:`tumble_ros.ensembles.run_ensemble` (``--out X.npz``: in memory) or
:func:`tumble_ros.ensembles.run_ensemble_to_store` (``--out X.zarr``: a labelled store written
chunk by chunk, resumed when the same command runs again), in this process (threads), on an
embedded Dask ``LocalCluster`` (``--workers N``) or on a running Dask cluster
(``--scheduler ADDRESS``); this module only parses, reports and saves. Random impacts and
the ω0 spread are drawn body by body from ``--seed`` (the same bodies whatever the engine and
chunking).
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import sys
from typing import Any, Sequence

import numpy as np

from tumble_ros.cli.engine import add_engine_arguments, engine
from tumble_ros.cli.progress import ProgressBar
from tumble_ros.core import (GaussianSpread, IntegratorSettings, load_scenario, RandomImpacts,
                             Scenario, ScenarioError)
from tumble_ros.core.compiling.jit import compile_notices
from tumble_ros.core.units import from_years, parse_time, TIME_INPUT_HELP, TIME_UNITS
from tumble_ros.ensembles import (EnsembleStoreError, open_ensemble, run_ensemble,
                                  run_ensemble_to_store)
from tumble_ros.errors import TumbleRosError
from tumble_ros.exits import Interrupted, interrupts
from tumble_ros.topics import SIM_NODE_PARAMETERS

__all__ = ['main']


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog='python -m tumble_ros.cli.ensemble',
        description='Integrate N copies of a scenario (random impact sequences and/or spread '
                    'initial spin) at once; progress on stderr, a summary on stdout, arrays to '
                    '--out (.npz).')
    p.add_argument('config', nargs='?',
                   help='scenario file (ROS 2 params YAML); default: the default scenario')
    p.add_argument('--bodies', '-n', type=int, default=100,
                   help='number of bodies N (default 100)')
    p.add_argument('--duration', metavar='T',
                   help=f"override the scenario's duration: {TIME_INPUT_HELP}")
    p.add_argument('--output-interval', metavar='T',
                   help=f'override the output interval: {TIME_INPUT_HELP}')
    p.add_argument('--method', help='override integrator.method (e.g. splitting6, dop853, rk4)')
    p.add_argument('--step', metavar='T', help=f'override integrator.step: {TIME_INPUT_HELP}')
    p.add_argument('--rtol', type=float, help='override integrator.rtol')
    p.add_argument('--atol', type=float, help='override integrator.atol')
    p.add_argument('--impact-rate', type=float, default=0.0,
                   help="random impacts per body per unit of the scenario's time_unit "
                        '(per year by default; default 0)')
    p.add_argument('--impact-torque', type=float, default=None,
                   help="impact torque magnitude [I rad/unit^2], unit the scenario's time_unit "
                        '(default 1e6 I rad/yr^2)')
    p.add_argument('--impact-duration', metavar='T', default=None,
                   help=f'pulse length: {TIME_INPUT_HELP} (default 3e-7 yr, 9.5 s)')
    p.add_argument('--impact-frame', choices=('body', 'orbital'), default='body')
    p.add_argument('--omega-spread', type=float, default=0.0,
                   help="standard deviation [rad/unit, unit the scenario's time_unit] of a "
                        'Gaussian perturbation of omega0 per body')
    p.add_argument('--seed', type=int, default=0, help='random seed (default 0)')
    p.add_argument('--reference', action='store_true',
                   help='run the reference path (one simulate() per body)')
    p.add_argument('--no-euler-angles', action='store_true',
                   help='leave out the Euler angles: the compiled loops skip their tracking '
                        '(~30 %% of a splitting body-step) and --out gets no euler array; '
                        'every other output keeps its bits')
    p.add_argument('--out',
                   help='X.npz: write t, omega, euler (unless --no-euler-angles), '
                        'quaternion, jacobi, success, n_steps (all in memory); X.zarr: a '
                        'labelled xarray/Zarr store written chunk by chunk (memory does not '
                        'grow with N), resumed when run again')
    p.add_argument('--overwrite', action='store_true',
                   help='replace an existing .zarr store instead of resuming it')
    add_engine_arguments(p)
    p.add_argument('--chunk-size', type=int,
                   help='bodies per task and per store chunk (default: up to 10,000, '
                        'smaller for long outputs and to give every worker several)')
    p.add_argument('--quiet', '-q', action='store_true', help='no progress display')
    return p


def _final_spin_lines(w_end: np.ndarray, jac_start: np.ndarray, jac_end: np.ndarray,
                      unit: str) -> list:
    """Return the summary lines of the succeeded bodies' last samples (w [rad/yr] in unit)."""
    w_end = w_end * TIME_UNITS[unit]
    w_perp = np.hypot(w_end[:, 0], w_end[:, 1])
    return [f'final |w_perp| [rad/{unit}]: mean {w_perp.mean():.6g}, std {w_perp.std():.3g}; '
            f'final wz [rad/{unit}]: mean {w_end[:, 2].mean():.6g}, '
            f'std {w_end[:, 2].std():.3g}',
            f'Jacobi integral: start {np.mean(jac_start):.10g}, '
            f'end mean {np.mean(jac_end):.10g}, std {np.std(jac_end):.3g}']


def _to_store(args, sc, inputs, client) -> int:
    summary = run_ensemble_to_store(
        sc, args.out, n_bodies=args.bodies, chunk_size=args.chunk_size, client=client,
        fast=False if args.reference else None, overwrite=args.overwrite,
        euler_angles=not args.no_euler_angles,
        progress=None if args.quiet else ProgressBar(sc.duration, args.bodies, by='bodies',
                                                     unit=sc.time_unit),
        **inputs)
    print('\n'.join(summary.lines()))
    if summary.succeeded:
        ds = open_ensemble(args.out)
        try:
            good = (ds.status == 1).values
            w_end = ds.omega.isel(time=-1).values[good]
            jac = ds.jacobi.isel(time=[0, -1]).values[good]
        except RuntimeError as err:       # numcodecs: a chunk that does not decompress
            raise EnsembleStoreError(f'{args.out}: damaged ensemble store: cannot read its '
                                     f"data ({' '.join(str(err).split())})") from None
        print('\n'.join(_final_spin_lines(w_end, jac[:, 0], jac[:, 1], sc.time_unit)))
    return 0 if summary.succeeded == summary.n_bodies else 1


def _save_npz(path: Path, **arrays) -> None:
    """Write ``arrays`` to ``path`` (.npz) whole or not at all: a temporary file, then a rename."""
    temporary = path.with_name(f'.{path.name}.{os.getpid()}.tmp')
    try:
        with open(temporary, 'xb') as stream:
            np.savez_compressed(stream, **arrays)
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run the command on ``argv``; return the exit status.

    0 every body succeeded, 1 some failed, 2 refused input (one ``error:`` line: a params
    file, an option, a store that is foreign, damaged, of another format version or being
    written by another run, a scheduler that does not answer), 130 / 143 / 129 stopped by
    SIGINT / SIGTERM / SIGHUP (a store keeps its complete chunks; nothing else is written).
    """
    args = _parser().parse_args(argv)
    to_store = False
    try:
        sc = (load_scenario(args.config, ignore=frozenset(SIM_NODE_PARAMETERS)) if args.config
              else Scenario())
        unit = sc.time_unit
        given = (('duration', args.duration), ('output_interval', args.output_interval))
        changes: dict[str, Any] = {k: parse_time(v, unit, f'--{k.replace("_", "-")}')
                                   for k, v in given if v is not None}
        if 'duration' in changes and 'output_interval' not in changes:
            changes['output_interval'] = min(sc.output_interval, changes['duration'])
        step = None if args.step is None else parse_time(args.step, unit, '--step')
        integ = {k: v for k, v in (('method', args.method), ('step', step),
                                   ('rtol', args.rtol), ('atol', args.atol)) if v is not None}
        if integ:
            fields = {f: getattr(sc.integrator, f)
                      for f in ('method', 'rtol', 'atol', 'step', 'max_step')}
            changes['integrator'] = IntegratorSettings(**{**fields, **integ})
        if changes:
            sc = sc.replace(**changes)
        if args.bodies < 1:
            raise ScenarioError(f'--bodies: must be >= 1, got {args.bodies}')
        impacts = omega0 = None
        if args.impact_rate > 0:
            per_year = 1.0 / TIME_UNITS[unit]      # (a rate per unit, per year)
            torque = (1e6 if args.impact_torque is None
                      else args.impact_torque * per_year * per_year)
            pulse = (3e-7 if args.impact_duration is None
                     else parse_time(args.impact_duration, unit, '--impact-duration'))
            impacts = RandomImpacts(rate=args.impact_rate * per_year, torque=torque,
                                    pulse=pulse, frame=args.impact_frame, seed=args.seed)
        if args.omega_spread > 0:
            omega0 = GaussianSpread(sc.omega0, args.omega_spread / TIME_UNITS[unit],
                                    seed=args.seed)
        inputs = {'impacts': impacts, 'omega0': omega0}
        to_store = bool(args.out) and args.out.rstrip('/').endswith('.zarr')
        with interrupts(), compile_notices(not args.quiet), engine(args) as client:
            if to_store:
                return _to_store(args, sc, inputs, client)
            result = run_ensemble(
                sc, n_bodies=args.bodies, fast=False if args.reference else None,
                client=client, chunk_size=args.chunk_size,
                progress=None if args.quiet else ProgressBar(
                    sc.duration, args.bodies, by='time' if client is None else 'bodies',
                    unit=sc.time_unit),
                impacts=impacts, omega0=omega0, euler_angles=not args.no_euler_angles)
    except (TumbleRosError, ValueError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 2
    except Interrupted as stop:
        kept = (f'; the chunks written to {args.out} are kept: run the same command to resume'
                if to_store else '; nothing written')
        print(f'\nensemble: stopped by {stop.name}{kept}', file=sys.stderr)
        return stop.exit_code
    n_impacts = (len(sc.impacts) * args.bodies if impacts is None else
                 f'random, {args.impact_rate:g}/{sc.time_unit} per body, seed {args.seed}')
    ok = int(result.success.sum())
    w_end = result.omega[:, -1]
    print(f'bodies: {result.n_bodies} ({ok} succeeded), impacts: {n_impacts}, '
          f'method: {sc.integrator.method}, '
          f"{'compiled' if result.compiled else 'reference'} path")
    print(f'time: {from_years(sc.duration, sc.time_unit):g} {sc.time_unit}, '
          f'{result.t.size} samples per body, '
          f'{int(result.n_steps.sum())} body-steps in {result.wall_time:.3f} s = '
          f'{result.body_steps_per_second:.3g} body-steps/s')
    if ok:
        good = result.success
        lines = _final_spin_lines(w_end[good], result.jacobi[good, 0], result.jacobi[good, -1],
                                  sc.time_unit)
        print('\n'.join(lines))
    for b, msg in enumerate(result.messages):
        if msg:
            print(f'body {b} failed: {msg}')
    if args.out:
        euler = {'euler': result.euler} if result.euler_angles else {}
        try:
            _save_npz(Path(args.out), t=result.t, omega=result.omega, **euler,
                      quaternion=result.quaternion, jacobi=result.jacobi,
                      success=result.success, n_steps=result.n_steps)
        except OSError as err:
            print(f'error: cannot write {args.out}: {err.strerror or err}', file=sys.stderr)
            return 2
        print(f'wrote {args.out}')
    return 0 if ok == result.n_bodies else 1


if __name__ == '__main__':  # pragma: no cover
    from tumble_ros.exits import call_closing_quietly, end_if_stopped  # a closed pipe: 141

    sys.exit(end_if_stopped(call_closing_quietly(main, sys.argv[1:])))   # stopped: no teardown

r"""
The ensemble command line: N copies of a scenario at once, progress on stderr, a summary.

    python -m tumble_ros.cli.ensemble tumble_ros/config/fig9.yaml --bodies 10000 \
        --duration 20 --output-interval 1 --impact-rate 0.5 --impact-torque 1e6 \
        --method splitting6 --step 0.01 --out ensemble.npz

(``ros2 run tumble_ros ensemble ...`` on a ROS 2 install.) The work is
:func:`tumble_ros.core.simulate_ensemble`; this module only parses, reports and saves.
"""
from __future__ import annotations

import argparse
import sys
from typing import Sequence

import numpy as np

from tumble_ros.cli.progress import ProgressBar
from tumble_ros.core import (IntegratorSettings, load_scenario, random_impacts, Scenario,
                             ScenarioError, simulate_ensemble)

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
    p.add_argument('--duration', type=float, help="override the scenario's duration [yr]")
    p.add_argument('--output-interval', type=float, help='override the output interval [yr]')
    p.add_argument('--method', help='override integrator.method (e.g. splitting6, dop853, rk4)')
    p.add_argument('--step', type=float, help='override integrator.step [yr]')
    p.add_argument('--rtol', type=float, help='override integrator.rtol')
    p.add_argument('--atol', type=float, help='override integrator.atol')
    p.add_argument('--impact-rate', type=float, default=0.0,
                   help='random impacts per year per body (default 0)')
    p.add_argument('--impact-torque', type=float, default=1e6,
                   help='impact torque magnitude [I rad/yr^2]')
    p.add_argument('--impact-duration', type=float, default=3e-7,
                   help='pulse length [yr] (default 3e-7)')
    p.add_argument('--impact-frame', choices=('body', 'orbital'), default='body')
    p.add_argument('--omega-spread', type=float, default=0.0,
                   help='standard deviation [rad/yr] of a Gaussian perturbation of omega0 '
                        'per body')
    p.add_argument('--seed', type=int, default=0, help='random seed (default 0)')
    p.add_argument('--reference', action='store_true',
                   help='run the reference path (one simulate() per body)')
    p.add_argument('--out',
                   help='write t, omega, euler, quaternion, jacobi, success, n_steps to this .npz')
    p.add_argument('--quiet', '-q', action='store_true', help='no progress display')
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        sc = load_scenario(args.config) if args.config else Scenario()
        changes = {k: v for k, v in (('duration', args.duration),
                                     ('output_interval', args.output_interval))
                   if v is not None}
        if 'duration' in changes and 'output_interval' not in changes:
            changes['output_interval'] = min(sc.output_interval, changes['duration'])
        integ = {k: v for k, v in (('method', args.method), ('step', args.step),
                                   ('rtol', args.rtol), ('atol', args.atol)) if v is not None}
        if integ:
            fields = {f: getattr(sc.integrator, f)
                      for f in ('method', 'rtol', 'atol', 'step', 'max_step')}
            changes['integrator'] = IntegratorSettings(**{**fields, **integ})
        if changes:
            sc = sc.replace(**changes)
        if args.bodies < 1:
            raise ScenarioError(f'--bodies: must be >= 1, got {args.bodies}')
        rng = np.random.default_rng(args.seed)
        impacts = None
        if args.impact_rate > 0:
            impacts = random_impacts(args.bodies, sc.duration, rate=args.impact_rate,
                                     torque=args.impact_torque, pulse=args.impact_duration,
                                     frame=args.impact_frame, seed=rng.integers(2**63))
        omega0 = None
        if args.omega_spread > 0:
            omega0 = np.array(sc.omega0) + args.omega_spread * rng.normal(size=(args.bodies, 3))
        result = simulate_ensemble(sc, impacts=impacts, omega0=omega0, n_bodies=args.bodies,
                                   fast=False if args.reference else None,
                                   progress=None if args.quiet else ProgressBar(sc.duration,
                                                                                args.bodies))
    except (ScenarioError, ValueError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 2
    n_impacts = (sum(len(b) for b in impacts) if impacts is not None
                 else len(sc.impacts) * args.bodies)
    ok = int(result.success.sum())
    w_end = result.omega[:, -1]
    print(f'bodies: {result.n_bodies} ({ok} succeeded), impacts: {n_impacts}, '
          f'method: {sc.integrator.method}, '
          f"{'compiled' if result.compiled else 'reference'} path")
    print(f'time: {sc.duration:g} yr, {result.t.size} samples per body, '
          f'{int(result.n_steps.sum())} body-steps in {result.wall_time:.3f} s = '
          f'{result.body_steps_per_second:.3g} body-steps/s')
    if ok:
        good = result.success
        w_perp = np.hypot(w_end[good, 0], w_end[good, 1])
        print(f'final |w_perp| [rad/yr]: mean {w_perp.mean():.6g}, std {w_perp.std():.3g}; '
              f'final wz: mean {w_end[good, 2].mean():.6g}, std {w_end[good, 2].std():.3g}')
        jac = result.jacobi[good]
        print(f'Jacobi integral: start {np.mean(jac[:, 0]):.10g}, '
              f'end mean {np.mean(jac[:, -1]):.10g}, '
              f'std {np.std(jac[:, -1]):.3g}')
    for b, msg in enumerate(result.messages):
        if msg:
            print(f'body {b} failed: {msg}')
    if args.out:
        np.savez_compressed(args.out, t=result.t, omega=result.omega, euler=result.euler,
                            quaternion=result.quaternion, jacobi=result.jacobi,
                            success=result.success,
                            n_steps=result.n_steps)
        print(f'wrote {args.out}')
    return 0 if ok == result.n_bodies else 1


if __name__ == '__main__':  # pragma: no cover
    sys.exit(main())

r"""
The invert command line: a tumbler's spin state and shape from its photometry.

    python -m tumble_ros invert obs.txt [more files] --out fit/          # the global search
    ... --periods 27.38,263 --modes SAM          # given period pairs [h] instead of the search
    ... --json                                   # the report as JSON on stdout

Reads the files with the inversion's readers (``tumble_ros.inversion.readers``: DAMIT, ALCDEF,
CSV, recordings; ``--format``, ``--ephemeris``), runs :func:`tumble_ros.inversion.search.invert`
(progress on stderr after 2 s) and prints the report; with ``--out`` it writes ``report.txt``,
``report.json``, ``fit.yaml`` (the best solution as a scenario: ``python -m tumble_ros
fit.yaml`` runs it), ``fit_2.yaml`` ... (the other accepted solutions) and, unless
``--no-figures``, ``nights.png``, ``period_plane.png``, ``poles.png``. The outputs are checked
before the search (a file there is refused unless ``--overwrite``, a symbolic link always).
Exit status: 0 done, 1 done with warnings about the answer (not unique, chi2/nu far from 1,
an alias), 2 refused input (one ``error:`` line), 128 + n stopped by a signal (nothing
written). docs/inversion.md.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import sys
from typing import Any, Sequence

from tumble_ros.analysis.figure_files import check_outputs, write_files
from tumble_ros.errors import TumbleRosError
from tumble_ros.exits import Interrupted, interrupts

__all__ = ['main', 'load_campaign']


def _pair(text: str) -> tuple[float, float]:
    """Parse ``P_phi,P_psi`` [h]."""
    try:
        a, b = (float(x) for x in text.split(','))
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected P_phi,P_psi in hours, got {text!r}') \
            from None
    return a, b


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog='python -m tumble_ros invert',
        description='Fit a torque-free tumbler (spin state, ellipsoid shape, scattering) to '
                    'photometry: the period search, a grid of poles and phases, local '
                    'least-squares fits; every solution within the chi2 threshold reported.')
    p.add_argument('files', nargs='+', help='photometry files (DAMIT, ALCDEF, CSV, MCAP)')
    p.add_argument('--format', help="the files' format (default: recognised per file)")
    p.add_argument('--ephemeris', nargs=2, metavar=('SUN_TABLE', 'OBSERVER_TABLE'),
                   help='Horizons vector tables for files without geometry')
    p.add_argument('--periods', type=_pair, action='append', default=[],
                   metavar='P_PHI,P_PSI', help='a (P_phi, P_psi) pair [h] to try (repeatable); '
                   "default: the two-period search's candidates")
    p.add_argument('--modes', default='SAM,LAM', help='modes tried (default SAM,LAM)')
    p.add_argument('--poles', type=int, default=12, help='L directions of the grid (12)')
    p.add_argument('--phases', type=int, default=3, help='values of phi0 and of psi0 (3)')
    p.add_argument('--starts', type=int, default=2, help='grid points fitted a candidate (2)')
    p.add_argument('--candidates', type=int, default=6, help='most period pairs (6)')
    p.add_argument('--epoch', type=float, help='t = 0 [JD TDB] (default: the first point)')
    p.add_argument('--posterior', type=int, metavar='STEPS',
                   help="sample the best fit's posterior with emcee, STEPS per walker (a "
                   'quarter burnt): posterior.npz in --out')
    p.add_argument('--flyby', metavar='SCENARIO',
                   help='run the accepted solutions (and --flyby-samples posterior samples) '
                   'through this flyby scenario (e.g. apophis_2029): flyby.txt in --out')
    p.add_argument('--flyby-samples', type=int, default=20, metavar='N',
                   help='posterior samples run through --flyby (20; one run each)')
    p.add_argument('--flyby-start', type=float, metavar='JD',
                   help="t = 0 of --flyby [JD TDB] (default: apophis_2029's, 2029-04-10 21:46)")
    p.add_argument('--json', action='store_true', help='print the report as JSON')
    p.add_argument('--out', type=Path, help='folder for the report, fit.yaml and figures')
    p.add_argument('--no-figures', action='store_true', help='no PNG figures in --out')
    p.add_argument('--overwrite', action='store_true',
                   help='replace files of --out that exist (symbolic links are still refused)')
    p.add_argument('--quiet', '-q', action='store_true', help='no progress lines')
    return p


def load_campaign(files: Sequence[str], file_format: str | None,
                  ephemeris: Sequence[str] | None) -> Any:
    """Return the Campaign of ``files`` read by the inversion's readers."""
    from tumble_ros.inversion import readers
    tables = None if ephemeris is None else (ephemeris[0], ephemeris[1])
    return readers.read_campaign(list(files), file_format, ephemeris=tables)


def _outputs(args: argparse.Namespace, accepted: int) -> list[str]:
    names = ['report.txt', 'report.json', 'fit.yaml']
    names += [f'fit_{k}.yaml' for k in range(2, accepted + 1)]
    names += (['posterior.npz'] if args.posterior else []) + (['flyby.txt'] if args.flyby else [])
    return names + ([] if args.no_figures else ['nights.png', 'period_plane.png', 'poles.png'])


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.overwrite and args.out is None:
            raise TumbleRosError('--overwrite: needs --out DIR')
        if args.out is not None:
            check_outputs(args.out, _outputs(args, 1), args.overwrite)
        from tumble_ros.inversion.search import invert, SearchSettings, stderr_progress
        settings = SearchSettings(periods=tuple(args.periods),
                                  modes=tuple(m.strip().upper() for m in args.modes.split(',')),
                                  max_candidates=args.candidates, poles=args.poles,
                                  phases=args.phases, starts=args.starts)
        flyby = _flyby_scenario(args.flyby) if args.flyby else None
        campaign = load_campaign(args.files, args.format, args.ephemeris)
        with interrupts():
            result = invert(campaign, settings, epoch_jd=args.epoch,
                            progress=None if args.quiet else stderr_progress())
            _print_and_write(args, campaign, result, _extras(args, campaign, result, flyby))
    except (TumbleRosError, ValueError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 2
    except BrokenPipeError:
        raise
    except OSError as err:
        print(f'error: cannot write to {args.out}: {err.strerror or err}', file=sys.stderr)
        return 2
    except Interrupted as stop:
        print(f'invert: stopped by {stop.name}; nothing written', file=sys.stderr)
        return stop.exit_code
    return 1 if result.warnings else 0


def _flyby_scenario(name: str) -> Any:
    """Return the scenario of ``--flyby`` (a params file or a shipped scenario's name)."""
    from tumble_ros.core import load_scenario
    from tumble_ros.core.model.shipped import shipped_scenarios
    from tumble_ros.topics import SIM_NODE_PARAMETERS
    path = shipped_scenarios().get(name, name)
    return load_scenario(path, ignore=frozenset(SIM_NODE_PARAMETERS))


def _extras(args: argparse.Namespace, campaign: Any, result: Any,
            flyby: Any) -> list[tuple[str, bytes]]:
    """Return the files of ``--posterior`` and ``--flyby`` (flyby.txt also printed)."""
    import io

    import numpy as np
    files: list[tuple[str, bytes]] = []
    models = [fit.parameters for fit in result.accepted]
    if args.posterior:
        from tumble_ros.inversion.posterior import sample_posterior
        posterior = sample_posterior(campaign, result.best, steps=args.posterior,
                                     burn=args.posterior // 4)
        buffer = io.BytesIO()
        np.savez(buffer, names=np.array(posterior.names), samples=posterior.samples,
                 log_probability=posterior.log_probability)
        files.append(('posterior.npz', buffer.getvalue()))
        count = max(0, args.flyby_samples) if flyby is not None else 0
        every = max(1, len(posterior.samples) // max(count, 1))
        models += [posterior.parameters(result.best, k)
                   for k in range(0, len(posterior.samples), every)][:count]
        print(f'posterior: {len(posterior.samples)} samples, acceptance '
              f'{posterior.acceptance:.2f}', file=sys.stderr)
    if flyby is not None:
        from tumble_ros.inversion.flyby import APOPHIS_2029_START_JD, flyby_ensemble
        start = args.flyby_start if args.flyby_start is not None else APOPHIS_2029_START_JD
        outcome = flyby_ensemble(flyby, models, result.best.epoch_jd, start)
        text = _flyby_text(outcome, len(result.accepted))
        files.append(('flyby.txt', (text + '\n').encode()))
    return files


def _flyby_text(outcome: Any, accepted: int) -> str:
    """Return the periods and L before and after the flyby, one line a model."""
    import math

    from tumble_ros.core.units import HOURS_PER_YEAR as H
    lines = ['flyby: model, P_phi, P_psi [h] before -> after, L (lambda, beta) [deg] after']
    for k, (before, after) in enumerate(zip(outcome.before, outcome.after)):
        label = 'nominal' if k == 0 else (f'accepted {k + 1}' if k < accepted
                                          else f'posterior {k - accepted + 1}')
        lines.append(f'  {label:<13} {before.precession_period * H:.5f} '
                     f'{before.rotation_period * H:.4f} -> {after.precession_period * H:.5f} '
                     f'{after.rotation_period * H:.4f}  '
                     f'({math.degrees(after.pole_longitude or 0.0) % 360:.2f}, '
                     f'{math.degrees(after.pole_latitude or 0.0):.2f})')
    return '\n'.join(lines)


def _print_and_write(args: argparse.Namespace, campaign: Any, result: Any,
                     extras: list[tuple[str, bytes]]) -> None:
    """Print the report; write the files of ``--out``."""
    from tumble_ros.inversion.report import format_result, result_json
    from tumble_ros.inversion.scenario_out import scenario_yaml
    text, document = format_result(result), result_json(result)
    print(document if args.json else text)
    for name, content in extras:
        if name == 'flyby.txt':
            print(content.decode().rstrip(), file=sys.stderr if args.json else sys.stdout)
    if args.out is None:
        return
    span_hours = campaign.span_days * 24.0
    files = [('report.txt', (text + '\n').encode()), ('report.json', document.encode()),
             ('fit.yaml', scenario_yaml(result.accepted[0], span_hours).encode())]
    files += [(f'fit_{k}.yaml', scenario_yaml(fit, span_hours, f'Accepted solution {k} of '
                                              f'{len(result.accepted)}').encode())
              for k, fit in enumerate(result.accepted[1:], start=2)]
    files += extras
    if not args.no_figures:
        from tumble_ros.inversion.figures import figure_files
        files += figure_files(campaign, result)
    write_files(files, args.out, args.overwrite)
    print(f'wrote {args.out}/' + ', '.join(name for name, _ in files), file=sys.stderr)

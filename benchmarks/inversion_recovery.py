"""The inversion's recovery table: injected truth, fit, 1 sigma and coverage over noise draws.

Usage (in the workspace environment; minutes to an hour, the machine's load decides)::

    scripts/env.sh python benchmarks/inversion_recovery.py [--draws N] [--cases lam,sam,...]

Cases: ``lam`` (a LAM, P_phi 9 h, P_psi 20 h, 25 nights), ``sam`` (a SAM, 6.2 h / 28 h, 30
nights), ``sam2`` (the SAM over two apparitions a year apart), ``apophis12`` (Pravec et al.
2014's state sampled like 2012-13: 800 points on 40 nights), ``apophis20`` (like 2020-21: 1,280
points on 67 nights), ``apophis2`` (both, 8 years apart, with the cycle-count aliases fitted).
Each campaign comes from tumble_ros/test/synthetic_campaigns.py (an integration and a
brightness independent of the fit's); each draw is new noise and new night offsets, the fit
(``inversion.fit.fit_local``) starts at the truth. Printed per quantity: the truth, the mean
fit, the median 1 sigma, the fractions of draws within 1/2/3 sigma and the mean z^2.
``make bench`` runs one draw of ``lam``, every case with ``--full``, nothing with ``--quick``.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path
import sys
import time

from common import section
import numpy as np

TESTS = Path(__file__).resolve().parent.parent / 'tumble_ros' / 'test'
CASES = ('lam', 'sam', 'sam2', 'apophis12', 'apophis20', 'apophis2')


def _modules():
    """Return the generator, the recovery helpers and the test module (the tests' folder)."""
    if str(TESTS) not in sys.path:
        sys.path.insert(0, str(TESTS))
    import inversion_recovery
    import synthetic_campaigns
    import test_inversion_recovery
    return synthetic_campaigns, inversion_recovery, test_inversion_recovery


def campaign_of(case: str):
    """Return the noiseless synthetic campaign of a case."""
    sc, _ir, t = _modules()
    if case == 'lam':
        return sc.make_campaign(t.LAM, [t.LAM_SEASON], seed=11)
    if case in ('sam', 'sam2'):
        return sc.make_campaign(t.SAM, t.SAM_SEASONS[:1 if case == 'sam' else 2], seed=12)
    if case == 'apophis12':
        return sc.make_campaign(sc.APOPHIS_PRAVEC_2014, [sc.APOPHIS_2012_13], seed=2029)
    if case == 'apophis20':
        return t.apophis(False)
    return t.apophis(True)


def run_case(case: str, draws: int, out=print) -> None:
    """Print the recovery table of one case (and the aliases of ``apophis2``)."""
    sc, ir, t = _modules()
    began = time.perf_counter()
    synthetic = campaign_of(case)
    made = time.perf_counter() - began
    truth = ir.truth_parameters(synthetic)
    fits = ir.recover(synthetic, draws, seed=5000)
    out(ir.table(f'{case}: {synthetic.jd.size} points on {len(synthetic.names)} nights, '
                 f'{synthetic.jd[-1] - synthetic.jd[0]:.0f} d', fits, truth))
    out(f'  (campaign made in {made:.0f} s, {draws} fits in '
        f'{time.perf_counter() - began - made:.0f} s)')
    if case == 'apophis2':
        from tumble_ros.inversion.fit import fit_local
        campaign = sc.draw(synthetic, np.random.default_rng(5000))
        best = fits[0]
        gap = (sc.APOPHIS_2020_21.start_jd - sc.APOPHIS_2012_13.end_jd) * 24.0
        threshold = math.sqrt(2.0 * best.dof) * best.chi2_reduced
        for pair in t.cycle_aliases(best, gap):
            alias = fit_local(campaign, truth.with_values(
                ('precession_period', 'rotation_period'), pair), epoch_jd=synthetic.truth.epoch_jd)
            out(f'  alias start ({pair[0]:.5f} h, {pair[1]:.3f} h) -> '
                f"({alias.value('precession_period')[0]:.5f} +- "
                f"{alias.value('precession_period')[1]:.5f} h, "
                f"{alias.value('rotation_period')[0]:.3f} +- "
                f"{alias.value('rotation_period')[1]:.3f} h): chi2 - best "
                f'{alias.chi2 - best.chi2:.1f} (accepted within {threshold:.1f})')


@section('Inversion: injection and recovery (benchmarks/inversion_recovery.py)', order=60)
def recovery_section(ctx):
    """``make bench``: one draw of the LAM; every case, 16 draws, with --full; none if --quick."""
    if ctx.quick:
        ctx.print('  not run with --quick (a fit takes tens of seconds): '
                  'scripts/env.sh python benchmarks/inversion_recovery.py')
    elif ctx.full:
        for case in CASES:
            run_case(case, 16, ctx.print)
    else:
        run_case('lam', 1, ctx.print)
        ctx.print('  (one draw: the coverage table is benchmarks/inversion_recovery.py)')


def main(argv=None) -> int:
    """Print the recovery table of the cases asked (module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--draws', type=int, default=32, help='noise draws per case (default 32)')
    p.add_argument('--cases', default=','.join(CASES),
                   help=f"comma-separated, of {', '.join(CASES)}")
    args = p.parse_args(argv)
    cases = [c for c in args.cases.split(',') if c]
    unknown = [c for c in cases if c not in CASES]
    if unknown or args.draws < 1:
        p.error(f'--cases: unknown {unknown}' if unknown else '--draws: at least 1')
    for case in cases:
        run_case(case, args.draws if not case.startswith('apophis') else
                 max(1, args.draws // 4))
        sys.stdout.flush()
    return 0


if __name__ == '__main__':
    sys.exit(main())

"""The tumbler inversion (issue 49): the local fit's and the global search's cost, and its growth.

Targets (issue 49): the local fit of a 30-night, ~2,000-point campaign from a given start
<= 30 s on this 2-core machine; the whole global search <= 10 min. The campaigns are made by
the inversion's own forward model (an Apophis-like SAM, 0.01 mag noise), nights of 0.3 d every
2 d; the start 0.1 % (P_phi), 1 % (P_psi) and ~5 deg off.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from common import section


def _campaign(nights: int, per_night: int, seed: int = 1):
    from tumble_ros.inversion.campaign import Campaign
    from tumble_ros.inversion.model import ForwardModel
    jd0 = 2460000.5
    t = np.concatenate([jd0 + 2.0 * k + np.linspace(0.0, 0.3, per_night) for k in range(nights)])
    angle = 0.01 * (t - jd0)
    sun = 1.1 * np.stack([np.cos(angle), np.sin(angle), np.full(t.size, 0.05)], 1)
    observer = 0.2 * np.stack([np.cos(angle + 0.4), np.sin(angle + 0.4),
                               np.full(t.size, 0.1)], 1)
    block = np.repeat(np.arange(nights), per_night)
    names = tuple(f'night {k}' for k in range(nights))
    sigma = np.full(t.size, 0.01)
    points = Campaign(t, np.zeros(t.size), sigma, sun, observer, block, names, (True,) * nights)
    clean = ForwardModel(points).magnitudes(_truth())
    noisy = clean + np.random.default_rng(seed).normal(0.0, 0.01, t.size)
    return Campaign(t, noisy, sigma, sun, observer, block, names, (True,) * nights)


def _truth():
    from tumble_ros.inversion.model import TumblerParameters
    return TumblerParameters.of('SAM', 27.38, 263.0, (0.61, 0.965),
                                (math.radians(250.0), math.radians(-55.0)), (0.5, 1.0),
                                axis_ratios=(0.8, 0.55))


def _start():
    from tumble_ros.inversion.model import TumblerParameters
    return TumblerParameters.of('SAM', 27.38 * 1.001, 263.0 * 1.01, (0.6, 0.95),
                                (math.radians(245.0), math.radians(-50.0)), (0.55, 1.05),
                                axis_ratios=(0.75, 0.6))


@section("Tumbler inversion: local fit and global search (inversion/, issue 49)", order=46)
def inversion_section(ctx):
    from tumble_ros.inversion.fit import fit_local
    from tumble_ros.inversion.search import invert, SearchSettings
    rows, result = [], {}
    sizes = ((5, 20), (10, 40)) if ctx.quick else ((10, 67), (20, 67), (30, 67))
    _campaign(2, 5)                 # (the compiled loops loaded before the clock starts)
    for nights, per_night in sizes:
        campaign = _campaign(nights, per_night)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        fit = fit_local(campaign, _start())
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        rows.append((f'local fit, {nights} nights', len(campaign), fit.nfev,
                     f'{wall / fit.nfev * 1e3:.0f}', f'{cpu:.1f}', f'{wall:.1f}',
                     f'{fit.chi2_reduced:.3f}'))
        result[f'fit_{nights}'] = {'points': len(campaign), 'evaluations': fit.nfev,
                                   'cpu_s': cpu, 'wall_s': wall, 'chi2_reduced': fit.chi2_reduced}
    big = result[f'fit_{sizes[-1][0]}']
    campaign = _campaign(*sizes[-1])
    for pairs in (((27.38, 263.0),), ((27.38, 263.0), (27.38 * 1.05, 263.0))):
        settings = SearchSettings(periods=pairs, modes=('SAM',),
                                  poles=6 if ctx.quick else 12, phases=2 if ctx.quick else 3,
                                  starts=1 if ctx.quick else 2)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        found = invert(campaign, settings)
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        evaluations = sum(s.nfev for s in found.solutions)
        rows.append((f'search, {len(pairs)} candidate(s)', len(campaign), evaluations, '',
                     f'{cpu:.1f}', f'{wall:.1f}', f'{found.best.chi2_reduced:.3f}'))
        result[f'search_{len(pairs)}'] = {'points': len(campaign), 'cpu_s': cpu, 'wall_s': wall,
                                          'accepted': len(found.accepted)}
    ctx.table(['case', 'points', 'model evaluations', 'ms / evaluation', 'CPU [s]', 'wall [s]',
               'chi2/nu'], rows)
    per_candidate = result['search_2']['cpu_s'] - result['search_1']['cpu_s']
    ctx.note(f"load average {os.getloadavg()[0]:.2f} (1 min) at the end: on a shared machine the "
             f"wall time is mostly other processes', so the verdicts take the CPU time (one "
             f"thread: the wall time of an idle machine). The local fit of the largest "
             f"campaign: {big['cpu_s']:.1f} s CPU ({ctx.verdict(big['cpu_s'] <= 30.0)} <= 30 s); "
             f"each candidate of the search adds ~{per_candidate:.0f} s CPU (the grid: poles x "
             f"phases^2 x 2 evaluations, then the starts' fits): 6 candidates x 2 modes at the "
             f"defaults ~{12 * per_candidate / 60:.1f} min "
             f"({ctx.verdict(12 * per_candidate <= 600.0)} <= 10 min)")
    ctx.note('an evaluation (propagation + 1,280-facet brightness) grows linearly with the '
             'points; a fit takes ~(free parameters + 1) evaluations an iteration')
    return result

"""The period search of a lightcurve: CPU and wall time of ``search_periods`` on a campaign.

A doubly periodic synthetic lightcurve (Apophis-like periods 30.565 h and 131.1 h, six terms,
0.01 mag noise) sampled like a ground-based campaign (nights of <= 8 h, clouded ones, 10
points an hour) of 3 and 4 weeks, searched over periods 10-600 h (docs/analysis.md, "Periods
from a lightcurve"). Target (issue 29): a few-week campaign in seconds.
"""
from __future__ import annotations

import time

import numpy as np

from common import section


@section("Period search of a lightcurve (analysis/periods.py)", order=45)
def periods_section(ctx):
    from tumble_ros.analysis.periods import campaign_times, search_periods

    f1, f2 = 1.0 / 30.565, 1.0 / 131.1
    terms = [(2, 0, 0.25, 0.3), (1, 0, 0.05, 1.0), (0, 1, 0.03, 2.0), (1, -1, 0.04, 0.5),
             (2, 1, 0.02, 4.0), (1, 2, 0.01, 2.5)]
    rows, result = [], {}
    for nights in ((14,) if ctx.quick else (21, 28)):
        rng = np.random.default_rng(nights)
        t = campaign_times(rng, nights, per_hour=10.0)
        y = sum(a * np.cos(2 * np.pi * (j * f1 + k * f2) * t + p) for j, k, a, p in terms)
        y = y + rng.normal(0.0, 0.01, t.size)
        wall, cpu = time.perf_counter(), time.process_time()
        sol = search_periods(t, y, np.full(t.size, 0.01), period_min=10.0, period_max=600.0)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        rows.append((nights, t.size, f"{sol.p1:.4f}", f"{sol.p2:.4f}", sol.order,
                     f"{cpu:.2f}", f"{wall:.2f}"))
        result[f"{nights} nights"] = {"points": int(t.size), "cpu_s": cpu, "wall_s": wall}
    ctx.table(["nights", "points", "P1 [h]", "P2 [h]", "order", "CPU [s]", "wall [s]"], rows)
    ctx.note("the basis may be a mirror of (30.565 h, 131.1 h): the same lattice of frequencies")
    return result

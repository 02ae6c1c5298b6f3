"""Scheduled impacts: a 2000-yr offline recording with 0, 1,000 and 10,000 impacts (issue 30).

`bringup --offline` (``runs.offline.record_offline``) of the paper's Fig 9 case (2000 yr,
200,001 samples) with n pulses of 3e-7 yr spread uniformly over the run, in this process (the
compiled loop already cached by a first, short run). Before issue 30 the cost grew as n^2: 100
impacts 2.8 s, 300 25.7 s, 1,000 more than 180 s; 10^6 held 3.9 GB and wrote nothing. Target:
10,000 impacts cost at most 2x the run without impacts; memory linear in the impacts, measured
here as the tracemalloc peak of a 100-yr run with 1,000 and 10,000 impacts (bytes per impact =
the difference of the peaks over the 9,000 impacts between them). In ensembles too:
``simulate_ensemble`` of 4 Fig 9 bodies over 2000 yr, one thread, without impacts and with
5 random impacts a year a body (~10,000 each), CPU against CPU.
"""
from __future__ import annotations

import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from common import section

CONFIG = Path(__file__).resolve().parents[1] / "tumble_ros" / "config" / "fig9.yaml"
TARGET_RATIO = 2.0
#: Bodies of the ensemble rows (each with its own impacts: ~10,000 over 2000 yr).
ENSEMBLE_BODIES = 4
#: Issue 30's figures before: impacts -> wall [s] (1,000: more than 180 s, not finished).
BEFORE_S = {100: 2.8, 300: 25.7, 1000: 180.0}


def _scenario(n: int, duration: float):
    from tumble_ros.core import Impact
    from tumble_ros.core.model.scenario import load_scenario

    base = load_scenario(CONFIG).replace(duration=duration)
    starts = np.sort(np.random.default_rng(1).uniform(0.0, duration - 1.0, n))
    return base.replace(impacts=tuple(Impact(float(s), 3e-7, (0.0, 1e3, 0.0)) for s in starts))


def _record(n: int, duration: float, folder: str) -> tuple[float, float]:
    """Return (wall, CPU) [s] of building the scenario and recording it."""
    from tumble_ros.runs.offline import record_offline

    wall, cpu = time.perf_counter(), time.process_time()
    path = Path(folder) / f"impacts_{n}_{duration:g}_{time.monotonic_ns()}.mcap"
    result = record_offline(_scenario(n, duration), path)
    if result.state != 2:   # FINISHED
        raise RuntimeError(result.message)
    return time.perf_counter() - wall, time.process_time() - cpu


def _ensemble(n_bodies: int, rate: float, duration: float) -> float:
    """Return the CPU [s] of ``simulate_ensemble`` of Fig 9 bodies, ``rate`` impacts/yr each."""
    from tumble_ros.core import random_impacts, simulate_ensemble
    from tumble_ros.core.model.scenario import load_scenario

    scenario = load_scenario(CONFIG).replace(duration=duration)
    impacts = (random_impacts(n_bodies, duration, rate=rate, torque=1e3, pulse=3e-7, seed=1)
               if rate else None)
    cpu = time.process_time()
    simulate_ensemble(scenario, impacts=impacts, n_bodies=None if rate else n_bodies,
                      threads=1)
    return time.process_time() - cpu


def _peak(n: int, duration: float, folder: str) -> int:
    tracemalloc.start()
    try:
        _record(n, duration, folder)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@section("Impacts: a 2000-yr offline recording with 0, 1,000 and 10,000 scheduled impacts", order=36)
def impacts_section(ctx):
    duration = 20.0 if ctx.quick else 2000.0
    counts = (0, 100, 1000) if ctx.quick else (0, 1000, 10_000)
    rows, out = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        _record(0, 2.0, tmp)   # compiled loop loaded, imports done
        base = None
        for n in counts:
            wall, cpu = _record(n, duration, tmp)
            base = base or (wall, cpu)
            before = None if ctx.quick else BEFORE_S.get(n)
            rows.append([n, f"{duration:g}", f"{wall:.2f}", f"{cpu:.2f}",
                         f"{wall / base[0]:.2f}x", f"{cpu / base[1]:.2f}x",
                         "-" if before is None else (f">{before:g}" if n == 1000 else f"{before:g}")])
            out[n] = {"wall_s": wall, "cpu_s": cpu}
        ctx.table(["impacts", "run [yr]", "wall [s]", "CPU [s]", "wall / none", "CPU / none",
                   "before [s]"], rows)
        mem_years = 20.0 if ctx.quick else 100.0
        lo, hi = (100, 1000) if ctx.quick else (1000, 10_000)
        p_lo, p_hi = _peak(lo, mem_years, tmp), _peak(hi, mem_years, tmp)
    per_impact = (p_hi - p_lo) / (hi - lo)
    ctx.note(f"memory (tracemalloc peak, {mem_years:g}-yr run): {lo:,} impacts {p_lo / 1e6:.1f} MB, "
             f"{hi:,} impacts {p_hi / 1e6:.1f} MB: {per_impact:,.0f} bytes per impact")
    ratio = out[counts[-1]]["cpu_s"] / out[0]["cpu_s"]
    ctx.note(f"target ({counts[-1]:,} impacts <= {TARGET_RATIO:g}x the run without, CPU): "
             f"{ctx.verdict(ratio <= TARGET_RATIO, f'MISSED by {ratio / TARGET_RATIO - 1:.0%}')}: "
             f"{ratio:.2f}x")
    out["bytes_per_impact"] = per_impact
    # in ensembles: the same per-body ratio (the compiled loop starts each segment itself)
    bodies, rate = ENSEMBLE_BODIES, counts[-1] / duration
    _ensemble(2, rate, 2.0)   # the loops' variants loaded
    cpu = {0: _ensemble(bodies, 0.0, duration), counts[-1]: _ensemble(bodies, rate, duration)}
    ratio = cpu[counts[-1]] / cpu[0]
    ctx.note(f"in ensembles (simulate_ensemble, {bodies} Fig 9 bodies over {duration:g} yr, "
             f"one thread): none {cpu[0]:.2f} s CPU, "
             f"{rate:g} impacts/yr a body (~{counts[-1]:,} each) {cpu[counts[-1]]:.2f} s: "
             f"{ratio:.2f}x (target <= {TARGET_RATIO:g}x: "
             f"{ctx.verdict(ratio <= TARGET_RATIO, f'MISSED by {ratio / TARGET_RATIO - 1:.0%}')})")
    out["ensemble"] = {"bodies": bodies, 0: {"cpu_s": cpu[0]},
                       counts[-1]: {"cpu_s": cpu[counts[-1]]}}
    return out

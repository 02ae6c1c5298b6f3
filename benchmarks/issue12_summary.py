"""Issue 12's four targets in one table: the issue's figure, this run's, the ratio, the verdict.

Runs last (order 99) and reads what the earlier sections of the same `make bench` returned
(ctx.results); a target whose section did not run (``--only``) is shown as not measured.
With ``--quick`` the sections run reduced workloads, so no verdict is given against targets
meant for the full run: the table shows this run's figures only.
The issue's figures are those its text states (2026-12-01): the main job 77 s; `analyze`
~45 us a message (22 k messages/s) with the generic decoder; the standalone nodes 1,755
samples/s (`make bench`, SingleThreadedExecutor); ensembles 1.15e7 body-steps/s.
"""
from __future__ import annotations

from common import section

MAIN_JOB = "Main job end to end: Fig 9 (2000 yr), simulate + compare + record + analyse"
READING = "Reading recordings (analyze): columnar vs generic decoding"
STANDALONE = "Standalone nodes: sim, comparator, recorder as three processes"
ENSEMBLE = "Ensemble throughput (body-steps per second)"


def _main_job(r):
    return min(r["wall_s"])


def _reading(r):
    return r["columnar_per_s"]


def _standalone(r):
    f = r["events"]
    return f["samples_per_s"] if sum(f["lost"].values()) == 0 else 0.0


def _ensemble(r):
    return r["splitting N=10000"]["body_steps_per_s"]


#: (what, section, its figure, the issue's figure, the target, lower is better, unit)
TARGETS = [
    ("Fig 9 main job, wall", MAIN_JOB, _main_job, 77.0, 10.0, True, "s"),
    ("analyze, columnar reading", READING, _reading, 22e3, 1e6, False, "messages/s"),
    ("standalone nodes, 0 lost", STANDALONE, _standalone, 1755.0, 2000.0, False, "samples/s"),
    ("ensembles, splitting, N = 10,000", ENSEMBLE, _ensemble, 1.15e7, 2e7, False,
     "body-steps/s"),
]


@section("Issue 12 targets: the issue's figure, this run's, the ratio", order=99)
def issue12_section(ctx):
    rows, results = [], {}
    for what, title, measure, before, target, lower, unit in TARGETS:
        if title not in ctx.results:
            rows.append([what, unit, f"{before:.4g}", "not measured", "", f"{target:.4g}", ""])
            continue
        now = measure(ctx.results[title])
        if ctx.quick:      # a reduced workload: not comparable with the full run's targets
            rows.append([what, unit, f"{before:.4g}", f"{now:.4g}", "", f"{target:.4g}",
                         "(quick: no verdict)"])
            results[what] = dict(before=before, now=now, target=target, met=None)
            continue
        gain = before / now if lower else now / before
        met = now <= target if lower else now >= target
        rows.append([what, unit, f"{before:.4g}", f"{now:.4g}", f"{gain:.3g}x", f"{target:.4g}",
                     "MET" if met else "MISSED"])
        results[what] = dict(before=before, now=now, gain=gain, target=target, met=met)
    ctx.table(["target", "unit", "issue 12's figure", "this run", "gain", "target", ""], rows)
    if ctx.quick:
        ctx.note("quick run: reduced workloads, no verdict; `make bench` for the targets")
    return results

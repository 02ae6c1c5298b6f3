"""The issues' speed targets in one table each: the issue's figure, this run's, the ratio, the verdict.

Runs last (order 99) and reads what the earlier sections of the same `make bench` returned
(ctx.results); a target whose section did not run (``--only``) is shown as not measured.
With ``--quick`` the sections run reduced workloads, so no verdict is given against targets
meant for the full run: the tables show this run's figures only.

Issue 12's figures are those its text states (2026-12-01): the main job 77 s; `analyze` ~45 us
a message (22 k messages/s) with the generic decoder; the standalone nodes 1,755 samples/s;
ensembles 1.15e7 body-steps/s. Issue 30's (2026-12-04, a quiet machine): ensembles 3.37e7
body-steps/s (`splitting`, N = 10,000, the per-body loop; the lockstep section also runs that
loop beside its own in the same run, and its ratio is the fair one); a node on the graph 3.3 s
after its start; the Fig 9 main job 6.0 s; impacts quadratic (1,000 scheduled impacts more
than 180 s, against ~2.5 s without); a fresh clone's first `make run` 95 s and its `make test`
5.5 minutes (the README then); `rk4`, `splitting6` and `dop853` ensembles at 1x (the per-body
loop, which each row measures beside its own in the same run).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable

from common import section

MAIN_JOB = "Main job end to end: Fig 9 (2000 yr), simulate + compare + record + analyse"
READING = "Reading recordings (analyze): columnar vs generic decoding"
STANDALONE = "Standalone nodes: sim, comparator, recorder as three processes"
BRINGUP = "End-to-end ROS throughput (bringup: sim + comparator + recorder)"
ENSEMBLE = "Ensemble throughput (body-steps per second)"
LOCKSTEP = "Ensembles in lockstep, vectorised across bodies (issue 30)"
STARTUP = "Node start-up: process start to the node on the ROS graph"
IMPACTS = "Impacts: a 2000-yr offline recording with 0, 1,000 and 10,000 scheduled impacts"
IMPACTS_LIVE = ("Impacts through the service: a live 2000-yr simulator with 0, 1,000 and 10,000 "
                "requested impacts")
FRESH_CLONE = "A fresh clone: its first make run and its make test (issues 30, 48)"
UNDER_LOAD = "events, 2 busy processes"     # ros_standalone.UNDER_LOAD


@dataclass(frozen=True)
class Target:
    """One row: what, the section it reads, how, the figure before, the target, its sense."""

    what: str
    section: str
    measure: Callable[[dict], float]
    before: float | None       # None: not measured before (shown as given in ``before_text``)
    target: float
    lower_is_better: bool
    unit: str
    before_text: str = ""

    def verdict(self, now: float) -> bool:
        """Tell whether ``now`` meets the target."""
        return now <= self.target if self.lower_is_better else now >= self.target

    def gain(self, now: float) -> float | None:
        """Return how many times better ``now`` is than before (None: no figure before)."""
        if self.before is None or now == 0:
            return None
        return self.before / now if self.lower_is_better else now / self.before


def _cpu_ratio(r: dict) -> float:
    return r[10_000]["cpu_s"] / r[0]["cpu_s"]


def _lost_under_load(r: dict) -> float:
    return float(sum(r[UNDER_LOAD]["lost"].values()))


def _fresh_clone_wall(target: str) -> Callable[[dict], float]:
    """Return the measure of a fresh clone's ``make <target>``: its wall time, inf if it failed."""
    return lambda r: r[target]["wall_s"] if r[target]["ok"] else math.inf


def _slowest_node(r: dict) -> float:
    return max(r[name]["visible_s"] for name in ("sim", "comparator", "recorder"))


ISSUE_12 = [
    Target("Fig 9 main job, wall", MAIN_JOB, lambda r: min(r["wall_s"]), 77.0, 10.0, True, "s"),
    Target("analyze, columnar reading", READING, lambda r: r["columnar_per_s"], 22e3, 1e6, False,
           "messages/s"),
    Target("standalone nodes, 0 lost", STANDALONE,
           lambda r: (r["events"]["samples_per_s"] if sum(r["events"]["lost"].values()) == 0
                      else 0.0), 1755.0, 2000.0, False, "samples/s"),
    Target("ensembles, splitting, N = 10,000", ENSEMBLE,
           lambda r: r["splitting N=10000"]["body_steps_per_s"], 1.15e7, 2e7, False,
           "body-steps/s"),
]

ISSUE_30 = [
    Target("ensembles, splitting, N = 10,000, end to end", LOCKSTEP,
           lambda r: r["splitting N=10000"]["end_to_end_per_s"], 3.37e7, 1e8, False,
           "body-steps/s"),
    Target("ensembles, splitting, N = 1,000,000, end to end", LOCKSTEP,
           lambda r: r["splitting N=1000000"]["end_to_end_per_s"], None, 1e8, False,
           "body-steps/s", "not measured"),
    Target("ensembles, splitting, N = 10,000, the compiled loop alone", LOCKSTEP,
           lambda r: r["splitting N=10000"]["loop_per_s"], None, 1e8, False, "body-steps/s"),
    Target("rk4, N = 10,000: lockstep / per-body loop", LOCKSTEP,
           lambda r: r["rk4 N=10000"]["ratio"], 1.0, 3.0, False, "x, same run"),
    Target("rk4, N = 10,000: lockstep / per-body, the loops alone", LOCKSTEP,
           lambda r: r["rk4 N=10000"]["loop_ratio"], 1.0, 3.0, False, "x, same run"),
    Target("splitting6, N = 10,000: lockstep / per-body loop", LOCKSTEP,
           lambda r: r["splitting6 N=10000"]["ratio"], 1.0, 3.0, False, "x, same run"),
    Target("splitting6, N = 10,000: lockstep / per-body, the loops alone", LOCKSTEP,
           lambda r: r["splitting6 N=10000"]["loop_ratio"], 1.0, 3.0, False, "x, same run"),
    Target("dop853, N = 10,000: lanes / per-body loop", LOCKSTEP,
           lambda r: r["dop853 N=10000"]["ratio"], 1.0, 3.0, False, "x, same run"),
    Target("dop853, N = 10,000: lanes / per-body, the loops alone", LOCKSTEP,
           lambda r: r["dop853 N=10000"]["loop_ratio"], 1.0, 3.0, False, "x, same run"),
    Target("node on the ROS graph after its start (slowest)", STARTUP, _slowest_node, 3.3, 1.0,
           True, "s"),
    Target("Fig 9 main job, wall", MAIN_JOB, lambda r: min(r["wall_s"]), 6.0, 3.0, True, "s"),
    Target("10,000 impacts / none, offline, CPU", IMPACTS, _cpu_ratio, None, 2.0, True, "x",
           "quadratic: 1,000 > 70x"),
    Target("10,000 impacts a body / none, ensembles, CPU", IMPACTS,
           lambda r: _cpu_ratio(r["ensemble"]), None, 2.0, True, "x", "not measured"),
    Target("10,000 impacts / none, live service, sim CPU", IMPACTS_LIVE, _cpu_ratio, None, 2.0,
           True, "x", "not measured"),
    Target("standalone nodes beside 2 busy processes: lost", STANDALONE, _lost_under_load,
           None, 0.0, True, "samples", "not measured"),
    Target("bringup beside 2 busy processes: lost", BRINGUP, _lost_under_load, None, 0.0, True,
           "samples", "not measured"),
    Target("a fresh clone's first make run, set-up included", FRESH_CLONE,
           _fresh_clone_wall("run"), 95.0, 60.0, True, "s"),
    Target("a fresh clone's make test, set-up included", FRESH_CLONE, _fresh_clone_wall("test"),
           330.0, 240.0, True, "s"),
]

#: Issue 48 (2026-12-07): issue 30's two newcomer's targets as a new machine sees them: the first
#: `make run` with every cache empty (103 s: the set-up 84 s, the run 19 s), `make test` warm on
#: two cores (10 min 37 s, 1,840 tests).
ISSUE_48 = [
    Target("a fresh clone's first make run, every cache empty", FRESH_CLONE,
           _fresh_clone_wall("run"), 103.0, 60.0, True, "s"),
    Target("a fresh clone's make test, warm", FRESH_CLONE, _fresh_clone_wall("test"),
           637.0, 240.0, True, "s"),
]

#: (issue, its targets), in the order the tables are printed.
ISSUES = [(12, ISSUE_12), (30, ISSUE_30), (48, ISSUE_48)]


def _row(target: Target, results: dict, quick: bool) -> tuple[list, dict | None]:
    """Return the table row of ``target`` and its entry in the section's results."""
    before = (f"{target.before:.4g}" if target.before is not None else target.before_text)
    if target.section not in results:
        return [target.what, target.unit, before, "not measured", "", f"{target.target:.4g}",
                ""], None
    try:
        now = target.measure(results[target.section])
    except (KeyError, TypeError, ZeroDivisionError):    # the section ran reduced (--quick)
        return [target.what, target.unit, before, "not measured", "", f"{target.target:.4g}",
                ""], None
    if quick:      # a reduced workload: not comparable with the full run's targets
        return ([target.what, target.unit, before, f"{now:.4g}", "", f"{target.target:.4g}",
                 "(quick: no verdict)"],
                dict(before=target.before, now=now, target=target.target, met=None))
    gain, met = target.gain(now), target.verdict(now)
    return ([target.what, target.unit, before, f"{now:.4g}",
             "" if gain is None else f"{gain:.3g}x", f"{target.target:.4g}",
             "MET" if met else "MISSED"],
            dict(before=target.before, now=now, gain=gain, target=target.target, met=met))


@section("Targets: each issue's figure before, this run's, the gain", order=99)
def targets_section(ctx):
    results: dict = {}
    for issue, targets in ISSUES:
        rows = []
        for target in targets:
            row, entry = _row(target, ctx.results, ctx.quick)
            rows.append(row)
            if entry is not None:
                results[f"issue {issue}: {target.what}"] = entry
        ctx.print(f"  issue {issue}:")
        ctx.table(["target", "unit", f"issue {issue}'s figure", "this run", "gain", "target",
                   ""], rows)
    if ctx.quick:
        ctx.note("quick run: reduced workloads, no verdict; `make bench` for the targets")
    return results

"""
Compile the integration loops ahead (build tooling): ``python -m tumble_ros.cli.warmup``.

numba compiles the single-body and the ensemble loops (per body, and in lockstep or as lanes for
the methods that have one) of each compiled method
(``core.kernels.KERNELS``) on their first use (then cached in the user's cache): a run compiles
only the loops it uses (``core.compiling.jit.first_use`` says so on stderr). This optional step
(``make warmup``; ``make test`` runs it first) compiles them all ahead (into the user's cache,
shared by the clones of the same sources: ``core.compiling.jit.shared_cache_folder``). It also
compiles the loops' variant for extra torques (``core.torques.TorqueComponent``: every scenario
with 1 to 8 of them shares it, whatever their functions; ``core.torques.component.EXTRA_SLOTS``)
and the reference path's calls. The loops compile in parallel, on up to as many processes as there
are cores (each method's loops are its own copies, so the compilations share nothing): one
task per method and variant, without and with extra torques, and the reference path's in
two more (:func:`_tasks`); each method says when its parts are ready.

``python -m tumble_ros.cli.warmup --scenario SCENARIO`` compiles (or loads) only what a run of
that scenario uses, by simulating its first output interval: ``make run`` does it beside the
set-up's colcon build, so that the run finds its loop compiled. SCENARIO is a params file or a
shipped scenario's name (``fig10``), as ``python -m tumble_ros`` takes it; a scenario this
cannot read or run is left to the run, which says why (this exits 0 either way).
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from concurrent.futures import as_completed, ProcessPoolExecutor
import multiprocessing
import os
from pathlib import Path
import sys
import time
from typing import Any

from tumble_ros.core import (Impact, IntegratorSettings, kernels, load_scenario, Scenario,
                             shipped_scenario, simulate, simulate_ensemble, torque_function,
                             TorqueComponent)
from tumble_ros.core.compiling import jit
from tumble_ros.core.integrators import INTEGRATORS

__all__ = ['warm_up', 'warm_up_scenario', 'main']


@torque_function
def _no_torque(par: object, t: float, q0: float, q1: float, q2: float,
               q3: float) -> tuple[float, float, float]:
    """Return no torque: only the type matters (the kernels' variant for one extra torque)."""
    return 0.0, 0.0, 0.0


def _tiny(extra: bool) -> Scenario:
    """Return the smallest scenario that runs a loop (with one extra torque if ``extra``)."""
    tiny = Scenario(duration=1e-3, output_interval=1e-3,
                    integrator=IntegratorSettings(method='splitting', step=1e-4))
    return tiny.replace(torques=(TorqueComponent('warm-up', _no_torque),)) if extra else tiny


#: The label of the reference path's compilations (:func:`_warm_reference`) in the reports.
REFERENCE = 'reference path'
#: The methods whose reference path (``simulate(..., fast=False)``) calls compiled functions.
REFERENCE_METHODS = ('splitting', 'rk4', 'dop853')


def _warm_variant(name: str, extra: bool) -> float:
    """
    Compile (or load) one method's single-body and ensemble loops; return the seconds.

    ``extra``: the variant for extra torques (else the one without).
    """
    started = time.perf_counter()
    run = _tiny(extra).replace(integrator=IntegratorSettings(method=name, step=1e-4))
    simulate(run)
    simulate_ensemble(run, n_bodies=2)   # the lockstep or lanes loop (methods with one)
    # bodies with their own impacts: the per-body loop
    simulate_ensemble(run, impacts=[(), (Impact(0.0, 5e-4, (1.0, 0.0, 0.0)),)])
    return time.perf_counter() - started


def _warm_reference(extra: bool) -> float:
    """Compile (or load) the reference path's compiled calls; return the seconds."""
    started = time.perf_counter()
    for method in REFERENCE_METHODS:
        simulate(_tiny(extra).replace(integrator=IntegratorSettings(method=method, step=1e-4)),
                 fast=False)
    return time.perf_counter() - started


#: One compilation of the warm-up: its function, arguments and label (a method's name).
Task = tuple[Callable[..., float], tuple[Any, ...], str]


def _tasks(names: list[str]) -> list[Task]:
    """
    Return the warm-up's compilations: each method's two variants apart, the reference path's.

    As one task a method, the longest (the splitting's two variants, ~30 s of CPU) started
    after another and ran alone for ~20 s of a fresh clone's warm-up, and the reference path
    (~7 s) compiled after them all, in one process; in parts of 3 to 30 s the processes stay
    busy to the end whatever their order (benchmarks/HISTORY.md, "The warm-up in parts").
    """
    return ([(_warm_reference, (extra,), REFERENCE) for extra in (False, True)]
            + [(_warm_variant, (name, extra), name) for name in names for extra in (False, True)])


def warm_up(report: bool = False) -> float:
    """
    Compile every method's single-body and ensemble loops now, or load them from the cache.

    The parts compile in parallel processes (up to the CPU count, :func:`_tasks`); ``report``
    prints a line as each method is ready, with the seconds its parts took. Returns the
    seconds taken (0 when numba is unavailable).
    """
    if not kernels.COMPILED:
        return 0.0
    started = time.perf_counter()
    # one integrator name per compiled method (its loops serve every name sharing the kernel)
    compiled = sorted({cls.kernel: name for name, cls in INTEGRATORS.items()
                       if cls.kernel in kernels.KERNELS}.values())
    tasks = _tasks(compiled)
    workers = max(1, min(len(tasks), os.cpu_count() or 1))
    left = Counter(label for _, _, label in tasks)
    took = dict.fromkeys(left, 0.0)
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context('spawn')) as pool:
        futures = {pool.submit(function, *args): label for function, args, label in tasks}
        for future in as_completed(futures):
            label = futures[future]
            took[label] += future.result()
            left[label] -= 1
            if report and not left[label]:
                print(f'   {label} {"calls" if label == REFERENCE else "loops"} ready '
                      f'({took[label]:.1f} s)', flush=True)
    for function, args, _ in tasks:  # loaded here from the cache the workers wrote (~3 s)
        function(*args)
    jit.prune_shared_cache()         # this version's folder marked used, old ones deleted
    return time.perf_counter() - started


def warm_up_scenario(name: str) -> float:
    """
    Compile (or load) the loops a run of scenario ``name`` uses; return the seconds taken.

    ``name``: a params file, or a shipped scenario's name (``fig10``: config/fig10.yaml), or
    ``''`` for the default scenario. The scenario's first output interval is simulated (the
    same method, torques and body: the same compiled loop). Raises what reading or running it
    raises (a ScenarioError for a file it refuses).
    """
    started = time.perf_counter()
    path = Path(name or 'default')
    if not path.is_file() and path.parent == Path('.') and path.suffix in ('', '.yaml'):
        path = shipped_scenario(path.name)
    scenario = load_scenario(path)
    simulate(scenario.replace(duration=scenario.output_interval))
    jit.prune_shared_cache()         # this version's folder marked used, old ones deleted
    return time.perf_counter() - started


def main(argv: list[str] | None = None) -> int:
    """Warm up, and say how long it took."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ['--scenario']:
        name = argv[1] if len(argv) > 1 else ''
        label = name or 'the default scenario'
        if not kernels.COMPILED:
            return 0
        print(f"== compiling the loops {label}'s run uses (numba; beside the set-up)", flush=True)
        try:
            seconds = warm_up_scenario(name)
        except Exception as err:     # the run itself reports it, in its own words
            print(f'   not compiled ahead ({type(err).__name__}: {err}): the run compiles what '
                  'it uses', flush=True)
            return 0
        print(f'== the loops of {label} ready ({seconds:.1f} s)', flush=True)
        return 0
    if kernels.COMPILED:
        print('== compiling the integration loops (numba; once per build, then cached)',
              flush=True)
    seconds = warm_up(report=True)
    print(f'== compiled loops ready ({seconds:.1f} s)' if kernels.COMPILED
          else '== numba not available: the reference path will be used', file=sys.stdout)
    return 0


if __name__ == '__main__':
    sys.exit(main())

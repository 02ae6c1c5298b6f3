"""``python -m tumble_ros``: the project's own entry point (the pip-only path has no ``ros2``).

    python -m tumble_ros [SCENARIO.yaml]      the main job on a scenario (default: config/default.yaml's)
    python -m tumble_ros sim [--ros-args ...] run an executable, as `ros2 run tumble_ros sim` would

The main job currently integrates the scenario with the core and prints a summary.
"""
from __future__ import annotations

import sys
import time

import numpy as np

from tumble_ros.core import Scenario, ScenarioError, load_scenario, simulate

#: Executables: name -> "module:function", as in setup.py's console_scripts.
EXECUTABLES = {
    "sim": "tumble_ros.nodes.sim:main",
    "comparator": "tumble_ros.nodes.comparator:main",
}


def run_executable(name: str, args: list[str]) -> int:
    """Run a node executable with ROS arguments."""
    import importlib

    module, function = EXECUTABLES[name].split(":")
    return getattr(importlib.import_module(module), function)([name, *args]) or 0


def main_job(argv: list[str]) -> int:
    """Simulate a scenario file (or the default scenario) and print a summary."""
    if len(argv) > 1 or (argv and argv[0].startswith("-")):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    try:
        scenario = load_scenario(argv[0]) if argv else Scenario()
    except ScenarioError as err:
        print(f"ERROR: {err}", file=sys.stderr)
        return 1
    source = argv[0] if argv else "the default scenario (config/default.yaml)"
    print(f"tumble_ros: {source}: {scenario.duration:g} yr, {scenario.integrator.method}, "
          f"inertia {scenario.inertia}, {len(scenario.impacts)} impact(s)")
    wall = time.perf_counter()
    result = simulate(scenario)
    wall = time.perf_counter() - wall
    print(f"  {len(result.t)} samples in {wall:.2f} s wall, {result.nfev} RHS evaluations, {result.n_steps} steps")
    if len(result.t):
        drift = np.max(np.abs(result.jacobi - result.jacobi[0])) / abs(result.jacobi[0])
        print(f"  w(t = {result.t[-1]:g} yr) = {np.round(result.omega[-1], 6).tolist()} rad/yr")
        print(f"  max relative Jacobi-integral change: {drift:.3g}" + (" (impacts change it)" if scenario.impacts else ""))
    if not result.success:
        print(f"ERROR: integration stopped: {result.message}", file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in EXECUTABLES:
        return run_executable(argv[0], argv[1:])
    return main_job(argv)


if __name__ == "__main__":
    raise SystemExit(main())

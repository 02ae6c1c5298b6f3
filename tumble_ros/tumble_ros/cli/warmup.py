"""
Compile the integration loops ahead (build tooling): ``python -m tumble_ros.cli.warmup``.

numba compiles the single-body and the ensemble loops of each compiled method
(``core.kernels.KERNELS``) on their first use (then cached beside the sources); ``make setup``
runs this after each build so that no run waits for it. It also compiles the loops' variant for
one extra torque (``core.torques.TorqueComponent``: every single extra torque shares it,
whatever its function) and the reference path's calls.
"""
from __future__ import annotations

import sys
import time

from tumble_ros.core import (IntegratorSettings, kernels, Scenario, simulate, simulate_ensemble,
                             torque_function, TorqueComponent)
from tumble_ros.core.integrators import INTEGRATORS

__all__ = ['warm_up', 'main']


@torque_function
def _no_torque(par: object, t: float, q0: float, q1: float, q2: float,
               q3: float) -> tuple[float, float, float]:
    """Return no torque: only the type matters (the kernels' variant for one extra torque)."""
    return 0.0, 0.0, 0.0


def warm_up() -> float:
    """
    Compile every method's single-body and ensemble loops now, or load them from the cache.

    Returns the seconds taken (0 when numba is unavailable).
    """
    if not kernels.COMPILED:
        return 0.0
    started = time.perf_counter()
    tiny = Scenario(duration=1e-3, output_interval=1e-3,
                    integrator=IntegratorSettings(method='splitting', step=1e-4))
    with_extra = tiny.replace(torques=(TorqueComponent('warm-up', _no_torque),))
    # one integrator name per compiled method (its loops serve every name sharing the kernel)
    compiled = {cls.kernel: name for name, cls in INTEGRATORS.items()
                if cls.kernel in kernels.KERNELS}
    for scenario in (tiny, with_extra):
        for name in compiled.values():
            run = scenario.replace(integrator=IntegratorSettings(method=name, step=1e-4))
            simulate(run)
            simulate_ensemble(run, n_bodies=2)
        for method in ('splitting', 'rk4', 'dop853'):   # the reference path's compiled calls
            simulate(scenario.replace(integrator=IntegratorSettings(method=method, step=1e-4)),
                     fast=False)
    return time.perf_counter() - started


def main(argv: list[str] | None = None) -> int:
    """Warm up, and say how long it took."""
    seconds = warm_up()
    print(f'== compiled loops ready ({seconds:.1f} s)' if kernels.COMPILED
          else '== numba not available: the reference path will be used', file=sys.stdout)
    return 0


if __name__ == '__main__':
    sys.exit(main())

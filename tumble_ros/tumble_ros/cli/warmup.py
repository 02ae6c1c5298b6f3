"""
Compile the integration loops ahead (build tooling): ``python -m tumble_ros.cli.warmup``.

numba compiles the single-body and the ensemble loops on their first use (~15 s, then cached
beside the sources); ``make setup`` runs this after each build so that no run waits for it.
"""
from __future__ import annotations

import sys
import time

from tumble_ros.core import IntegratorSettings, kernels, Scenario, simulate, simulate_ensemble

__all__ = ['warm_up', 'main']


def warm_up() -> float:
    """
    Compile the single-body and the ensemble loops now, or load them from numba's cache.

    Returns the seconds taken (0 when numba is unavailable).
    """
    if not kernels.COMPILED:
        return 0.0
    started = time.perf_counter()
    tiny = Scenario(duration=1e-3, output_interval=1e-3,
                    integrator=IntegratorSettings(method='splitting', step=1e-4))
    simulate(tiny)
    simulate_ensemble(tiny, n_bodies=2)
    return time.perf_counter() - started


def main(argv: list[str] | None = None) -> int:
    """Warm up, and say how long it took."""
    seconds = warm_up()
    print(f'== compiled loops ready ({seconds:.1f} s)' if kernels.COMPILED
          else '== numba not available: the reference path will be used', file=sys.stdout)
    return 0


if __name__ == '__main__':
    sys.exit(main())

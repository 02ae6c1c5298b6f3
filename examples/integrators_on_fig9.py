"""
Integrators on the paper's Fig 9 case over 100 years: wall time, Jacobi drift, error.

    scripts/env.sh python examples/integrators_on_fig9.py

Each method's largest |omega - omega_ref| [rad/yr] against dop853 at rtol 1e-13, and its
largest relative Jacobi drift: the choice of docs/performance.md, on a tenth of the span.
"""
from pathlib import Path
import time

import numpy as np

from tumble_ros.core import IntegratorSettings, load_scenario, simulate

CONFIG = Path(__file__).resolve().parents[1] / 'tumble_ros' / 'config' / 'fig9.yaml'
METHODS = {
    'dop853 rtol 1e-9': IntegratorSettings(method='dop853', rtol=1e-9, atol=1e-11),
    'splitting6 step 0.01': IntegratorSettings(method='splitting6', step=0.01),
    'splitting6 step 0.004': IntegratorSettings(method='splitting6', step=0.004),
    'rk4 step 2.5e-4': IntegratorSettings(method='rk4', step=2.5e-4),
}


def main(span: float = 100.0) -> None:
    """Print one line per method: seconds, drift, error against the reference."""
    scenario = load_scenario(CONFIG).replace(duration=span)
    reference = simulate(scenario.replace(
        integrator=IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-15)))
    print(f'Fig 9 over {span:g} yr, {len(reference.t)} samples, |omega| ~ 30 rad/yr')
    for name, settings in METHODS.items():
        start = time.perf_counter()
        run = simulate(scenario.replace(integrator=settings))
        seconds = time.perf_counter() - start
        drift = np.abs(run.jacobi - run.jacobi[0]).max() / abs(run.jacobi[0])
        error = np.linalg.norm(run.omega - reference.omega, axis=1).max()
        print(f'{name:24s} {seconds:7.3f} s   drift {drift:.1e}   error {error:.1e} rad/yr')


if __name__ == '__main__':
    main()

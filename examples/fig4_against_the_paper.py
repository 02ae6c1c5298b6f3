"""
The paper's Fig 4 case against its analytic solution: omega.png and error.png.

    scripts/env.sh python examples/fig4_against_the_paper.py [OUT_DIR]    # default: examples_out/

Simulates tumble_ros/config/fig4.yaml (2 yr, dop853), evaluates the paper's model (eqs 16-19,
corrected) at the same times, prints the largest difference [rad/yr] and draws both figures.
"""
from pathlib import Path
import sys

import numpy as np

from tumble_ros.analysis.plots import error_figure, omega_figure
from tumble_ros.core import load_scenario, make_model, simulate

CONFIG = Path(__file__).resolve().parents[1] / 'tumble_ros' / 'config' / 'fig4.yaml'


def main(out: Path) -> None:
    """Simulate, compare, draw into ``out``."""
    scenario = load_scenario(CONFIG)
    result = simulate(scenario)
    model = make_model('paper', scenario).omega(result.t)
    error = np.linalg.norm(result.omega - model, axis=1)
    print(f'{len(result.t)} samples over {result.t[-1]:g} yr; |omega| ~ '
          f"{np.linalg.norm(result.omega[0]):.4g} rad/yr; the paper's model is off by at most "
          f'{error.max():.3g} rad/yr (t = {result.t[error.argmax()]:.4g} yr)')
    out.mkdir(parents=True, exist_ok=True)
    omega_figure(result, scenario, model='paper').savefig(out / 'omega.png')
    error_figure(result, scenario, model='paper').savefig(out / 'error.png')
    print(f'figures: {out / "omega.png"}, {out / "error.png"}')


if __name__ == '__main__':
    main(Path(sys.argv[1] if len(sys.argv) > 1 else 'examples_out'))

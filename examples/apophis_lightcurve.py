"""
What a telescope would see of Apophis during its 2029 flyby: the lightcurve, drawn.

    scripts/env.sh python examples/apophis_lightcurve.py [OUT_DIR]    # default: examples_out/

Simulates tumble_ros/config/apophis_2029.yaml (144 h about perigee), computes the body's
magnitude as seen from the geocentre (core.photometry) and draws it with the phase angle.
"""
from pathlib import Path
import sys

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np

from tumble_ros.core import load_scenario, simulate
from tumble_ros.core.photometry import synthetic_lightcurve
from tumble_ros.core.units import HOURS_PER_YEAR

CONFIG = Path(__file__).resolve().parents[1] / 'tumble_ros' / 'config' / 'apophis_2029.yaml'


def main(out: Path) -> None:
    """Simulate the flyby and write ``out``/apophis_lightcurve.png."""
    scenario = load_scenario(CONFIG)
    run = simulate(scenario)
    lc = synthetic_lightcurve(scenario, run.t, run.quaternion)
    hours = lc.t * HOURS_PER_YEAR
    fig = Figure(figsize=(9, 5), layout='constrained')
    FigureCanvasAgg(fig)
    mag, phase = fig.subplots(2, 1, sharex=True)
    mag.plot(hours, lc.magnitude, lw=0.8)
    mag.invert_yaxis()
    mag.set_ylabel('magnitude')
    phase.plot(hours, np.degrees(lc.phase_angle), lw=0.8, color='tab:orange')
    phase.set_ylabel('phase angle [deg]')
    phase.set_xlabel('t [h] (perigee at 72 h)')
    mag.set_title('Apophis from the geocentre, 2029-04-10 21:46 TDB + t')
    out.mkdir(parents=True, exist_ok=True)
    fig.savefig(out / 'apophis_lightcurve.png')
    print(f'{len(hours)} samples; magnitude {np.nanmin(lc.magnitude):.2f} .. '
          f'{np.nanmax(lc.magnitude):.2f}; {out / "apophis_lightcurve.png"}')


if __name__ == '__main__':
    main(Path(sys.argv[1] if len(sys.argv) > 1 else 'examples_out'))

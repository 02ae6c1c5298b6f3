"""
The simulated Apophis lightcurve before and after the 2029 flyby, with the periods recovered.

    scripts/env.sh python scripts/make_lightcurve_figure.py [OUT_DIR]   # docs/figures/lightcurve/

The tumbler of tumble_ros/config/apophis_2029.yaml, torque-free over a 28-night campaign (nights
of <= 8 h, clouded ones, 10 points an hour, 0.01 mag Gaussian noise, a fixed seed), seen by
core/photometry with the Sun and the observer 37 deg from the ecliptic pole at 25 deg phase:
before the flyby (the file's spin state) and after it (the full scenario run, then propagated
torque-free from its end state). Each campaign is searched by analysis/periods.py; the figure
shows each campaign with the fit, and the periods found beside the spin state from omega
(docs/analysis.md, "Periods from a lightcurve"). Writes apophis_lightcurve.png and a summary.txt.
"""
from __future__ import annotations

import math
from pathlib import Path
import sys

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt   # noqa: E402
import numpy as np   # noqa: E402

from tumble_ros.analysis.periods import campaign_times, format_periods, search_periods  # noqa
from tumble_ros.core import load_scenario, simulate   # noqa: E402
from tumble_ros.core.model.rotation import quaternion_to_euler   # noqa: E402
from tumble_ros.core.model.spinstate import spin_state   # noqa: E402
from tumble_ros.core.photometry import LightcurveSettings, synthetic_lightcurve   # noqa: E402
from tumble_ros.core.units import HOURS_PER_YEAR as H   # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / 'tumble_ros' / 'config' / 'apophis_2029.yaml'
ALPHA = math.radians(25.0)
SETTINGS = LightcurveSettings(sun=(0.6, 0.0, -0.8),
                              observer=(0.6 * math.cos(ALPHA), 0.6 * math.sin(ALPHA), -0.8))


def campaign(scenario, seed: int):
    """Return (t [h], magnitude with noise, the spin state, the period solution)."""
    rng = np.random.default_rng(seed)
    th = campaign_times(rng, 28, per_hour=10.0)
    sc = scenario.replace(orbit=None, duration=(th[-1] + 1.0) / H)
    run = simulate(sc, th / H)
    mag = synthetic_lightcurve(sc, th / H, run.quaternion, SETTINGS).magnitude
    mag = mag + rng.normal(0.0, 0.01, th.size)
    state = spin_state(run.omega[0], sc.inertia, run.quaternion[0])
    return th, mag, state, search_periods(th, mag, np.full(th.size, 0.01), 10.0, 600.0)


def main(out: Path) -> None:
    """Write the figure and its summary into ``out``."""
    apophis = load_scenario(CONFIG)
    flyby = simulate(apophis)
    after = apophis.replace(omega0=tuple(flyby.omega[-1]),
                            euler0=quaternion_to_euler(flyby.quaternion[-1]))
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(2, 1, figsize=(12, 7))
    text = []
    for ax, (name, sc, seed) in zip(axes, (('before the flyby', apophis, 29),
                                           ('after the simulated flyby', after, 2029))):
        th, mag, state, sol = campaign(sc, seed)
        p_phi, p_psi = state.precession_period * H, state.rotation_period * H
        g = 1.0 / (1.0 / p_phi - 1.0 / p_psi)
        fine = np.linspace(th[0], th[-1], 20000)
        ax.plot(fine, sol.model(fine), '-', lw=0.4, color='C3', alpha=0.5,
                label='2-period Fourier fit (also through the gaps)')
        ax.plot(th, mag, '.', ms=1.5, color='0.2', label='synthetic photometry')
        ax.invert_yaxis()
        ax.set_ylabel('magnitude [mag]')
        periods = (f'found P1 = {sol.p1:.4g} h, P2 = {sol.p2:.4g} h' if sol.two_periods
                   else f'found P = {sol.p1:.3f} h')
        ax.set_title(f'Apophis {name}: from omega P_phi = {p_phi:.3f} h, P_psi = {p_psi:.1f} h, '
                     f'1/(1/P_phi - 1/P_psi) = {g:.3f} h\n{periods}, strongest term '
                     f'{1.0 / abs(sol.harmonics[0].frequency):.3f} h (order {sol.order}, '
                     f'RMS {sol.rms:.3f} mag, {sol.n} points over {sol.span / 24:.0f} d)',
                     fontsize=9)
        ax.legend(loc='lower right', fontsize=8)
        text += [f'Apophis {name}: P_phi = {p_phi:.4f} h, P_psi = {p_psi:.2f} h from omega',
                 format_periods(sol), '']
    axes[-1].set_xlabel('t [h] (a 28-night campaign, nights of <= 8 h, clouded ones lost)')
    fig.tight_layout()
    fig.savefig(out / 'apophis_lightcurve.png', dpi=110)
    (out / 'summary.txt').write_text('\n'.join(text))
    print('\n'.join(text))
    print(f'written: {out / "apophis_lightcurve.png"}')


if __name__ == '__main__':
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / 'docs' / 'figures' / 'lightcurve')

"""Apophis 2029 at the new depth (issue 28): degree 4 and 3, the Moon, the Sun, J2, the coupling.

    scripts/env.sh python scripts/apophis_depth.py [--bodies 1000] [--out DIR]

Writes into DIR (default build/figures/apophis_2029/depth/; the published copy is
docs/figures/apophis_2029/depth/, refreshed with --out and committed):

- summary.txt: the nominal body, the degree-3 sensitivity table, the size of each effect for
  the nominal spin state at a few phases (degree 4, the Moon, the Sun, the coupling, a
  plausible degree-3 moment), the ensembles' table and their body-by-body differences;
- table.md: the same tables in Markdown (docs/apophis.md quotes them);
- depth.png: the ensembles' distributions after the flyby and the differences of each step.

The body: a homogeneous ellipsoid of principal moments 0.64 : 0.97 : 1 (Lee et al. 2022, A&A
661, L3), semi-axes by the inverse formulas of core/model/shape.py scaled to a volume-equivalent
diameter of 0.34 km (Brozovic et al. 2018, Icarus 300, 115), density 2600 kg/m^3 (assumed, an
Sq-type rubble pile's; it cancels out of the torque on the fixed hyperbola), its field to
degree 4 (Ellipsoid.gravity_field). The ensembles: 1000 bodies, seed 1, 10 inertia draws of
+- 0.03, +- 0.015 as `make figures FIGS=apophis_2029` draws (the same bodies in every column).
"""
from __future__ import annotations

import argparse
from datetime import datetime
import math
from pathlib import Path
import sys
import time

import numpy as np

from tumble_ros.analysis.depth import (after_state, coupling_size, DEGREE3,
                                       degree3_sensitivity, depth_figure, distribution_table,
                                       lunisolar_perturbers, paired_differences, phase_states)
from tumble_ros.analysis.encounter import encounter_ensemble, format_encounter
from tumble_ros.core import load_scenario, simulate_ensemble
from tumble_ros.core.model.body import BodySpec
from tumble_ros.core.torques.perturbers import Perturber
from tumble_ros.core.units import HOURS_PER_YEAR
from tumble_ros.topics import SIM_NODE_PARAMETERS

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "tumble_ros" / "config" / "apophis_2029.yaml"
OUT = ROOT / "build" / "figures" / "apophis_2029" / "depth"
#: Volume-equivalent diameter [km] (Brozovic et al. 2018) and the assumed density [kg/m^3].
DIAMETER, DENSITY = 0.34, 2600.0
#: Perigee: 2029-04-13 21:46 TDB (the scenario's t_p; Souchay et al. 2014), as a Julian date.
PERIGEE_JD = 2451545.0 + (datetime(2029, 4, 13, 21, 46) - datetime(2000, 1, 1, 12, 0)
                          ).total_seconds() / 86400.0
#: The Earth's J2 (IERS 2010: 1.0826e-3) and pole in ecliptic J2000 (obliquity 23.4393 deg).
EARTH_J2 = 1.0826e-3
EARTH_POLE = (0.0, -math.sin(math.radians(23.4393)), math.cos(math.radians(23.4393)))
#: |K_3m| <~ 0.01 (Dinsmore & de Wit 2023, sec. 2.3: "typically").
K_PLAUSIBLE = 0.01
#: Period precisions [s]: AIME's threshold, their test case's sigma_P (1e-7 of 9 h), and the
#: 2026 A&A solution's formal P_phi precision (27.374 +- 0.001 h).
PRECISIONS = (3.6, 0.27, 3.2e-3)


def ellipsoid_axes(inertia) -> tuple[float, float, float]:
    """Semi-axes [km] of the homogeneous ellipsoid of these moments and diameter DIAMETER."""
    i = np.asarray(inertia, dtype=float)
    squares = np.array([i[1] + i[2] - i[0], i[0] + i[2] - i[1], i[0] + i[1] - i[2]])
    axes = np.sqrt(squares)
    axes *= (DIAMETER / 2.0) / float(np.prod(axes)) ** (1.0 / 3.0)
    return tuple(float(v) for v in axes)


def with_earth_j2(sc):
    """Return the scenario with its flyby's Earth oblate (J2, pole), the first perturber."""
    earth = Perturber('earth', sc.orbit, j2=EARTH_J2, pole=EARTH_POLE)
    return sc.replace(orbit=None, perturbers=(earth,) + sc.perturbers)


def effects_table(sc2, sc4, phases) -> str:
    """Return the size of each effect on the nominal state at ``phases`` (Markdown)."""
    w0, e0 = phase_states(sc4, phases)
    moon, sun = lunisolar_perturbers(sc4, PERIGEE_JD)

    def after(sc):
        run = simulate_ensemble(sc, [0.0, sc.duration], omega0=w0, euler0=e0)
        return after_state(run.omega[:, -1], run.quaternion[:, -1], sc.inertia)

    def diff(a, b):
        pole = np.degrees(np.arctan2(np.linalg.norm(np.cross(a[:, 2:5], b[:, 2:5]), axis=1),
                                     np.sum(a[:, 2:5] * b[:, 2:5], axis=1)))
        return np.column_stack([np.abs(a[:, 0] - b[:, 0]), np.abs(a[:, 1] - b[:, 1]), pole,
                                np.abs(a[:, 5] - b[:, 5]) / b[:, 5]])

    base = after(sc4)
    rows = {
        'degree 4 - degree 2 (the ellipsoid C40, C42, C44)': diff(base, after(sc2)),
        'the Moon': diff(after(sc4.replace(perturbers=(moon,))), base),
        'the Sun': diff(after(sc4.replace(perturbers=(sun,))), base),
        'the Moon and the Sun': diff(after(sc4.replace(perturbers=(moon, sun))), base),
        "the Earth's J2": diff(after(with_earth_j2(sc4)), base),
    }
    started = time.perf_counter()
    rows['coupled - fixed hyperbola (Earth, degree 4)'] = coupling_size(
        sc4, sc4.gravity_field, w0, e0, rtol=1e-13)
    coupling_time = time.perf_counter() - started
    lines = ['| effect (nominal spin state, phases ' + ', '.join(f'{p:g}' for p in phases)
             + ' of P_psi) | median / max abs dP_phi [s] | dP_psi [s] | pole [deg] | '
             '|w| (relative) |', '|---|---|---|---|---|']
    for name, d in rows.items():
        lines.append(f'| {name} | ' + ' | '.join(
            f'{np.median(d[:, k]):.2g} / {np.max(d[:, k]):.2g}' for k in range(4)) + ' |')
    print(f'coupled runs: {coupling_time:.1f} s for {2 * len(phases)}', file=sys.stderr)
    return '\n'.join(lines)


def sensitivity_table(sens, precisions) -> str:
    """Return the sensitivity table (Markdown); detectable: the change of K = 0.01 >= each."""
    lines = ['| moment | C of K = 0.01 | dP_phi/dC [s] | dP_psi/dC [s] | dpole/dC [deg] | '
             'dP_phi, dP_psi [s] of K = 0.01 | pole [deg] of K = 0.01 | linearity | '
             'P_phi / P_psi change >= ' + ', '.join(f'{p:g} s' for p in precisions) + ' |',
             '|---' * 9 + '|']
    median = sens.median
    for k, (kind, n, m) in enumerate(DEGREE3):
        change = K_PLAUSIBLE * sens.per_k[k]
        dp = median[k, :2] * change
        seen = [' / '.join('yes' if v >= p else 'no' for v in dp) for p in precisions]
        lines.append(
            f'| {kind}{n}{m} | {change:.4f} | {median[k, 0]:.3g} | {median[k, 1]:.3g} | '
            f'{median[k, 2]:.3g} | {dp[0]:.2g}, {dp[1]:.2g} | {median[k, 2] * change:.2g} | '
            f'{np.nanmax(sens.linearity[k, :3]):.0e} | {"; ".join(seen)} |')
    lines += ['', 'the nominal spin state alone (phase 0), signed: | moment | dP_phi/dC [s] | '
              'dP_psi/dC [s] | dpole/dC [deg] |', '|---|---|---|---|']
    for k, (kind, n, m) in enumerate(DEGREE3):
        d = sens.derivative[k, 0, 0]
        lines.append(f'| {kind}{n}{m} | {d[0]:.3g} | {d[1]:.3g} | {d[2]:.3g} |')
    return '\n'.join(lines)


def steps_table(steps) -> str:
    """Return the body-by-body differences of each step (median / 95 % / max; Markdown)."""
    lines = ['| step (the same 1000 bodies) | abs dP_phi [s] median / 95 % / max | abs dP_psi [s] '
             '| pole [deg] | mode changed |', '|---|---|---|---|---|']
    for name, d in steps.items():
        cells = [' / '.join(f'{v:.2g}' for v in np.nanpercentile(d[k], [50, 95, 100]))
                 for k in ('P_phi [s]', 'P_psi [s]', 'pole [deg]')]
        lines.append(f'| {name} | ' + ' | '.join(cells) + f' | {int(np.sum(d["mode"]))} |')
    return '\n'.join(lines)


def main(argv: list[str]) -> int:
    """Run everything and write DIR/summary.txt, table.md, depth.png; return the exit status."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--bodies', type=int, default=1000)
    p.add_argument('--phases', type=int, default=8, help='phases of the sensitivity (default 8)')
    p.add_argument('--out', type=Path, default=OUT)
    args = p.parse_args(argv)
    started = time.perf_counter()
    sc2 = load_scenario(CONFIG, ignore=frozenset(SIM_NODE_PARAMETERS))
    axes = ellipsoid_axes(sc2.inertia)
    sc4 = sc2.replace(body=BodySpec(model='ellipsoid', semi_axes=axes, density=DENSITY),
                      gravity_degree=4)
    field = sc4.gravity_field
    assert field is not None
    semi = ', '.join(f'{a * 1000:.1f}' for a in axes)
    ratios = ', '.join(f'{v / field.principal_moments[2]:.4f}' for v in field.principal_moments)
    head = [f'body: homogeneous ellipsoid, semi-axes {semi} m, D = {DIAMETER} km, density '
            f'{DENSITY:g} kg/m^3, mass {field.mass:.3e} kg, moments {ratios}',
            f'field: degree {field.degree}, reference radius '
            f'{field.reference_radius * 1000:.1f} m; '
            f'C20 {field.C[2, 0]:.5f}, C22 {field.C[2, 2]:.5f}, C40 {field.C[4, 0]:.3e}, '
            f'C42 {field.C[4, 2]:.3e}, C44 {field.C[4, 4]:.3e}; every odd degree and every S '
            f'zero (max |C3m| {np.max(np.abs(field.C[3])):.1e}, '
            f'|S| {np.max(np.abs(field.S)):.1e})',
            f'perigee JD {PERIGEE_JD:.5f} (2029-04-13 21:46 TDB)']
    phases = np.arange(args.phases) / args.phases
    w0, e0 = phase_states(sc4, phases)
    sens = degree3_sensitivity(sc4, w0, e0, deltas=(0.01, 0.02))
    print(f'sensitivity: {time.perf_counter() - started:.1f} s', file=sys.stderr)
    sens_md = sensitivity_table(sens, PRECISIONS)
    effects_md = effects_table(sc2, sc4, phases[::2])
    moon, sun = lunisolar_perturbers(sc4, PERIGEE_JD)
    scenarios = {'today (quadrupole)': sc2, 'degree 4': sc4,
                 '+ Moon & Sun': sc4.replace(perturbers=(moon, sun)),
                 "+ Earth's J2": with_earth_j2(sc4.replace(perturbers=(moon, sun)))}
    results = {}
    for name, sc in scenarios.items():
        t = time.perf_counter()
        results[name] = encounter_ensemble(sc, args.bodies, seed=1, inertia_spread=(0.03, 0.015),
                                           n_inertia=10)
        print(f'ensemble {name}: {time.perf_counter() - t:.1f} s', file=sys.stderr)
    names = list(results)
    steps = {'degree 4 - today': paired_differences(results[names[0]], results[names[1]]),
             '+ Moon & Sun - degree 4': paired_differences(results[names[1]], results[names[2]]),
             "+ Earth's J2 - (+ Moon & Sun)": paired_differences(results[names[2]],
                                                                 results[names[3]])}
    dist_md, steps_md = distribution_table(results), steps_table(steps)
    today = results[names[0]]
    change = (today.precession_after - today.precession_before) * HOURS_PER_YEAR
    ssr = (f'P_phi after - before [h] (today): 5 % {np.percentile(change, 5):.1f}, median '
           f'{np.median(change):.1f}, 95 % {np.percentile(change, 95):.1f}; |change| >= 10 h: '
           f'{100 * np.mean(np.abs(change) >= 10):.1f} % (faster '
           f'{100 * np.mean(change <= -10):.1f} %, slower {100 * np.mean(change >= 10):.1f} %), '
           '10 to 15 h: '
           f'{100 * np.mean((np.abs(change) >= 10) & (np.abs(change) <= 15)):.1f} %')
    base_lines = [f'nominal state after the flyby (degree 4), phase {ph:g}: P_phi '
                  f'{b[0] / 3600:.4f} h, P_psi {b[1] / 3600:.3f} h'
                  for ph, b in zip(phases, sens.base)]
    text = '\n\n'.join([
        '\n'.join(head + base_lines),
        f'## Sensitivity to the degree-3 moments (median over {args.phases} phases of |d/dC|, '
        f'central differences at dC = {sens.deltas[0]:g}; linearity: max relative change of '
        f'the derivative at dC = {sens.deltas[-1]:g})\n\n' + sens_md,
        '## Size of each effect\n\n' + effects_md,
        f'## Ensembles ({args.bodies} bodies, seed 1)\n\n' + dist_md,
        '## Body by body\n\n' + steps_md + '\n\n' + ssr,
        *[f'### {name}\n\n' + format_encounter(r) for name, r in results.items()]])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / 'summary.txt').write_text(text + '\n')
    (args.out / 'table.md').write_text('\n\n'.join([sens_md, effects_md, dist_md, steps_md])
                                       + '\n')
    (args.out / 'depth.png').write_bytes(depth_figure(results, steps))
    print(text)
    print(f'wrote {args.out}; {time.perf_counter() - started:.1f} s', file=sys.stderr)
    return 0


if __name__ == '__main__':
    raise SystemExit(main(sys.argv[1:]))

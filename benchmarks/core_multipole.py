"""The gravitational torque to degree N (issue 28): the compiled loop's cost at degree 4 vs 2.

The Apophis flyby (``config/apophis_2029.yaml``, 144 h) integrated by the compiled loops with
today's quadrupole torque (``gravity.degree`` 2: ``point_mass_torque``) and with the body's
field to degree 3, 4, 6 and 8 (``core/torques/multipole.py``). The field is Apophis' inertia
(0.64 : 0.97 : 1, 4.1e10 kg, reference radius 0.2 km) with random degree >= 3 coefficients of
the size a rubble pile's has (their values do not change the cost). Timed: ``simulate`` after a
warm-up (compiled, cached), best of a few repeats, for the scenario's own ``dop853`` and for
fixed-step ``rk4`` (the same number of torque calls at every degree). Target: degree 4 at most
3x degree 2.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from common import section

ROOT = Path(__file__).resolve().parents[1]


def _field(inertia, degree):
    from tumble_ros.core.model.gravity_field import GravityField

    moments = np.array(inertia) * 1.0e9                 # kg km^2: 4.1e10 kg, ~0.16 km rms
    base = GravityField.from_principal_moments(4.1e10, 0.2, moments, degree)
    rng = np.random.default_rng(28)
    c, s = base.C.copy(), base.S.copy()
    for n in range(3, degree + 1):
        c[n, :n + 1] = rng.normal(scale=0.01, size=n + 1)
        s[n, 1:n + 1] = rng.normal(scale=0.01, size=n)
    return GravityField(base.mass, base.reference_radius, c, s, base.principal_moments)


def _best(fn, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


@section("Gravity beyond the quadrupole: the compiled loop at degree N vs 2 (issue 28)", order=25)
def multipole_cost(ctx):
    from tumble_ros.core import IntegratorSettings, load_scenario, simulate

    scenario = load_scenario(ROOT / "tumble_ros" / "config" / "apophis_2029.yaml")
    field = _field(scenario.inertia, 8)
    repeats = 2 if ctx.quick else 5
    methods = {
        "dop853 (rtol 1e-11, the scenario's)": scenario.integrator,
        "rk4, step 0.002 h (72,000 steps)": IntegratorSettings(method="rk4", step=0.002 / 8766.0),
    }
    rows, results = [], {}
    for label, integrator in methods.items():
        base = scenario.replace(integrator=integrator, gravity_field=field)
        times = {}
        for degree in (2, 3, 4, 6, 8):
            sc = base.replace(gravity_degree=degree)
            simulate(sc)                                                   # warm-up
            times[degree] = _best(lambda: simulate(sc), repeats)
        for degree, wall in times.items():
            rows.append((label, degree, wall, wall / times[2]))
        results[label] = {d: t / times[2] for d, t in times.items()}
    ctx.table(["integrator", "degree", "wall [s]", "/ degree 2"], rows)
    ratio = max(r[4] for r in results.values())
    ctx.note(f"degree 4 / degree 2: {ratio:.2f}x (target <= 3x): {ctx.verdict(ratio <= 3.0)}\n"
             "Each: simulate of the 144-h Apophis flyby, best of the repeats after a warm-up.")
    return results

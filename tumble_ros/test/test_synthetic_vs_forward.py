"""
The project's forward model against the independent generator (synthetic_campaigns.py).

Where they meet, they must agree:

* the spin state: ``SpinObservables.scenario_fields`` (periods -> w by Carlson's integrals, the
  phases by ``rotation.euler_to_matrix``) and the generator's (periods -> w by K(k) and a
  trapezoid mean of phi', phases by its own passive z-x-z matrices) give the same w and attitude
  at the epoch to 1e-10;
* the motion: ``simulate`` (the project's DOP853, rtol 1e-12) and scipy's DOP853 on Euler's
  equations and dC/dt = C [w]x give the same attitude over days to 1e-8;
* the brightness: ``core.photometry.brightness`` on ``ellipsoid_mesh`` (an inscribed icosphere,
  20 4^k facets) and the generator's surface quadrature of the same ellipsoid differ by the
  mesh's discretisation only: the lightcurve's shape (magnitudes less their mean) agrees to
  7e-4 mag at k = 3 (1,280 facets), 1.4e-4 at k = 4 and 3e-5 at k = 5 (measured, a 0.7-mag
  lightcurve; the quadrature itself is good to ~1e-6 on its 1024 x 512 grid), the difference
  falling 4-6x per level (second order in the facet size): it is the mesh's, not a
  disagreement of the laws, frames or geometry.
"""
import math

import numpy as np
import pytest

import synthetic_campaigns as sc
from tumble_ros.core import IntegratorSettings, Scenario, simulate
from tumble_ros.core.model.observables import SpinObservables
from tumble_ros.core.model.rotation import euler_to_matrix, quaternion_to_matrix
from tumble_ros.core.photometry import brightness, ellipsoid_mesh
from tumble_ros.core.units import HOURS_PER_YEAR

DAYS_PER_YEAR = 365.25
STATES = [sc.TrueSpin('SAM', 11.0, 47.0, (0.55, 0.83), (123.0, -35.0), (0.7, 2.2),
                      epoch_jd=2459200.5),
          sc.TrueSpin('LAM', 9.0, 20.0, (0.5, 0.8), (30.0, 40.0), (0.4, 2.0), True,
                      2459200.5),
          sc.APOPHIS_PRAVEC_2014]


def project_state(spin: sc.TrueSpin) -> SpinObservables:
    """Return the same state in the project's type (periods in years, angles in radians)."""
    return SpinObservables(spin.mode, spin.precession_period_h / HOURS_PER_YEAR,
                           spin.rotation_period_h / HOURS_PER_YEAR, spin.inertia_ratios,
                           tuple(math.radians(v) for v in spin.pole_deg), spin.phases,
                           spin.anti_aligned)


@pytest.mark.parametrize('spin', STATES, ids=['SAM', 'LAM', 'Apophis'])
def test_the_epoch_state_is_the_same(spin):
    fields = project_state(spin).scenario_fields()
    omega, attitude = sc.initial_state(spin)
    assert np.array(fields['inertia']) == pytest.approx(spin.moments, rel=1e-15)
    assert np.array(fields['omega0']) / DAYS_PER_YEAR == pytest.approx(omega, rel=1e-10,
                                                                       abs=1e-10)
    assert euler_to_matrix(*fields['euler0']).T == pytest.approx(attitude, abs=1e-10)


@pytest.fixture(scope='module', params=STATES[:2], ids=['SAM', 'LAM'])
def both_runs(request):
    """(spin, t [JD], C the project's, C the generator's) every 0.05 d over 4 days."""
    spin = request.param
    days = 4.0
    scenario = Scenario(**project_state(spin).scenario_fields(), orbit_rate=0.0,
                        duration=days / DAYS_PER_YEAR, output_interval=0.05 / DAYS_PER_YEAR,
                        integrator=IntegratorSettings(method='dop853', rtol=1e-12,
                                                      atol=1e-12))
    run = simulate(scenario)
    assert run.success
    jd = spin.epoch_jd + run.t * DAYS_PER_YEAR
    ours = np.array([quaternion_to_matrix(q) for q in run.quaternion])
    _w, theirs = sc.integrate_attitude(spin, jd)
    return spin, jd, run.quaternion, ours, theirs


def test_the_motion_is_the_same(both_runs):
    _spin, _jd, _q, ours, theirs = both_runs
    assert np.max(np.abs(ours - theirs)) < 1e-8


def _lightcurves(both_runs, subdivisions):
    spin, jd, quaternion, _ours, attitude = both_runs
    # a fixed geometry at 25 deg phase, the Sun and the observer off the body's equator
    sun = np.array([0.6, 0.7, 0.39])
    sun /= np.linalg.norm(sun)
    axis = np.cross(sun, [0.0, 0.0, 1.0])
    axis /= np.linalg.norm(axis)
    a = math.radians(25.0)
    observer = sun * math.cos(a) + np.cross(axis, sun) * math.sin(a)
    axes = sc.ellipsoid_of_inertia(spin.inertia_ratios)
    theirs = sc.magnitudes(attitude, np.tile(sun, (jd.size, 1)),
                           np.tile(observer, (jd.size, 1)), axes, 0.0, 1024, 512)
    b = brightness(quaternion, sun, observer, ellipsoid_mesh(axes, subdivisions),
                   law='kaasalainen')
    ours = -2.5 * np.log10(b)
    return ours - ours.mean(), theirs - theirs.mean()


def test_the_brightness_is_the_same_to_the_mesh(both_runs):
    differences = []
    for k in (3, 4, 5):
        ours, theirs = _lightcurves(both_runs, k)
        assert np.ptp(theirs) > 0.2          # a lightcurve with something to compare
        differences.append(float(np.max(np.abs(ours - theirs))))
    assert differences[0] < 1e-3 and differences[2] < 1e-4
    assert differences[1] / differences[2] > 3.0 and differences[0] / differences[1] > 3.0

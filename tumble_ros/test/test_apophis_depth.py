"""
Apophis at the new depth (analysis/depth.py, analysis/encounter.with_inertia).

The degree-3 sensitivity obeys the mirror symmetry of a planar spin; the K_nm of Dinsmore &
de Wit computed from their definition match the Stokes coefficients through
:func:`stokes_per_k`; an ensemble's inertia draws re-derive an ellipsoid's field (proportional
moments, the new ellipsoid's C_4m) or keep a given field's higher moments; the low-precision
Moon and Sun meet two eclipses.
"""
from datetime import datetime
import math

import numpy as np
import pytest
from scipy.special import lpmv

from tumble_ros.analysis.depth import (DEGREE3, degree3_sensitivity, lunisolar_perturbers,
                                       moon_geocentric, paired_differences, stokes_per_k,
                                       sun_geocentric, with_coefficient)
from tumble_ros.analysis.encounter import encounter_ensemble, with_inertia
from tumble_ros.core import Scenario, ScenarioError
from tumble_ros.core.model.body import BodySpec
from tumble_ros.core.model.gravity_field import GravityField, principal_frame
from tumble_ros.core.model.mass_models import Ellipsoid
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.units import GM_EARTH, HOURS_PER_YEAR

H = HOURS_PER_YEAR
AXES = (0.217, 0.154, 0.147)        # km: an ellipsoid of moments ~0.64 : 0.97 : 1


def _flyby(**changes):
    """Return a planar (XY) Earth flyby at 38,326 km, perigee 72 h into a 144-h run."""
    orbit = KeplerOrbit.flyby(GM_EARTH, 38326.0, v_inf=5.84, t_p=72.0 / H)
    values = {'orbit_rate': 0.0, 'orbit': orbit, 'duration': 144.0 / H,
              'output_interval': 144.0 / H, 'gravity_degree': 3,
              'body': BodySpec(model='ellipsoid', semi_axes=AXES, density=2600.0)}
    values.update(changes)
    return Scenario(**values)


def _jd(*when):
    return 2451545.0 + (datetime(*when) - datetime(2000, 1, 1, 12)).total_seconds() / 86400.0


def test_a_mirror_symmetric_spin_is_blind_to_half_the_degree3_moments_at_first_order():
    """
    A spin about z (the largest moment) along the orbit's normal, the flyby in the xy plane.

    The mirror z -> -z maps the body with C_nm, S_nm (n + m odd: C30, C32, S32) onto the body
    with their opposites, the orbit and the spin onto themselves: |w| after is even in them
    (its derivative 0) while the pole tilts out of z at first order. The other four (n + m
    even) leave the body mirror-symmetric: the motion stays planar, the pole does not move,
    and |w| does change.
    """
    sc = _flyby()
    w = 2.0 * math.pi / (30.0 / H)
    sens = degree3_sensitivity(sc, [[0.0, 0.0, w]], [[0.0, 0.0, 0.0]], deltas=(0.05,))
    d = sens.derivative[:, 0, 0]                 # (7, outputs)
    odd = [k for k, (_, n, m) in enumerate(DEGREE3) if (n + m) % 2]
    even = [k for k in range(7) if k not in odd]
    assert [DEGREE3[k] for k in odd] == [('C', 3, 0), ('C', 3, 2), ('S', 3, 2)]
    spin, pole = np.abs(d[:, 3]), d[:, 2]
    assert np.min(spin[even]) > 1e-9                        # a real change of |w| ...
    assert np.max(spin[odd]) < 1e-6 * np.min(spin[even])    # ... none at first order
    assert np.min(pole[odd]) > 1e-6                         # the pole tilts [deg per unit C]
    assert np.max(pole[even]) < 1e-6 * np.min(pole[odd])    # ... or stays on z


def test_the_sensitivity_is_linear_and_names_its_coefficient():
    """Central differences at two steps agree (linear response); the field keeps its frame."""
    sc = _flyby()
    w0 = [[200.0, 30.0, 1500.0], [-150.0, 80.0, 1400.0]]
    sens = degree3_sensitivity(sc, w0, [[0.3, 1.0, 0.7], [2.0, 0.5, 1.1]], deltas=(0.01, 0.03))
    assert np.all(np.abs(sens.derivative[:, 0, :, :2]) > 0.0)
    assert np.max(sens.linearity[:, :2]) < 1e-4
    field = sc.gravity_field
    changed = with_coefficient(field, 'S', 3, 1, 0.2)
    assert changed.S[3, 1] == 0.2 and changed.C[2, 0] == field.C[2, 0]
    with pytest.raises(ValueError, match='S30'):
        with_coefficient(field, 'S', 3, 0, 0.1)


def test_stokes_per_k_is_dinsmore_and_de_wits_normalisation():
    """K_3m from their definition (app. A) over point masses = (C + i S) / stokes_per_k."""
    rng = np.random.default_rng(3)
    masses = rng.uniform(0.5, 1.5, 400)
    local, moments, _ = principal_frame(masses, rng.normal(size=(400, 3)) * [1.0, 0.7, 0.5])
    radius = float(np.linalg.norm(local, axis=1).max())
    field = GravityField.from_point_masses(masses, local, 3, radius)
    total, i_a = masses.sum(), moments.sum() / 2.0
    a_a = math.sqrt(i_a / total)                # uniform: I_A = M a_A^2
    r = np.linalg.norm(local, axis=1)
    cos_theta, phi = local[:, 2] / r, np.arctan2(local[:, 1], local[:, 0])
    for m in range(4):
        legendre = (-1) ** m * lpmv(m, 3, cos_theta)      # without Condon-Shortley
        regular = (-1) ** m * r ** 3 * legendre * np.exp(1j * m * phi) / math.factorial(3 + m)
        k = a_a ** (2 - 3) / i_a * np.sum(masses * regular)
        stokes = field.C[3, m] + 1j * field.S[3, m]
        assert abs(k) > 1e-4
        assert abs(abs(stokes) / stokes_per_k(field, 3, m) - abs(k)) < 1e-12 * abs(k) + 1e-15


def test_an_ellipsoids_field_follows_each_inertia_draw():
    """A drawn inertia rebuilds the ellipsoid (same volume): moments proportional, its C_4m."""
    sc = _flyby(gravity_degree=4)
    drawn = (0.62, 0.975, 1.0)
    new = with_inertia(sc, drawn)
    assert new.inertia == pytest.approx(drawn, rel=1e-12)
    ratios = np.asarray(new.gravity_field.principal_moments) / np.asarray(drawn)
    assert np.ptp(ratios) < 1e-12 * ratios[0]
    squares = [drawn[1] + drawn[2] - drawn[0], drawn[0] + drawn[2] - drawn[1],
               drawn[0] + drawn[1] - drawn[2]]
    axes = np.sqrt(squares) * (np.prod(AXES) / np.prod(np.sqrt(squares))) ** (1 / 3)
    expected = Ellipsoid(tuple(axes), 2600.0).gravity_field(4)
    np.testing.assert_allclose(new.gravity_field.C, expected.C, rtol=1e-12, atol=1e-15)
    assert new.gravity_field.mass == pytest.approx(sc.gravity_field.mass, rel=1e-12)
    assert with_inertia(sc, sc.inertia) is sc


def test_a_given_field_keeps_its_higher_moments_through_an_inertia_draw():
    """A field given directly: C_20, C_22 follow the drawn moments, C_3m and C_4m stay."""
    base = _flyby(gravity_degree=4)
    lumpy = with_coefficient(base.gravity_field, 'C', 3, 1, 0.01)
    sc = base.replace(body=BodySpec(), gravity_field=lumpy)
    new = with_inertia(sc, (0.63, 0.96, 1.0))
    field = new.gravity_field
    assert field.C[3, 1] == 0.01 and field.C[4, 2] == lumpy.C[4, 2]
    a, b, c = field.principal_moments
    assert c == pytest.approx(lumpy.principal_moments[2], rel=1e-12)
    assert (a / c, b / c) == pytest.approx((0.63, 0.96), rel=1e-12)
    scale = field.mass * field.reference_radius ** 2
    assert field.C[2, 2] == pytest.approx((b - a) / (4 * scale), rel=1e-12)


def test_the_ensemble_draws_inertias_with_a_mass_model():
    """encounter_ensemble with an ellipsoid at degree 4 and three inertia draws runs them."""
    sc = _flyby(gravity_degree=4, omega0=(300.0, 0.0, 1400.0), euler0=(0.4, 0.9, 0.2))
    result = encounter_ensemble(sc, 6, seed=1, inertia_spread=(0.03, 0.015), n_inertia=3)
    assert np.all(result.success)
    assert len({tuple(row) for row in result.inertia}) == 3
    assert paired_differences(result, result)['P_phi [s]'].max() == 0.0


def test_a_polyhedron_cannot_take_drawn_moments():
    sc = _flyby(body=BodySpec(model='polyhedron', shape_file='config/shapes/apophis.obj',
                              density=2600.0), gravity_degree=2)
    with pytest.raises(ScenarioError, match='^body.model: polyhedron'):
        with_inertia(sc, (0.6, 0.95, 1.0))


def test_the_low_precision_moon_and_sun_meet_two_eclipses():
    """Total solar eclipse 2024-04-08 (~18:17 UT): aligned; total lunar 2025-03-14 (~06:59)."""
    def angle(jd):
        m, s = moon_geocentric(jd), sun_geocentric(jd)
        return math.degrees(math.acos(np.dot(m, s) / np.linalg.norm(m) / np.linalg.norm(s)))

    assert angle(_jd(2024, 4, 8, 18, 17)) < 1.0
    assert angle(_jd(2025, 3, 14, 6, 59)) > 179.0
    assert 356_000 < np.linalg.norm(moon_geocentric(_jd(2029, 4, 13))) < 407_000
    assert np.linalg.norm(sun_geocentric(_jd(2029, 4, 13))) / 1.495978707e8 == pytest.approx(
        1.003, abs=0.003)


def test_the_moon_and_sun_tables_are_the_earths_hyperbola_plus_their_geocentric_positions():
    sc = _flyby()
    moon, sun = lunisolar_perturbers(sc, _jd(2029, 4, 13, 21, 46))
    t = np.array([0.0, 50.0, 72.0, 100.0, 144.0]) / H
    jd = _jd(2029, 4, 13, 21, 46) + (t - 72.0 / H) * H / 24.0
    earth = sc.orbit.position(t)
    np.testing.assert_allclose(moon.source.position(t), earth + moon_geocentric(jd),
                               rtol=0, atol=1e-3)
    np.testing.assert_allclose(sun.source.position(t), earth + sun_geocentric(jd),
                               rtol=1e-12, atol=1e-3)

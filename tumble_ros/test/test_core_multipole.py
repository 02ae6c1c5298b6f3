"""
The gravitational torque to degree N (core/torques/multipole.py, core/model/gravity_field.py).

Proven against independent computations: the solid harmonics against scipy's Legendre functions;
the field's acceleration and torque against the brute-force sum over the point masses the field
was made of, converging like (a/R)^(N+1) in N (the fitted slope) and inside the rigorous bound
GM/R^2 sum_{n>N} (n+1) (a/R)^n; degree 2 against today's quadrupole torque (paper eq 12 on the
Kepler orbit) to rounding; the odd degrees of a centrally symmetric body vanish; and through a
flyby integrated with the degree-4 torque, the inertial angular momentum changes by the
quadrature of the torque (dL/dt = C M) and the energy by its work (dE/dt = w . M).
"""
import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson, simpson
from scipy.special import lpmv

from tumble_ros.core import IntegratorSettings, Scenario, ScenarioError, simulate
from tumble_ros.core.model.dynamics import angular_momentum_orbital
from tumble_ros.core.model.gravity_field import (GravityField, principal_frame,
                                                 regular_solid_harmonics)
from tumble_ros.core.model.rotation import quaternion_to_matrix
from tumble_ros.core.torques import tidal_torque
from tumble_ros.core.torques.multipole import field_acceleration, field_torque
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.torques.perturbers import Perturber
from tumble_ros.core.units import SECONDS_PER_YEAR

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 28


def solid_body(rng, n=300, axes=(0.6, 0.8, 1.0)):
    """
    Return (masses [kg], positions [km]) of a random body in an ellipsoid, principal frame.

    ``rng`` is the calling test's own generator.
    """
    p = rng.uniform(-1.0, 1.0, size=(8 * n, 3))
    p = p[(p ** 2).sum(axis=1) <= 1.0][:n] * np.array(axes)
    m = rng.uniform(0.5, 1.5, n) * 1e9
    q, _, _ = principal_frame(m, p)
    return m, q


def brute_force(m, q, point):
    """Return the acceleration per G [kg/km^2] at ``point`` and -R x it: sums over the masses."""
    d = q - point
    acceleration = (m[:, None] * d / np.linalg.norm(d, axis=1)[:, None] ** 3).sum(axis=0)
    return acceleration, -np.cross(point, acceleration)


def evaluate(field, degree, point):
    """Return (acceleration per G, torque per G m_p) of ``field`` to ``degree`` at ``point``."""
    c = np.array(field.packed(degree))
    a = field.reference_radius
    return (np.array(field_acceleration(*point, field.mass, a, degree, c, 0, 0)),
            np.array(field_torque(*point, field.mass, a, degree, c, 0)))


def test_the_solid_harmonics_are_r_n_times_the_legendre_functions():
    """r^n P_nm(sin phi) (cos, sin) m lam, P_nm without the Condon-Shortley phase (scipy's has)."""
    rng = np.random.default_rng(SEED)
    points = rng.normal(size=(20, 3))
    v, w = regular_solid_harmonics(points, 8)
    r = np.linalg.norm(points, axis=1)
    sin_lat, lon = points[:, 2] / r, np.arctan2(points[:, 1], points[:, 0])
    # with this seed the worst element is 2.6e-14 of itself beyond the atol; near a root of P_nm
    # an element's relative error grows (1.6e-12 in 2 of 100 other draws), hence the fixed seed
    for n in range(9):
        for m in range(n + 1):
            p = (-1.0) ** m * lpmv(m, n, sin_lat) * r ** n
            np.testing.assert_allclose(v[:, n, m], p * np.cos(m * lon), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(w[:, n, m], p * np.sin(m * lon), rtol=1e-12, atol=1e-12)
    assert np.all(v[:, 3, 5] == 0.0)


@pytest.mark.parametrize('ratio', [2.0, 3.0, 5.0, 10.0])
def test_the_field_converges_to_the_point_mass_sum_like_a_over_r_to_the_n_plus_1(ratio):
    """Error of degree N ~ (a/R)^(N+1): the slope of log(error) in N is log(a/R)."""
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng)
    a = float(np.linalg.norm(q, axis=1).max())
    field = GravityField.from_point_masses(m, q, 8, a)
    degrees = np.arange(2, 9)
    errors, torque_errors = [], []
    for _ in range(8):                        # directions: the geometric mean of their errors
        u = rng.normal(size=3)
        point = ratio * a * u / np.linalg.norm(u)
        acc, torque = brute_force(m, q, point)
        got = [evaluate(field, int(n), point) for n in degrees]
        errors.append([np.linalg.norm(g[0] - acc) / np.linalg.norm(acc) for g in got])
        torque_errors.append([np.linalg.norm(g[1] - torque) / np.linalg.norm(torque)
                              for g in got])
        # the rigorous bound: |grad of degree n| <= (n + 1) r^n / R^(n+2) for each mass
        for n, g in zip(degrees, got):
            tail = sum((k + 1) * ratio ** -k for k in range(n + 1, 200))
            assert np.linalg.norm(g[0] - acc) <= m.sum() / (ratio * a) ** 2 * tail
    for e in (errors, torque_errors):
        mean = np.exp(np.log(e).mean(axis=0))
        slope = np.polyfit(degrees, np.log(mean), 1)[0]
        # with this seed, at a/R = 1/2: -0.20 (acceleration), -0.14 (torque); other bodies give
        # -0.01 to -0.26 there (degrees 2-8 steeper than the bound), which is why the seed is fixed
        assert abs(slope - math.log(1.0 / ratio)) < 0.25, (slope, math.log(1.0 / ratio))
        assert mean[-1] < 2.0 * ratio ** -6.0           # degree 8: (a/R)^9 and a factor


def test_degree_2_is_the_quadrupole_torque_to_rounding():
    """-m_p R x a_2(R) = 3 GM_p / R^3 u x (I u) (paper eq 12), the moments in kg km^2."""
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng)
    a = float(np.linalg.norm(q, axis=1).max())
    field = GravityField.from_point_masses(m, q, 4, a)
    ix, iy, iz = field.principal_moments
    for _ in range(10):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        distance = rng.uniform(2.0, 10.0) * a
        _, torque = evaluate(field, 2, distance * u)
        k = 3.0 / distance ** 3
        eq12 = np.array(tidal_torque(k * (iz - iy), k * (ix - iz), k * (iy - ix), *u))
        # rounding of the moments' differences: C_20, C_22 are summed apart from the moments
        np.testing.assert_allclose(torque, eq12, rtol=0, atol=1e-14 * k * (ix + iy + iz))


def test_the_degree_2_component_is_todays_kepler_torque_to_rounding():
    """The orbit's component at degree 2 (normalised inertia, years) is the point-mass law's."""
    rng = np.random.default_rng(SEED)
    inertia = (0.64, 0.97, 1.0)
    field = GravityField.from_principal_moments(2.7e10, 0.34, np.array(inertia) * 3.1e8, 4)
    orbit = KeplerOrbit.flyby(398600.4418, 38000.0, v_inf=5.8, t_p=0.001, inclination=0.4,
                              node=1.1, lambda_p=0.3)
    ours = field.torque_component(orbit, inertia, 2)
    today = Perturber('kepler_orbit', orbit).torque_component(inertia)
    for t in np.linspace(0.0, 0.002, 11):
        quaternion = rng.normal(size=4)
        quaternion /= np.linalg.norm(quaternion)
        expected = today.torque(t, quaternion)
        np.testing.assert_allclose(ours.torque(t, quaternion), expected, rtol=0,
                                   atol=1e-13 * np.linalg.norm(expected))
    assert np.linalg.norm(today.torque(0.001, (1.0, 0.0, 0.0, 0.0))) > 0.0


def test_the_acceleration_without_its_lowest_degrees_is_the_difference():
    """``lowest`` 2 leaves out degrees 0 and 1 (the default 0 keeps them)."""
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng)
    a = float(np.linalg.norm(q, axis=1).max())
    field = GravityField.from_point_masses(m, q, 5, a)
    c = np.array(field.packed())
    point = np.array([2.0, -1.0, 1.5]) * a
    whole = np.array(field_acceleration(*point, 3.0, a, 5, c, 0))
    central = -3.0 * point / np.linalg.norm(point) ** 3
    beyond = np.array(field_acceleration(*point, 3.0, a, 5, c, 0, 2))
    np.testing.assert_allclose(beyond, whole - central, rtol=0, atol=1e-13 * np.linalg.norm(whole))
    assert np.linalg.norm(beyond) > 1e-3 * np.linalg.norm(whole)


def test_odd_degrees_vanish_for_a_centrally_symmetric_body():
    """Point masses in +- pairs: C_nm = S_nm = 0 for odd n; degree 2k+1 torque = degree 2k's."""
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng, 150)
    m2, q2 = np.concatenate([m, m]), np.concatenate([q, -q])
    q2, _, _ = principal_frame(m2, q2)
    a = float(np.linalg.norm(q2, axis=1).max())
    symmetric = GravityField.from_point_masses(m2, q2, 7, a)
    lopsided = GravityField.from_point_masses(m, q, 7, a)
    for n in (3, 5, 7):
        assert np.max(np.abs(symmetric.C[n])) + np.max(np.abs(symmetric.S[n])) < 1e-14
        assert np.max(np.abs(lopsided.C[n])) > 1e-4      # (the check can see odd terms)
    point = 2.5 * a * np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    for n in (2, 4, 6):
        even, odd = evaluate(symmetric, n, point)[1], evaluate(symmetric, n + 1, point)[1]
        np.testing.assert_allclose(odd, even, rtol=0, atol=1e-14 * np.linalg.norm(even))
        one, two = evaluate(lopsided, n, point)[1], evaluate(lopsided, n + 1, point)[1]
        assert np.linalg.norm(two - one) > 1e-4 * np.linalg.norm(one)


def test_the_field_of_a_body_turned_about_z_turns_with_it():
    """Rotating the masses by an angle about z: the acceleration at the rotated point rotates."""
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng)
    a = float(np.linalg.norm(q, axis=1).max())
    angle = 0.7
    rz = np.array([[math.cos(angle), -math.sin(angle), 0.0],
                   [math.sin(angle), math.cos(angle), 0.0], [0.0, 0.0, 1.0]])
    field = GravityField.from_point_masses(m, q, 6, a)
    # the turned body is not principal in these axes: its coefficients straight from the sums
    v, w = regular_solid_harmonics(q @ rz.T, 6)
    turned_c = np.einsum('i,inm->nm', m, v)
    turned_s = np.einsum('i,inm->nm', m, w)
    c_n = np.einsum('i,inm->nm', m, regular_solid_harmonics(q, 6)[0])
    s_n = np.einsum('i,inm->nm', m, regular_solid_harmonics(q, 6)[1])
    for order in range(7):    # C + i S of order m turns by e^(i m angle) (unnormalised sums)
        turned = (c_n[:, order] + 1j * s_n[:, order]) * np.exp(1j * order * angle)
        np.testing.assert_allclose(turned_c[:, order], turned.real, rtol=0, atol=1e-6 * m.sum())
        np.testing.assert_allclose(turned_s[:, order], turned.imag, rtol=0, atol=1e-6 * m.sum())
    point = np.array([2.0, 1.0, -1.5]) * a
    acc, _ = evaluate(field, 6, point)
    brute, _ = brute_force(m, q @ rz.T, rz @ point)
    np.testing.assert_allclose(rz @ acc, brute, rtol=0, atol=3e-4 * np.linalg.norm(brute))


@pytest.mark.parametrize('kwargs, match', [
    ({'mass': 0.0}, r'^gravity_field\.mass: .*got 0\.0'),
    ({'reference_radius': math.nan}, r'^gravity_field\.reference_radius: .*got nan'),
    ({'moments': (1.0, 1.0, 1.01)}, r'^gravity_field\.C\[2, 0\]: must agree'),
    ({'offset': (1, 0)}, r'^gravity_field\.C\[1, 0\]: must be 0'),
    ({'offset': (2, 1)}, r'^gravity_field\.C\[2, 1\]: must be 0'),
])
def test_a_bad_field_is_refused_naming_the_field(kwargs, match):
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng, 100)
    good = GravityField.from_point_masses(m, q, 3, 1.0)
    values = {'mass': good.mass, 'reference_radius': good.reference_radius, 'C': good.C.copy(),
              'S': good.S.copy(), 'principal_moments': good.principal_moments}
    offset = kwargs.pop('offset', None)
    if 'moments' in kwargs:
        kwargs['principal_moments'] = tuple(np.multiply(good.principal_moments,
                                                        kwargs.pop('moments')))
    if offset is not None:
        values['C'][offset] = 1e-6
    values.update(kwargs)
    with pytest.raises(ValueError, match=match):
        GravityField(**values)


def test_truncated_and_packed_keep_the_coefficients():
    rng = np.random.default_rng(SEED)
    m, q = solid_body(rng, 100)
    field = GravityField.from_point_masses(m, q, 5, 1.2)
    low = field.truncated(3)
    assert low.degree == 3 and np.array_equal(low.C, field.C[:4, :4])
    packed = field.packed(3)
    assert len(packed) == 20 and packed[3 * 4 // 2 + 2] == field.C[3, 2]
    assert packed[10 + 3 * 4 // 2 + 1] == field.S[3, 1]
    assert low == field.truncated(3) and low != field
    with pytest.raises(ValueError, match=r'^gravity_field\.degree: .*\[2, 5\].*got 6'):
        field.truncated(6)


# -- through a flyby: the scenario's gravity_degree ---------------------------------------------

def _flyby(degree, field=None, **changes):
    """Return a tumbler passed at 3 body radii by a point mass, its field to ``degree``."""
    if field is None:  # one body whatever the tests run before (the flyby's effect depends on
        # it: the energy changes by 3e-6 to 1e-3 of itself over seeds 0-9)
        m, q = solid_body(np.random.default_rng(SEED), 300, axes=(0.5, 0.8, 1.0))
        field = GravityField.from_point_masses(m, q, 4, float(np.linalg.norm(q, axis=1).max()))
    inertia = tuple(np.array(field.principal_moments) / field.principal_moments[2])
    # GM 4e6 km^3/yr^2 (the orbit takes km^3/s^2), pericentre a (e - 1) = 3 body radii
    orbit = KeplerOrbit(gm=4.0e6 / SECONDS_PER_YEAR ** 2, a=1.0,
                        e=1.0 + 3.0 * field.reference_radius, t_p=0.01, lambda_p=0.4,
                        inclination=0.3, node=0.2)
    base = Scenario(inertia=inertia, orbit_rate=0.0, orbit=orbit, omega0=(300.0, -200.0, 2000.0),
                    euler0=(0.3, 0.2, 0.8), duration=0.02, output_interval=1e-5,
                    gravity_degree=degree, gravity_field=field,
                    integrator=IntegratorSettings(method='dop853', rtol=1e-12, atol=1e-12))
    return base.replace(**changes)


def test_through_a_degree_4_flyby_momentum_and_energy_change_by_the_torque():
    """dL/dt = C(q) M and dE/dt = w . M by quadrature over the samples; degree 4 is not 2."""
    sc = _flyby(4)
    component = sc.extra_torques[0]
    assert component.name == 'kepler_orbit'
    r = simulate(sc)
    assert r.success
    inertia = np.array(sc.inertia)
    c = np.array([quaternion_to_matrix(q) for q in r.quaternion])
    momentum = angular_momentum_orbital(r.omega, c, inertia)
    torque = np.array([component.torque(t, q) for t, q in zip(r.t, r.quaternion)])
    torque_orbital = np.einsum('nij,nj->ni', c, torque)
    change = momentum[-1] - momentum[0]
    assert np.linalg.norm(change) > 1e-2 * np.linalg.norm(momentum[0])    # the flyby matters
    np.testing.assert_allclose(change, simpson(torque_orbital, x=r.t, axis=0), rtol=0,
                               atol=1e-10 * np.linalg.norm(momentum[0]))   # 4e-13 seen
    energy = 0.5 * np.sum(inertia * r.omega ** 2, axis=1)
    work = cumulative_simpson(np.sum(r.omega * torque, axis=1), x=r.t, initial=0.0)
    # 2.9e-4 of itself: 1000x the tolerance below (1e-7), so the check is not vacuous
    assert abs(energy[-1] - energy[0]) > 1e-4 * energy[0]
    np.testing.assert_allclose(energy - energy[0], work, rtol=0, atol=1e-7 * energy[0])  # 5e-9
    quadrupole = simulate(sc.replace(gravity_degree=2))
    # degree 4 moves the spin by 1.0e-3 of |omega0| from the quadrupole's (measured)
    assert np.max(np.abs(quadrupole.omega - r.omega)) > 3e-4 * np.linalg.norm(sc.omega0)


def test_degree_3_of_the_inertia_alone_runs_as_todays_torque():
    """A field with C_20, C_22 only: gravity_degree 3 integrates today's quadrupole."""
    field = GravityField.from_principal_moments(1e12, 1.0, (0.5e12, 0.8e12, 1.0e12), 3)
    sc = _flyby(3, field)
    np.testing.assert_allclose(simulate(sc).omega, simulate(sc.replace(gravity_degree=2)).omega,
                               rtol=0, atol=1e-9 * np.linalg.norm(sc.omega0))


def test_the_scenario_refuses_a_bad_gravity_degree_naming_it():
    sc = _flyby(2)
    with pytest.raises(ScenarioError, match=r"^gravity\.degree: must be <= the gravity_field's "
                       r'degree \(4\).*got 5$'):
        sc.replace(gravity_degree=5)
    with pytest.raises(ScenarioError, match=r'^gravity\.degree: .*Kepler orbit.*got 3$'):
        Scenario(gravity_degree=3, gravity_field=sc.gravity_field, inertia=sc.inertia)
    with pytest.raises(ScenarioError, match=r'^gravity\.degree: .*no gravity_field.*got 4$'):
        sc.replace(gravity_degree=4, gravity_field=None)
    with pytest.raises(ScenarioError, match=r'^gravity\.degree: .*integer.*got 2\.0$'):
        sc.replace(gravity_degree=2.0)
    with pytest.raises(ScenarioError, match=r'^gravity_field\.principal_moments: must be '
                       r'proportional'):
        sc.replace(inertia=(sc.inertia[0] * 1.001,) + sc.inertia[1:])
    with pytest.raises(ScenarioError, match=r'^gravity\.degree: .*Kepler orbit.*got 4$'):
        Scenario.from_parameters({'gravity.degree': 4})
    assert Scenario().to_parameters()['gravity.degree'] == 2


def test_an_ensemble_runs_the_degree_4_torque_as_simulate_does():
    from tumble_ros.core import simulate_ensemble

    sc = _flyby(4, integrator=IntegratorSettings(method='splitting6', step=2e-5),
                output_interval=1e-3)
    ens = simulate_ensemble(sc, n_bodies=2, omega0=[sc.omega0, (100.0, 50.0, 1500.0)])
    np.testing.assert_allclose(ens.omega[0], simulate(sc).omega, rtol=0, atol=1e-8)
    quadrupole = simulate_ensemble(sc.replace(gravity_degree=2), n_bodies=2,
                                   omega0=[sc.omega0, (100.0, 50.0, 1500.0)])
    assert np.max(np.abs(ens.omega - quadrupole.omega)) > 3e-4 * np.linalg.norm(sc.omega0)


def test_the_scenario_with_its_field_pickles_as_dask_ships_it():
    import pickle

    sc = _flyby(4)
    copy = pickle.loads(pickle.dumps(sc))
    assert copy == sc and copy.gravity_field == sc.gravity_field
    assert copy.extra_torques[0].parameters == sc.extra_torques[0].parameters

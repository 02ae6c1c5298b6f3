"""
Several perturbers and the perturber's J2 (core/torques/perturbers.py, core/torques/oblateness.py).

The Scenario's ``orbit`` is its first perturber (the same run, bit for bit); several perturbers
integrate as an independent numpy/scipy integration of Euler's equations with the sum of their
point-mass torques; the J2 torque equals the brute-force sum, over the point masses of a body,
of the exact force of the J2 potential (differentiated by complex steps); the parameters
``perturbers.*`` round-trip and are refused naming the field.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_core_torque import point_cloud

from tumble_ros.core import (dump_scenario, IntegratorSettings, parse_scenario, Scenario,
                             ScenarioError, simulate)
from tumble_ros.core.model.rotation import quaternion_to_matrix
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.torques.perturbers import Perturber
from tumble_ros.core.units import GM_EARTH, SECONDS_PER_YEAR

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 280
YR2 = SECONDS_PER_YEAR ** 2


def test_the_orbit_is_the_first_perturber():
    orbit = KeplerOrbit.flyby(GM_EARTH, 40000.0, v_inf=6.0, t_p=0.004, lambda_p=0.3)
    sc = Scenario(inertia=(0.64, 0.97, 1.0), orbit_rate=0.0, omega0=(30.0, 0.0, 200.0),
                  duration=0.008, output_interval=1e-4, orbit=orbit)
    as_perturber = sc.replace(orbit=None, perturbers=(Perturber('earth', orbit),))
    assert [p.name for p in sc.all_perturbers] == ['kepler_orbit']
    assert sc.encounter_window == as_perturber.encounter_window is not None
    a, b = simulate(sc), simulate(as_perturber)
    np.testing.assert_array_equal(a.omega, b.omega)
    np.testing.assert_array_equal(a.quaternion, b.quaternion)
    np.testing.assert_array_equal(sc.perturber_position(a.t), as_perturber.perturber_position(a.t))


def numpy_run(sc: Scenario, t_eval):
    """Integrate Euler's equations with scipy, the torque summed in numpy from the positions."""
    inertia = np.asarray(sc.inertia)

    def torque(t, q):
        c = quaternion_to_matrix(q)                             # body -> orbital
        total = np.zeros(3)
        for body in sc.all_perturbers:
            s = c.T @ body.position([t])[0]
            r = np.linalg.norm(s)
            u = s / r
            total += 3.0 * body.gm * YR2 / r ** 3 * np.cross(u, inertia * u)
        return total

    def f(t, y):
        w, q = y[:3], y[3:]
        dw = (np.cross(inertia * w, w) + torque(t, q)) / inertia
        q0, q1, q2, q3 = q
        wx, wy, wz = w
        dq = 0.5 * np.array([-q1 * wx - q2 * wy - q3 * wz, q0 * wx + q2 * wz - q3 * wy,
                             q0 * wy - q1 * wz + q3 * wx, q0 * wz + q1 * wy - q2 * wx])
        return np.concatenate([dw, dq])

    q0 = simulate(sc, t_eval=[0.0]).quaternion[0]
    sol = solve_ivp(f, (0.0, t_eval[-1]), np.concatenate([sc.omega0, q0]), method='DOP853',
                    t_eval=t_eval, rtol=1e-12, atol=1e-12)
    return sol.y[:3].T


def test_several_perturbers_torque_as_the_sum_of_their_point_masses():
    earth = KeplerOrbit.flyby(GM_EARTH, 40000.0, v_inf=6.0, t_p=0.004, lambda_p=0.3,
                              inclination=0.4, node=1.0)
    moon = KeplerOrbit(gm=4902.800066, a=20000.0, e=0.3, t_p=0.001, lambda_p=2.0,
                       inclination=-0.7)
    sun = KeplerOrbit(gm=1.3271244e11, a=1.4e8, e=0.2, t_p=0.3, node=0.5)
    sc = Scenario(inertia=(0.64, 0.97, 1.0), orbit_rate=0.0, omega0=(30.0, 0.0, 200.0),
                  euler0=(0.3, 0.2, 0.8), duration=0.008, output_interval=1e-4,
                  perturbers=(Perturber('earth', earth), Perturber('moon', moon),
                              Perturber('sun', sun)),
                  integrator=IntegratorSettings(rtol=1e-12, atol=1e-12))
    assert [t.name for t in sc.extra_torques] == ['earth', 'moon', 'sun']
    t = sc.output_times[::10]
    run = simulate(sc, t_eval=t)
    reference = numpy_run(sc, t)
    scale = np.max(np.linalg.norm(reference, axis=1))
    assert np.max(np.abs(run.omega - reference)) < 1e-9 * scale
    # each perturber matters: without the Moon the run differs by far more than that
    no_moon = simulate(sc.replace(perturbers=sc.perturbers[::2]), t_eval=t)
    assert np.max(np.abs(no_moon.omega - run.omega)) > 1e-6 * scale


def j2_potential(s, k, mu):
    """V_J2 = (mu / 2) (3 (s.k)^2 / s^5 - 1 / s^3) at (n, 3) positions s (complex allowed)."""
    r2 = np.sum(s * s, axis=-1)
    z = s @ k
    return 0.5 * mu * (3.0 * z * z / r2 ** 2.5 - 1.0 / r2 ** 1.5)


def complex_step_force(s, k, mu):
    """Return -grad V_J2 at s, each component by a complex step (exact to rounding)."""
    h = 1e-30 * np.max(np.abs(s))
    force = np.empty_like(s)
    for axis in range(3):
        step = np.zeros(3, dtype=complex)
        step[axis] = 1j * h
        force[:, axis] = -np.imag(j2_potential(s + step, k, mu)) / h
    return force


@pytest.mark.parametrize('trial', range(4))
def test_the_j2_torque_is_the_sum_of_the_j2_forces_on_the_bodys_point_masses(trial):
    rng = np.random.default_rng((SEED, trial))           # a body, pole and place per trial
    m, r, inertia = point_cloud(rng, 200)
    m, r = np.concatenate([m, m]), np.concatenate([r, -r])      # centrally symmetric
    inertia = 2.0 * inertia                                      # (no octupole: error ~ (r/s)^2)
    radius, j2 = 6378.137, 1.0826e-3 * (1 + 30 * trial)          # J2 up to 0.1 (the limit)
    pole = rng.normal(size=3)
    position = rng.normal(size=3)
    position *= 1.5 * radius / np.linalg.norm(position)          # the perturber, orbital frame
    orbit = KeplerOrbit(gm=GM_EARTH, a=1e9, e=0.0)               # (its source is not used)
    body = Perturber('earth', orbit, j2=j2, pole=tuple(pole))
    point = Perturber('earth', orbit)
    law, law_point = body.law(inertia), point.law(inertia)
    from tumble_ros.core.compiling.jit import python_source
    from tumble_ros.core.torques.perturbers import perturber_torque
    torque_of = python_source(perturber_torque)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    j2_torque = (np.array(torque_of(np.array(law), *position, *q))
                 - np.array(torque_of(np.array(law_point), *position, *q)))
    c = quaternion_to_matrix(q)                                  # body -> orbital
    k = pole / np.linalg.norm(pole)
    mu = GM_EARTH * YR2 * j2 * radius ** 2
    at = c @ r.T                                                 # the masses, orbital frame
    force = m[:, None] * complex_step_force(at.T - position, k, mu)
    brute = c.T @ np.sum(np.cross(at.T, force), axis=0)
    assert np.linalg.norm(brute) > 0.0
    np.testing.assert_allclose(j2_torque, brute, rtol=1e-6, atol=1e-6 * np.linalg.norm(brute))
    # and the point-mass part: 3 GM / s^3 u x (I u), brute force as well
    g = GM_EARTH * YR2 * (position - at.T) / np.linalg.norm(position - at.T, axis=1)[:, None] ** 3
    point_brute = c.T @ np.sum(np.cross(at.T, m[:, None] * g), axis=0)
    np.testing.assert_allclose(torque_of(np.array(law_point), *position, *q), point_brute,
                               rtol=1e-6, atol=1e-6 * np.linalg.norm(point_brute))
    ratio = np.linalg.norm(j2_torque) / np.linalg.norm(point_brute)
    assert 0.1 * j2 < ratio < 10.0 * j2        # J2 (R/s)^2 ~ 0.44 J2 of the point mass's


PARAMS = """
/**/sim:
  ros__parameters:
    time_unit: h
    inertia: [0.64, 0.97, 1.0]
    orbit_rate: 0.0
    omega0: [0.0455, 0.0, 0.2022]
    duration: 48.0
    output_interval: 0.5
    perturbers:
      names: [earth, moon]
      earth:
        kind: flyby
        gm: 398600.4418
        perigee: 38326.0
        v_inf: 5.84
        t_p: 24.0
        j2: 1.0826e-3
        pole: [0.0, 0.3977771559, 0.9174820621]
      moon:
        kind: kepler
        gm: 4902.800066
        a: 380000.0
        e: 0.05
"""


def test_the_perturbers_section_round_trips_and_runs():
    sc = parse_scenario(PARAMS)
    earth, moon = sc.perturbers
    assert earth.j2 == 1.0826e-3 and earth.radius == 6378.137 and moon.radius == 1737.4
    assert earth.source.t_p == pytest.approx(24.0 / 8766.0, rel=1e-15)
    assert abs(np.linalg.norm(earth.law(sc.inertia)[5:8]) - 1.0) < 1e-15
    assert sc.encounter_window is not None       # the first perturber's flyby
    assert parse_scenario(dump_scenario(sc)) == sc
    params = sc.to_parameters()
    assert params['perturbers.names'] == ['earth', 'moon']
    assert params['perturbers.earth.kind'] == 'kepler' and params['perturbers.earth.j2'] > 0
    run = simulate(sc)
    assert run.success and run.omega.shape == (len(sc.output_times), 3)


@pytest.mark.parametrize('change, match', [
    (('names: [earth, moon]', 'names: [earth, earth]'), r'^perturbers\.names: must be distinct'),
    (('kind: kepler', 'kind: elliptic'), r"^perturbers\.moon\.kind: must be one of \['ephemeris"),
    (('a: 380000.0', 'a: 380000.0\n        perigee: 1.0'),
     r'^perturbers\.moon\.perigee: is used only with perturbers\.moon\.kind: flyby'),
    (('e: 0.05', 'e: 0.05\n        epoch_jd: 2.4e6'),
     r'^perturbers\.moon\.epoch_jd: is used only with kind: ephemeris'),
    (('v_inf: 5.84', 'v_inf: -5.84'), r'^perturbers\.earth\.v_inf, perturbers\.earth\.v_perigee'),
    (('j2: 1.0826e-3', 'j2: 0.5'), r'^perturbers\.earth\.j2: must be in \[-0\.1, 0\.1\]'),
    (('pole: [0.0, 0.3977771559, 0.9174820621]', 'pole: [0.0, 0.0, 0.0]'),
     r'^perturbers\.earth\.pole: must not be the zero vector'),
    (('orbit_rate: 0.0', 'orbit_rate: 1.0'), r'^orbit_rate: must be 0 with perturbers'),
    (('      moon:\n', '      moon:\n        colour: 1.0\n'),
     r'^perturbers\.moon\.colour: unknown scenario parameter'),
])
def test_a_bad_perturbers_section_is_refused_naming_the_field(change, match):
    old, new = change
    assert old in PARAMS
    with pytest.raises(ScenarioError, match=match):
        parse_scenario(PARAMS.replace(old, new, 1))


def test_j2_needs_a_radius_unless_the_gm_is_a_known_bodys():
    orbit = KeplerOrbit(gm=1000.0, a=1e5, e=0.1)
    with pytest.raises(ValueError, match=r'^perturbers\.x\.radius: J2 needs its reference'):
        Perturber('x', orbit, j2=1e-3)
    assert Perturber('x', orbit, j2=1e-3, radius=100.0).radius == 100.0
    assert math.isclose(Perturber('e', KeplerOrbit(gm=GM_EARTH, a=1e5, e=0.1)).radius, 6378.137)


def test_an_ensemble_runs_several_perturbers_and_a_table_as_simulate_does():
    from tumble_ros.core import simulate_ensemble
    from tumble_ros.core.torques.ephemeris import Ephemeris

    earth = KeplerOrbit.flyby(GM_EARTH, 40000.0, v_inf=6.0, t_p=0.004, lambda_p=0.3)
    knots = np.linspace(-0.001, 0.009, 241)
    table = Ephemeris(tuple(knots), tuple(map(tuple, earth.position(knots))))
    moon = KeplerOrbit(gm=4902.800066, a=20000.0, e=0.3, t_p=0.001, lambda_p=2.0)
    sc = Scenario(inertia=(0.64, 0.97, 1.0), orbit_rate=0.0, omega0=(30.0, 0.0, 200.0),
                  duration=0.008, output_interval=1e-3,
                  perturbers=(Perturber('earth', table, gm=GM_EARTH, j2=1e-3),
                              Perturber('moon', moon)),
                  integrator=IntegratorSettings(method='splitting6', step=1e-5))
    ens = simulate_ensemble(sc, n_bodies=2, omega0=[sc.omega0, (10.0, 5.0, 150.0)])
    np.testing.assert_allclose(ens.omega[0], simulate(sc).omega, rtol=0, atol=1e-10)
    assert np.max(np.abs(ens.omega[0] - simulate(sc.replace(perturbers=())).omega)) > 1e-2


def test_with_the_bodys_field_the_torque_is_its_degree_n_torque():
    """
    Degree 2 of the field: the point-mass law to rounding; degree 4: the brute-force sum.

    The field of a point cloud to degree 4 (``GravityField.from_point_masses``) against the sum
    of the perturber's pull on every point; the monopole, left out, would cost 5e-3 of the
    torque at 1e6 km from a 0.3-km body (``perturbers`` docstring).
    """
    from tumble_ros.core.compiling.jit import python_source
    from tumble_ros.core.model.gravity_field import GravityField, principal_frame
    from tumble_ros.core.torques.perturbers import perturber_torque

    torque_of = python_source(perturber_torque)
    rng = np.random.default_rng(SEED)
    m, r, _ = point_cloud(rng, 300)
    m = m * 1e9                                              # kg
    r = r * 0.1                                              # km: a body ~0.3 km across
    r, moments, _ = principal_frame(m, r)
    inertia = moments / moments[2]
    field4 = GravityField.from_point_masses(m, r, 4, float(np.max(np.linalg.norm(r, axis=1))))
    field2 = GravityField.from_principal_moments(field4.mass, field4.reference_radius,
                                                 field4.principal_moments, 2)
    orbit = KeplerOrbit(gm=GM_EARTH, a=1e9, e=0.0)
    earth = Perturber('earth', orbit)
    point = np.array(earth.law(inertia))
    for distance in (3.0, 40000.0, 1.0e6):
        position = rng.normal(size=3)
        position *= distance / np.linalg.norm(position)
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        law = torque_of(point, *position, *q)
        two = earth.torque_component(inertia, field2).parameters
        np.testing.assert_allclose(torque_of(np.array(two), *position, *q), law, rtol=1e-12)
        four = np.array(earth.torque_component(inertia, field4).parameters)
        c = quaternion_to_matrix(q)
        s = c.T @ position                                   # the Earth in body axes
        d = s - r
        pull = GM_EARTH * YR2 * d / np.linalg.norm(d, axis=1)[:, None] ** 3
        brute = np.sum(np.cross(r, m[:, None] * pull), axis=0) / (moments[2] / inertia[2])
        # degree 4 leaves (size / R)^3 ~ 1e-3 of the torque at 3 km, far below rounding beyond.
        # At 3 km the bar is on |torque|, not on each component: the truncation's error is
        # (size / R)^3 of the whole torque, so a small component (a direction nearly along a
        # principal axis) can be off by more of itself (2.4e-2 seen over 60 draws, |error| /
        # |torque| at most 1.5e-3 over them: 3e-3 is 2x that; 3.8e-5 with this seed)
        near = distance < 10
        np.testing.assert_allclose(torque_of(four, *position, *q), brute, rtol=0 if near else 1e-6,
                                   atol=3e-3 * np.linalg.norm(brute) if near else 0)


def test_the_earths_j2_through_the_apophis_flyby_is_small_and_linear_in_j2():
    """
    Measured 2026-12-04: the Earth's J2 moves Apophis' spin by up to 4.1e-5 of |w|.

    The pole of the Earth in ecliptic J2000, (0, -sin eps, cos eps); doubling J2 doubles the
    change (the torque is linear in J2; the spin's response to it, 4e-5, nearly so).
    """
    from pathlib import Path

    from tumble_ros.core import load_scenario

    apophis = load_scenario(Path(__file__).resolve().parents[1] / 'config' / 'apophis_2029.yaml')
    eps = math.radians(23.4393)
    pole = (0.0, -math.sin(eps), math.cos(eps))

    def run(j2):
        earth = Perturber('earth', apophis.orbit, j2=j2, pole=pole)
        return simulate(apophis.replace(orbit=None, perturbers=(earth,))).omega

    point, once, twice = run(0.0), run(1.0826e-3), run(2.0 * 1.0826e-3)
    scale = np.linalg.norm(point, axis=1)
    change = np.max(np.linalg.norm(once - point, axis=1) / scale)
    assert 1e-5 < change < 1e-4
    np.testing.assert_allclose(twice - point, 2.0 * (once - point), rtol=0,
                               atol=0.01 * change * scale.max())


def test_every_perturber_takes_the_mass_models_field_to_the_scenarios_degree():
    """An ellipsoid body at gravity.degree 4: the Earth (a flyby) and the Moon (a table)."""
    from tumble_ros.core.torques.ephemeris import Ephemeris

    text = PARAMS.replace('    inertia: [0.64, 0.97, 1.0]\n', """    body:
      model: ellipsoid
      semi_axes: [0.217, 0.154, 0.147]
      density: 2600.0
    gravity:
      degree: 4
""")
    sc = parse_scenario(text)
    assert sc.gravity_field is not None and sc.gravity_field.degree >= 4
    moon = sc.perturbers[1]
    knots = np.linspace(-0.001, sc.duration + 0.001, 400)
    table = Ephemeris(tuple(knots), tuple(map(tuple, moon.source.position(knots))))
    sc = sc.replace(perturbers=(sc.perturbers[0], Perturber('moon', table, gm=moon.gm)))
    for component in sc.extra_torques:
        assert component.parameters[8] > 0          # the law reads the body's field
    four, two = simulate(sc), simulate(sc.replace(gravity_degree=2))
    assert four.success
    difference = np.max(np.abs(four.omega - two.omega)) / np.max(np.abs(two.omega))
    assert 0.0 < difference < 1e-6                  # an ellipsoid's degree 4: (a / R)^2 C_40


def test_a_perturber_named_moon_1_is_refused_for_its_name_not_its_kind():
    """Issue 48: the refusal blamed perturbers.moon-1.kind, a parameter the name could not key."""
    from tumble_ros.core import ScenarioError

    expected = (r'^perturbers\.names: each name must be an identifier \(letters, digits, _; a '
                r"parameter key\), got 'moon-1'$")
    with pytest.raises(ScenarioError, match=expected):
        Scenario.from_parameters({'orbit_rate': 0.0, 'perturbers.names': ['moon-1'],
                                  'perturbers.moon-1.kind': 'kepler'})
    with pytest.raises(ScenarioError, match=expected):
        Scenario.from_parameters({'orbit_rate': 0.0, 'perturbers.names': ['moon-1']})
    with pytest.raises(ValueError, match=expected):
        Perturber('moon-1', KeplerOrbit(gm=4902.800066, a=4e5))


def test_an_ephemeris_passing_inside_the_perturber_is_refused():
    """As a Kepler pericentre inside the Earth is: the table's closest approach, not a knot."""
    from tumble_ros.core.torques.ephemeris import Ephemeris

    orbit = KeplerOrbit.flyby(GM_EARTH, 7000.0, v_inf=6.0, t_p=0.001)
    t = np.linspace(0.0, 0.002, 400)
    x = orbit.position(t) * (6000.0 / 7000.0)            # the same path scaled to 6,000 km
    table = Ephemeris(tuple(t), tuple(map(tuple, x)))
    with pytest.raises(ValueError, match=r'^perturbers\.earth\.ephemeris_file: the table passes '
                                         r'6000 km from the perturber at t = 0\.001 yr, inside '
                                         r'its radius 6378\.137 km'):
        Perturber('earth', table, gm=GM_EARTH)
    assert Perturber('earth', table, gm=GM_EARTH, radius=5000.0).radius == 5000.0

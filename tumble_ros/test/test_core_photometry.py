"""
What a telescope sees (core/photometry): the brightness of the body and its synthetic lightcurve.

Proven against closed forms (the Lambert and the Lommel-Seeliger sphere's phase curves), against
an independent quadrature over the ellipsoid's analytic surface (a (u, v) grid with the analytic
normal and area element, no mesh), by the mesh's convergence to it at second order, by
invariances (turning body and directions together; swapping Sun and observer), and on a run: a
principal-axis rotator's lightcurve repeats every half turn, with two maxima per turn.
"""
import math

import numpy as np
import pytest

from tumble_ros.core import Scenario, simulate
from tumble_ros.core.model.rotation import (matrix_to_quaternion, quaternion_multiply,
                                            quaternion_to_matrix)
from tumble_ros.core.photometry import (aspect_angles, body_mesh, brightness, convex_mesh,
                                        ellipsoid_mesh, icosphere, LAWS, LightcurveSettings,
                                        magnitude, observer_geometry, phase_angle,
                                        reference_brightness, synthetic_lightcurve)
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.units import KM_PER_AU, SECONDS_PER_YEAR

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def phase_geometry(alpha):
    """Return (q, sun, observer) with the Sun along +x and the observer at phase ``alpha``."""
    alpha = np.asarray(alpha, dtype=float)
    sun = np.tile([1.0, 0.0, 0.0], (alpha.size, 1))
    observer = np.stack([np.cos(alpha), np.sin(alpha), np.zeros_like(alpha)], axis=1)
    return np.tile(IDENTITY, (alpha.size, 1)), sun, observer


def lambert_sphere(alpha):
    """Lambert sphere of radius 1: (2 pi / 3) (sin a + (pi - a) cos a) / pi."""
    return 2.0 * math.pi / 3.0 * (np.sin(alpha) + (math.pi - alpha) * np.cos(alpha)) / math.pi


def lommel_seeliger_sphere(alpha):
    """Lommel-Seeliger sphere of radius 1: (pi / 2) (1 - sin(a/2) tan(a/2) ln cot(a/4))."""
    half = alpha / 2.0
    return math.pi / 2.0 * (1.0 - np.sin(half) * np.tan(half) * np.log(1.0 / np.tan(alpha / 4.0)))


ALPHAS = np.array([0.1, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0])


@pytest.mark.parametrize('name, closed_form', [('lambert', lambert_sphere),
                                               ('lommel_seeliger', lommel_seeliger_sphere)])
def test_the_sphere_follows_its_closed_form_phase_curve_at_second_order(name, closed_form):
    q, sun, observer = phase_geometry(ALPHAS)
    errors = []
    for k in (3, 4, 5):
        b = brightness(q, sun, observer, ellipsoid_mesh((1.0, 1.0, 1.0), k), name)
        errors.append(np.max(np.abs(b - closed_form(ALPHAS))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:])) / 1.0   # h halves per level
    assert errors[-1] < 2e-3 * closed_form(np.array([0.1]))[0]
    assert np.all((orders > 1.8) & (orders < 2.2)), orders


def test_the_reference_is_the_zero_phase_sphere_of_the_same_volume():
    mesh = ellipsoid_mesh((1.0, 1.0, 1.0), 5)
    r2 = mesh.equivalent_radius ** 2
    assert reference_brightness(mesh, 'lambert') == pytest.approx(2.0 * math.pi / 3.0 * r2,
                                                                  rel=1e-13)
    assert reference_brightness(mesh, 'lommel_seeliger') == pytest.approx(math.pi / 2.0 * r2,
                                                                          rel=1e-13)
    assert reference_brightness(mesh, 'kaasalainen') == pytest.approx(
        (math.pi / 2.0 + 0.1 * 2.0 * math.pi / 3.0) * r2, rel=1e-13)
    q, sun, observer = phase_geometry(np.array([0.0]))
    m = magnitude(brightness(q, sun, observer, mesh, 'lambert'),
                  reference_brightness(mesh, 'lambert'))
    assert abs(m[0]) < 2e-3       # a sphere at opposition, 1 au from Sun and observer: m = 0


def ellipsoid_quadrature(axes, sun, observer, law, n_u=2400, n_v=1200):
    """
    Brightness of the ellipsoid by the midpoint rule over its parametric surface.

    r(u, v) = (a sin v cos u, b sin v sin u, c cos v); outward normal along (x/a^2, y/b^2, z/c^2);
    dA = |r_u x r_v| du dv: the analytic surface, no mesh.
    """
    a, b, c = axes
    u = (np.arange(n_u) + 0.5) * 2.0 * math.pi / n_u
    v = (np.arange(n_v) + 0.5) * math.pi / n_v
    uu, vv = np.meshgrid(u, v, indexing='ij')
    su, cu, sv, cv = np.sin(uu), np.cos(uu), np.sin(vv), np.cos(vv)
    normal = np.stack([sv * cu / a, sv * su / b, cv / c], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    area = sv * np.sqrt((b * c * sv * cu) ** 2 + (a * c * sv * su) ** 2 + (a * b * cv) ** 2)
    area *= (2.0 * math.pi / n_u) * (math.pi / n_v)
    mu0 = normal @ np.asarray(sun)
    mu = normal @ np.asarray(observer)
    seen = (mu0 > 0) & (mu > 0)
    mu0, mu = np.where(seen, mu0, 0.0), np.where(seen, mu, 0.0)
    return float(np.sum(area * LAWS[law](mu0, mu)))


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


GEOMETRIES = [  # (sun, observer) in body axes
    (unit([1.0, 0.0, 0.0]), unit([1.0, 0.0, 0.0])),
    (unit([1.0, 0.3, 0.2]), unit([0.2, 1.0, -0.4])),
    (unit([0.3, -0.5, 0.8]), unit([-0.6, 0.1, 0.7])),
    (unit([0.0, 0.0, 1.0]), unit([0.9, 0.0, 0.5])),
]


@pytest.mark.parametrize('law', sorted(LAWS))
def test_the_ellipsoid_mesh_converges_to_the_quadrature_over_the_analytic_surface(law):
    axes = (1.0, 0.7, 0.45)
    sun = np.array([g[0] for g in GEOMETRIES])
    observer = np.array([g[1] for g in GEOMETRIES])
    q = np.tile(IDENTITY, (len(GEOMETRIES), 1))
    exact = np.array([ellipsoid_quadrature(axes, s, o, law) for s, o in GEOMETRIES])
    errors = [np.max(np.abs(brightness(q, sun, observer, ellipsoid_mesh(axes, k), law) / exact
                            - 1.0)) for k in (3, 4, 5)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1.5e-3, errors
    assert errors[1] / errors[2] > 3.0, errors        # second order: the error quarters


def random_rotation(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.mark.parametrize('law', sorted(LAWS))
def test_turning_body_and_directions_together_changes_nothing(law):
    rng = np.random.default_rng(29)
    mesh = ellipsoid_mesh((1.0, 0.6, 0.4), 3)
    n = 50
    q = np.array([random_rotation(rng) for _ in range(n)])
    sun = np.array([unit(rng.normal(size=3)) for _ in range(n)])
    observer = np.array([unit(rng.normal(size=3)) for _ in range(n)])
    turn = random_rotation(rng)
    rot = quaternion_to_matrix(turn)
    turned_q = np.array([quaternion_multiply(turn, x) for x in q])
    before = brightness(q, sun, observer, mesh, law)
    after = brightness(turned_q, sun @ rot.T, observer @ rot.T, mesh, law)
    np.testing.assert_allclose(after, before, rtol=1e-12, atol=1e-14)
    assert np.ptp(before) > 0.1 * before.max()   # the attitudes do matter


@pytest.mark.parametrize('law', sorted(LAWS))
def test_swapping_sun_and_observer_changes_nothing_for_symmetric_laws(law):
    rng = np.random.default_rng(7)
    mesh = ellipsoid_mesh((1.0, 0.8, 0.5), 3)
    q = np.array([random_rotation(rng) for _ in range(40)])
    sun = np.array([unit(rng.normal(size=3)) for _ in range(40)])
    observer = np.array([unit(rng.normal(size=3)) for _ in range(40)])
    np.testing.assert_allclose(brightness(q, observer, sun, mesh, law),
                               brightness(q, sun, observer, mesh, law), rtol=1e-13, atol=1e-15)


def test_a_principal_axis_rotator_repeats_every_half_turn_with_two_maxima_per_turn():
    rate = 40.0                                    # rad/yr about the largest moment, z
    period = 2.0 * math.pi / rate
    per_turn = 200
    sc = Scenario(inertia=(2.0, 3.0, 4.0), orbit_rate=0.0, omega0=(0.0, 0.0, rate),
                  euler0=(0.0, 0.0, 0.0), duration=2.0 * period,
                  output_interval=period / per_turn)
    t = np.arange(2 * per_turn + 1) * (period / per_turn)
    run = simulate(sc, t_eval=t)
    settings = LightcurveSettings(law='lommel_seeliger', sun=(1.0, 0.0, 0.0),
                                  observer=(1.0, 0.3, 0.0))
    record = synthetic_lightcurve(sc, t, run.quaternion, settings)
    b = record.brightness
    half = per_turn // 2
    np.testing.assert_allclose(b[half:], b[:-half], rtol=1e-8)
    quarter = per_turn // 4
    assert np.max(np.abs(b[quarter:] - b[:-quarter])) > 0.2 * b.max()
    turn = b[:per_turn]
    maxima = np.sum((turn > np.roll(turn, 1)) & (turn > np.roll(turn, -1)))
    assert maxima == 2
    # the observer and the Sun lie in the body's equator throughout: latitude 0
    assert np.max(np.abs(record.sun_aspect[:, 0])) < 1e-8
    assert np.max(np.abs(record.observer_aspect[:, 0])) < 1e-8


def test_aspect_angles_are_latitude_and_longitude_in_body_axes():
    # the body turned by 90 deg about the inertial z: body x is inertial y
    q = matrix_to_quaternion(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    directions = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], unit([0.0, 1.0, 1.0])])
    angles = aspect_angles(np.tile(q, (3, 1)), directions)
    np.testing.assert_allclose(angles, [[0.0, 0.0], [0.0, math.pi / 2.0],
                                        [math.pi / 4.0, 0.0]], atol=1e-15)
    assert phase_angle([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]) == pytest.approx(math.pi)


def test_magnitude_adds_the_distance_modulus_and_is_infinite_without_light():
    m = magnitude(np.array([1.0, 10.0, 0.0]), 1.0, np.array([2.0, 1.0, 1.0]),
                  np.array([5.0, 1.0, 1.0]))
    np.testing.assert_allclose(m[:2], [5.0 * math.log10(10.0), -2.5], rtol=1e-15)
    assert m[2] == math.inf


def test_a_body_seen_from_behind_is_dark():
    q, sun, observer = phase_geometry(np.array([math.pi]))
    assert brightness(q, sun, observer, ellipsoid_mesh((1.0, 0.5, 0.3), 3), 'lambert')[0] == 0.0


def test_the_icosphere_has_the_expected_counts_and_a_closed_convex_surface():
    for k in range(4):
        v, f = icosphere(k)
        assert (v.shape[0], f.shape[0]) == (10 * 4**k + 2, 20 * 4**k)
        mesh = convex_mesh(v, f)
        # closed: the outward normals weighted by area sum to zero
        assert np.max(np.abs(mesh.areas @ mesh.normals)) < 1e-13
        convex_mesh(v * np.array([1.0, 0.7, 0.45]), f)     # checked: no error
    mesh = ellipsoid_mesh((1.0, 0.7, 0.45), 5)
    assert mesh.volume == pytest.approx(4.0 / 3.0 * math.pi * 1.0 * 0.7 * 0.45, rel=1e-3)


def test_a_concave_mesh_is_refused():
    v, f = icosphere(2)
    for depth in (0.5, 0.05):          # (the sagitta of these facets is ~0.01)
        dented = v.copy()
        dented[0] *= 1.0 - depth       # push one vertex in: a dimple
        with pytest.raises(ValueError, match='not convex'):
            convex_mesh(dented, f)
    rounded = np.round(v * np.array([1.0, 0.7, 0.45]), 7)   # printed to 7 decimals: accepted
    convex_mesh(rounded, f)


def test_facets_given_inward_are_turned_outward():
    v, f = icosphere(1)
    mesh = convex_mesh(v, f[:, ::-1])
    centroids = v[mesh.facets].mean(axis=1)
    assert np.all(np.einsum('ij,ij->i', centroids, mesh.normals) > 0)


def test_a_body_that_cannot_exist_has_no_lightcurve():
    with pytest.raises(ValueError, match='inertia: .*triangle inequality'):
        body_mesh((1.0, 1.0, 3.0))
    sc = Scenario(inertia=(1.0, 1.0, 3.0), allow_unphysical_inertia=True)
    with pytest.raises(ValueError, match='inertia'):
        synthetic_lightcurve(sc, [0.0], [IDENTITY])


@pytest.mark.parametrize('changes, match', [
    ({'law': 'hapke'}, 'lightcurve.law'),
    ({'observer': (0.0, float('nan'), 0.0)}, 'lightcurve.observer'),
    ({'sun': (0.0, 0.0, 0.0)}, 'lightcurve.sun'),
    ({'light_time': 'yes'}, 'lightcurve.light_time'),
    ({'subdivisions': 9}, 'lightcurve.subdivisions'),
])
def test_bad_settings_are_refused_naming_the_field(changes, match):
    with pytest.raises(ValueError, match=match):
        LightcurveSettings(**changes)


def test_settings_round_trip_through_parameters():
    s = LightcurveSettings(law='lambert', observer=(0.0, 0.0, 2.0), light_time=True)
    assert s.observer == (0.0, 0.0, 1.0)
    assert LightcurveSettings.from_parameters(s.to_parameters()) == s
    with pytest.raises(ValueError, match='lightcurve.colour'):
        LightcurveSettings.from_parameters({'lightcurve.colour': 'red'})


def test_on_the_circular_orbit_the_sun_is_the_torques_and_the_observer_follows_it():
    sc = Scenario()
    t = np.linspace(0.0, 2.0, 5)
    g = observer_geometry(sc, t, LightcurveSettings())
    expected = np.stack([np.sin(t), np.cos(t), 0 * t], axis=1)     # orbit_rate 1 rad/yr
    np.testing.assert_allclose(g.sun, expected, atol=1e-15)
    np.testing.assert_allclose(g.observer, expected, atol=1e-15)  # default: zero phase
    # R0 = (GM_sun / ws^2)^(1/3) with ws = 1 rad/yr: (2 pi)^(2/3) au (Kepler's third law)
    np.testing.assert_allclose(g.sun_distance, (2.0 * math.pi) ** (2.0 / 3.0), rtol=2e-4)
    fixed = observer_geometry(sc, t, LightcurveSettings(observer=(0.0, 0.0, 1.0)))
    np.testing.assert_allclose(phase_angle(fixed.sun, fixed.observer), math.pi / 2.0)


def test_in_a_flyby_the_observer_is_on_the_perturber_and_light_time_delays_the_stamps():
    orbit = KeplerOrbit.flyby(398600.4418, 38326.0, v_inf=5.84, t_p=72.0 / 8766.0)
    sc = Scenario(inertia=(0.64, 0.97, 1.0), orbit_rate=0.0, orbit=orbit,
                  omega0=(0.0, 0.0, 50.0), duration=144.0 / 8766.0, output_interval=1.0 / 8766.0)
    t = np.linspace(0.0, sc.duration, 7)
    settings = LightcurveSettings(sun=(1.0, 0.0, 0.0), light_time=True)
    g = observer_geometry(sc, t, settings)
    position = orbit.position(t)
    distance = np.linalg.norm(position, axis=1)
    np.testing.assert_allclose(g.observer, position / distance[:, None], atol=1e-15)
    np.testing.assert_allclose(g.observer_distance, distance / KM_PER_AU, rtol=1e-15)
    np.testing.assert_allclose(g.sun, np.tile([1.0, 0.0, 0.0], (7, 1)))
    q = np.tile(IDENTITY, (7, 1))
    record = synthetic_lightcurve(sc, t, q, settings)
    delay = distance / 299792.458                                       # s
    np.testing.assert_allclose(record.light_time, delay, rtol=1e-15)
    np.testing.assert_allclose(record.t, t + delay / SECONDS_PER_YEAR, rtol=0, atol=1e-18)
    plain = synthetic_lightcurve(sc, t, q, LightcurveSettings(sun=(1.0, 0.0, 0.0)))
    np.testing.assert_array_equal(plain.t, t)
    np.testing.assert_array_equal(plain.light_time, record.light_time)   # given either way
    np.testing.assert_array_equal(plain.brightness, record.brightness)
    # the body's axes are the inertial ones (q = 1): the aspects are the directions' own angles
    direction = position / distance[:, None]
    np.testing.assert_allclose(record.observer_aspect[:, 0], np.arcsin(direction[:, 2]),
                               atol=1e-14)
    np.testing.assert_allclose(record.observer_aspect[:, 1],
                               np.arctan2(direction[:, 1], direction[:, 0]), atol=1e-14)
    np.testing.assert_allclose(record.sun_aspect, 0.0, atol=1e-15)
    # the distance modulus: 5 log10(r delta) with r = 1 au and delta [au]
    reference = reference_brightness(body_mesh(sc.inertia), settings.law)
    expected = (-2.5 * np.log10(record.brightness / reference)
                + 5.0 * np.log10(distance / KM_PER_AU))
    np.testing.assert_allclose(record.magnitude, expected, rtol=1e-13)


def test_a_sample_comes_out_the_same_bit_for_bit_in_any_block():
    # the live simulator's batches and the offline writer's differ; their samples must not
    rng = np.random.default_rng(3)
    mesh = ellipsoid_mesh((1.0, 0.6, 0.4), 4)
    n = 300
    q = np.array([random_rotation(rng) for _ in range(n)])
    sun = np.array([unit(rng.normal(size=3)) for _ in range(n)])
    observer = np.array([unit(rng.normal(size=3)) for _ in range(n)])
    whole = brightness(q, sun, observer, mesh, 'kaasalainen')
    for start, stop in ((0, 1), (7, 8), (5, 37), (100, 300)):
        part = brightness(q[start:stop], sun[start:stop], observer[start:stop], mesh,
                          'kaasalainen')
        np.testing.assert_array_equal(part, whole[start:stop])


def test_the_lightcurve_parameters_are_the_scenarios_and_refused_naming_the_field():
    from tumble_ros.core import parse_scenario, ScenarioError
    text = ('/**/sim:\n  ros__parameters:\n    lightcurve:\n      law: lambert\n'
            '      observer: [0.0, 0.0, 3.0]\n      light_time: true\n')
    scenario = parse_scenario(text)
    assert scenario.lightcurve == LightcurveSettings(law='lambert', observer=(0.0, 0.0, 1.0),
                                                     light_time=True)
    assert Scenario.from_parameters(scenario.to_parameters()) == scenario
    with pytest.raises(ScenarioError, match='lightcurve.law: must be one of'):
        Scenario.from_parameters({'lightcurve.law': 'hapke'})
    with pytest.raises(ScenarioError, match='lightcurve.colour: unknown'):
        Scenario.from_parameters({'lightcurve.colour': 'red'})


def test_a_heliocentric_kepler_orbit_places_the_sun_and_no_torque_takes_the_fixed_sun():
    orbit = KeplerOrbit(gm=1.3271244e11, a=1.5e8, e=0.3)      # the Sun's GM: the Sun moves
    sc = Scenario(orbit_rate=0.0, orbit=orbit)
    t = np.linspace(0.0, 1.0, 6)
    g = observer_geometry(sc, t, LightcurveSettings(observer=(1.0, 0.0, 0.0)))
    position = orbit.position(t)
    distance = np.linalg.norm(position, axis=1)
    np.testing.assert_allclose(g.sun, position / distance[:, None], atol=1e-15)
    np.testing.assert_allclose(g.sun_distance, distance / KM_PER_AU, rtol=1e-15)
    np.testing.assert_allclose(g.observer, np.tile([1.0, 0.0, 0.0], (6, 1)))
    np.testing.assert_allclose(g.observer_distance, 1.0)
    free = observer_geometry(Scenario(orbit_rate=0.0), t, LightcurveSettings(sun=(0.0, 0.0, 2.0)))
    np.testing.assert_allclose(free.sun, np.tile([0.0, 0.0, 1.0], (6, 1)))
    np.testing.assert_allclose(free.observer, free.sun)       # default: along the Sun

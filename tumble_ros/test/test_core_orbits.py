"""
Kepler orbits of the torquing body (core/torques/orbits.py) and their tidal torque.

Checked on identities (Kepler's equation, the anomalies' round trip), against a direct two-body
integration, against the brute-force torque of point masses at the orbit's varying distance,
against the built-in circular orbit (e = 0), and through a hyperbolic flyby (the change of the
inertial angular momentum equals the quadrature of the torque along the trajectory).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_core_torque import point_cloud

from tumble_ros.core import IntegratorSettings, Scenario, simulate
from tumble_ros.core.dynamics import angular_momentum_orbital
from tumble_ros.core.rotation import quaternion_to_matrix
from tumble_ros.core.torques.orbits import (eccentric_anomaly, hyperbolic_anomaly, KeplerOrbit,
                                            orbit_state)

RNG = np.random.default_rng(29)


@pytest.mark.parametrize('e', [0.0, 0.3, 0.9, 0.99])
def test_keplers_equation_is_solved_to_rounding_for_ellipses(e):
    mean = np.concatenate([np.linspace(-30.0, 30.0, 4001), RNG.uniform(-1e-3, 1e-3, 200)])
    big = np.array([eccentric_anomaly(m, e) for m in mean])
    assert np.max(np.abs(big - e * np.sin(big) - mean)) < 1e-14 * 40


@pytest.mark.parametrize('e', [1.000001, 1.2, 3.0, 50.0])
def test_keplers_equation_is_solved_to_rounding_for_hyperbolas(e):
    mean = np.concatenate([np.linspace(-800.0, 800.0, 4001), RNG.uniform(-1e-4, 1e-4, 200)])
    h = np.array([hyperbolic_anomaly(m, e) for m in mean])
    residual = np.abs(e * np.sinh(h) - h - mean) / np.maximum(1.0, np.abs(mean))
    assert np.max(residual) < 1e-14


@pytest.mark.parametrize('e', [0.2, 0.95, 1.5])
def test_the_anomalies_round_trip(e):
    orbit = KeplerOrbit(gm=4.0, a=2.0, e=e, t_p=0.3, lambda_p=0.7)
    t = np.linspace(-3.0, 3.0, 301)
    distance, angle = orbit.state(t)
    nu = angle - orbit.lambda_p
    if e < 1:
        big = 2 * np.arctan2(np.sqrt(1 - e) * np.sin(nu / 2), np.sqrt(1 + e) * np.cos(nu / 2))
        mean = big - e * np.sin(big)
        expected = orbit.mean_motion * (t - orbit.t_p)
        np.testing.assert_allclose(np.angle(np.exp(1j * (mean - expected))), 0, atol=1e-12)
        np.testing.assert_allclose(distance, orbit.a * (1 - e * np.cos(big)), rtol=1e-13)
        # the orbit equation r = a (1 - e^2) / (1 + e cos nu)
        np.testing.assert_allclose(distance, orbit.a * (1 - e * e) / (1 + e * np.cos(nu)),
                                   rtol=1e-12)
        assert np.all(np.diff(angle) > 0)                      # lambda continuous, increasing
    else:
        h = 2 * np.arctanh(np.sqrt((e - 1) / (e + 1)) * np.tan(nu / 2))
        np.testing.assert_allclose(e * np.sinh(h) - h, orbit.mean_motion * (t - orbit.t_p),
                                   rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(distance, orbit.a * (e * e - 1) / (1 + e * np.cos(nu)),
                                   rtol=1e-12)


@pytest.mark.parametrize('e, span', [(0.0, 7.0), (0.6, 7.0), (0.97, 7.0), (2.5, 4.0)])
def test_the_orbit_is_the_two_body_motion(e, span):
    """Integrate r'' = -GM r / r^3 from pericentre and compare positions (independent)."""
    orbit = KeplerOrbit(gm=9.0, a=1.5, e=e, t_p=0.0, lambda_p=0.4)
    rp = orbit.pericentre
    vp = math.sqrt(orbit.gm * (1 + e) / rp)
    lam = orbit.lambda_p
    y0 = [rp * math.sin(lam), rp * math.cos(lam), vp * math.cos(lam), -vp * math.sin(lam)]

    def two_body(t, y):
        r3 = math.hypot(y[0], y[1]) ** 3
        return [y[2], y[3], -orbit.gm * y[0] / r3, -orbit.gm * y[1] / r3]

    times = np.linspace(0.0, span, 200)
    sol = solve_ivp(two_body, (0.0, span), y0, method='DOP853', rtol=1e-13, atol=1e-13,
                    t_eval=times)
    position = orbit.position(times)[:, :2]
    scale = np.max(np.hypot(*sol.y[:2]))
    assert np.max(np.abs(position - sol.y[:2].T)) < 1e-9 * scale


def test_the_torque_is_the_sum_over_point_masses_at_the_varying_distance():
    m, r, inertia = point_cloud(300)
    orbit = KeplerOrbit(gm=2.0e15, a=2.0e5, e=0.5, t_p=0.0, lambda_p=0.3)
    component = orbit.torque_component(inertia)
    for t in (0.0, 0.13, 0.5 / orbit.mean_motion * math.pi):
        q = RNG.normal(size=4)
        q /= np.linalg.norm(q)
        c = quaternion_to_matrix(q)                         # body -> orbital
        sun = c.T @ orbit.position([t])[0]                  # the perturber in body axes
        d = sun - r
        g = orbit.gm * d / np.linalg.norm(d, axis=1)[:, None] ** 3
        brute = np.sum(np.cross(r, m[:, None] * g), axis=0)
        torque = component.torque(t, q)
        assert np.linalg.norm(torque) > 0
        np.testing.assert_allclose(torque, brute, rtol=2e-4, atol=2e-4 * np.linalg.norm(brute))
    # the distance really varies along this orbit: a factor 3 between peri- and apocentre
    distance, _ = orbit.state(np.linspace(0, 2 * math.pi / orbit.mean_motion, 50))
    assert distance.max() / distance.min() > 2.9


@pytest.mark.parametrize('method', ['dop853', 'splitting6'])
def test_a_circular_kepler_orbit_is_the_built_in_circular_orbit(method):
    inertia, ws = (1.0, 1.3, 1.8), 2.0
    settings = IntegratorSettings(method=method, rtol=1e-12, atol=1e-12, step=1e-3)
    circular = Scenario(inertia=inertia, orbit_rate=ws, omega0=(1.0, -2.0, 20.0), duration=1.0,
                        output_interval=0.05, integrator=settings)
    orbit = KeplerOrbit(gm=ws * ws, a=1.0, e=0.0)
    kepler = circular.replace(orbit_rate=0.0, torques=(orbit.torque_component(inertia),))
    a, b = simulate(circular), simulate(kepler)
    np.testing.assert_allclose(b.omega, a.omega, rtol=0, atol=1e-9)
    assert np.max(np.abs(a.omega - simulate(circular.replace(orbit_rate=0.0)).omega)) > 1e-2


def test_a_flyby_changes_the_angular_momentum_by_the_integral_of_the_torque():
    """Delta L (inertial) = integral of C(q) M dt along the trajectory, by quadrature."""
    inertia = (1.0, 1.4, 2.0)
    orbit = KeplerOrbit(gm=4.0e6, a=20.0, e=4.0, t_p=0.5, lambda_p=1.0)   # pericentre 60
    component = orbit.torque_component(inertia)
    sc = Scenario(inertia=inertia, orbit_rate=0.0, omega0=(3.0, -1.0, 40.0),
                  euler0=(0.3, 0.2, 0.8), duration=1.0, output_interval=1e-4,
                  torques=(component,),
                  integrator=IntegratorSettings(method='dop853', rtol=1e-12, atol=1e-12))
    r = simulate(sc)
    assert r.success
    c = np.array([quaternion_to_matrix(q) for q in r.quaternion])
    momentum = angular_momentum_orbital(r.omega, c, np.array(inertia))
    torque_orbital = np.array([ck @ component.torque(t, q)
                               for t, q, ck in zip(r.t, r.quaternion, c)])
    # Simpson's rule on the 10,001 samples (the flyby lasts ~0.1 yr: ~1000 samples)
    from scipy.integrate import simpson
    integral = simpson(torque_orbital, x=r.t, axis=0)
    change = momentum[-1] - momentum[0]
    assert np.linalg.norm(change) > 1e-3 * np.linalg.norm(momentum[0])   # the flyby matters
    np.testing.assert_allclose(change, integral, rtol=0,
                               atol=1e-6 * np.linalg.norm(momentum[0]))


@pytest.mark.parametrize('field, value, match', [
    ('gm', 0.0, 'orbit.gm'), ('a', -1.0, 'orbit.a'), ('e', 1.0, 'parabolic'),
    ('e', 0.995, 'orbit.e'), ('t_p', math.nan, 'orbit.t_p'),
])
def test_bad_orbits_are_refused_naming_the_field(field, value, match):
    fields = {'gm': 1.0, 'a': 1.0, 'e': 0.1}
    fields[field] = value
    with pytest.raises(ValueError, match=match):
        KeplerOrbit(**fields)


def test_orbit_state_gives_the_circular_direction_at_e_0():
    for t in (0.0, 0.3, 2.9):
        distance, angle = orbit_state(t, 4.0, 1.0, 0.0, 0.0, 0.0)
        assert distance == pytest.approx(1.0, abs=1e-15)
        assert angle == pytest.approx(2.0 * t, abs=1e-12)       # n = sqrt(GM / a^3) = 2


def test_the_scenarios_orbit_section_round_trips_and_runs():
    from tumble_ros.core import dump_scenario, parse_scenario

    orbit = KeplerOrbit(gm=4.0, a=1.0, e=0.0)
    circular = Scenario(inertia=(1.0, 1.3, 1.8), orbit_rate=2.0, omega0=(1.0, -2.0, 20.0),
                        duration=0.5, output_interval=0.05)
    kepler = circular.replace(orbit_rate=0.0, orbit=orbit)
    assert parse_scenario(dump_scenario(kepler)) == kepler
    params = kepler.to_parameters()
    assert params['orbit.kind'] == 'kepler' and params['orbit.gm'] == 4.0
    assert Scenario.from_parameters(params) == kepler
    assert Scenario.from_parameters(circular.to_parameters()).orbit is None
    np.testing.assert_allclose(simulate(kepler).omega, simulate(circular).omega, rtol=0,
                               atol=1e-9)
    assert [t.name for t in kepler.extra_torques] == ['kepler_orbit']


@pytest.mark.parametrize('params, match', [
    ({'orbit.e': 0.5}, r'^orbit\.e: is used only with orbit\.kind: kepler'),
    ({'orbit.kind': 'kepler'}, r'^orbit_rate: must be 0 with a Kepler orbit'),
    ({'orbit.kind': 'kepler', 'orbit_rate': 0.0, 'orbit.e': 1.0}, r'^orbit\.e: .*parabolic'),
    ({'orbit.kind': 'elliptic'}, r'^orbit\.kind: must be one of'),
])
def test_a_bad_orbit_section_is_refused_naming_the_field(params, match):
    from tumble_ros.core import ScenarioError

    with pytest.raises(ScenarioError, match=match):
        Scenario.from_parameters(params)


def test_the_analytic_models_say_they_do_not_apply_to_a_kepler_orbit():
    from tumble_ros.core import applicability, make_model, ModelNotApplicable

    sc = Scenario(orbit_rate=0.0, orbit=KeplerOrbit(gm=1.0, a=1.0, e=0.3))
    reasons = applicability(sc)
    assert reasons and all('circular orbit' in why and 'kepler_orbit' in why
                           for why in reasons.values())
    with pytest.raises(ModelNotApplicable, match='kepler_orbit'):
        make_model('paper', sc)


def test_an_ensemble_runs_the_orbit_too():
    from tumble_ros.core import simulate_ensemble

    sc = Scenario(inertia=(1.0, 1.3, 1.8), orbit_rate=0.0, omega0=(1.0, -2.0, 20.0),
                  duration=0.3, output_interval=0.1,
                  orbit=KeplerOrbit(gm=4.0, a=1.0, e=0.6, t_p=0.1),
                  integrator=IntegratorSettings(method='splitting6', step=1e-3))
    ens = simulate_ensemble(sc, n_bodies=2, omega0=[sc.omega0, (0.5, 0.5, 10.0)])
    np.testing.assert_allclose(ens.omega[0], simulate(sc).omega, rtol=0, atol=1e-10)
    free = simulate(sc.replace(orbit=None))
    assert np.max(np.abs(ens.omega[0] - free.omega)) > 1e-3

"""
Coupled orbit and attitude (core/propagation/coupled.py) through the Apophis flyby.

Apophis as a homogeneous ellipsoid of moments 0.64 : 0.97 : 1 (config/apophis_2029.yaml), volume-
equivalent radius 0.17 km (diameter 340 m), density 2.6 g/cm^3 (mass 5.35e10 kg). Checked: the
body's field (its reaction on the orbit) is the gradient of MacCullagh's potential; the total
energy and angular momentum are conserved while the spin and the orbit exchange them; the
point-mass limit is the fixed hyperbola, against an independent integration; the size of the
coupling.
"""
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tumble_ros.core import load_scenario, simulate
from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.model.gravity_field import GravityField, principal_frame
from tumble_ros.core.propagation.coupled import CoupledBody, field_potential, propagate_coupled
from tumble_ros.core.torques.multipole import field_acceleration
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.torques.perturbers import Perturber
from tumble_ros.core.units import SECONDS_PER_YEAR

APOPHIS = load_scenario(Path(__file__).resolve().parents[1] / 'config' / 'apophis_2029.yaml')
G = 6.6743e-20                                     # km^3 / (kg s^2), CODATA 2018
#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 2029


def apophis_body(degree: int = 2) -> CoupledBody:
    """Return Apophis as a homogeneous ellipsoid (module docstring)."""
    moments = np.asarray(APOPHIS.inertia)
    semi = np.sqrt(moments.sum() - 2.0 * moments)          # a^2 ~ Iy + Iz - Ix, ...
    semi *= 0.17 / np.prod(semi) ** (1.0 / 3.0)
    mass = 2.6e12 * 4.0 / 3.0 * np.pi * np.prod(semi)      # kg (2.6e12 kg/km^3)
    return CoupledBody.ellipsoid(G * mass, semi, degree)


@pytest.fixture(scope='module')
def runs():
    body = apophis_body()
    return body, propagate_coupled(APOPHIS, body), propagate_coupled(APOPHIS, body,
                                                                     coupled=False)


def test_the_potential_is_maccullaghs_at_degree_2_and_its_gradient_the_field():
    """The energy's potential against MacCullagh's formula, its gradient against the force."""
    rng = np.random.default_rng(SEED)
    acceleration = python_source(field_acceleration)
    m = rng.uniform(0.5, 1.5, 60) * 1e9
    r, moments, _ = principal_frame(m, rng.normal(size=(60, 3)) * [0.2, 0.15, 0.1])
    radius = float(np.max(np.linalg.norm(r, axis=1)))
    for degree in (2, 4):
        field = GravityField.from_point_masses(m, r, degree, radius)
        packed = np.array(field.packed())
        packed[0] = 0.0                                   # beyond the monopole
        for _ in range(3):
            x = rng.normal(size=3) * 3.0
            h = 1e-30
            gradient = [np.imag(field_potential(*(x + 1j * h * np.eye(3)[k]), radius, degree,
                                                packed)) / h for k in range(3)]
            np.testing.assert_allclose(acceleration(*x, 1.0, radius, degree, packed, 0, 0),
                                       gradient, rtol=1e-11, atol=1e-14 * np.linalg.norm(gradient))
            if degree == 2:      # U_2 = -(tr A - 3 u.A u) / (2 R^3) per unit G m, A = I / m
                a = np.asarray(field.principal_moments) / field.mass
                u = x / np.linalg.norm(x)
                maccullagh = (a.sum() - 3.0 * u @ (a * u)) / (2.0 * np.linalg.norm(x) ** 3)
                assert np.real(field_potential(*x, radius, degree, packed)) == pytest.approx(
                    maccullagh, rel=1e-10)


def test_energy_and_angular_momentum_are_conserved_while_spin_and_orbit_exchange_them(runs):
    """
    The totals hold while the spin's and the orbit's parts change by far more.

    Measured 2026-12-04 (rtol 3e-14): |dE| / |E| = 1.1e-24, |dL| / |L| = 1.0e-24 (the totals are
    the orbit's); the exchanged parts: the spin's angular momentum changes by 9.33 km^2/yr per
    unit mass (37 % of it) and the orbit's by the opposite, the sum 3.7e-13 of |L_spin|; the
    spin energy changes by 51 % and the balance closes to 8.4e-13 of it.
    """
    body, coupled, _ = runs
    assert coupled.success
    spin_energy = 0.5 * np.sum(np.asarray(body.inertia_per_mass) * coupled.omega[0] ** 2)
    spin_momentum = np.linalg.norm(coupled.spin_momentum[0])
    assert np.max(np.abs(coupled.energy_change)) <= 1e-12 * abs(coupled.energy)
    assert np.max(np.abs(coupled.momentum_change)) <= 1e-12 * coupled.momentum
    # the balance resolves the exchange: each part changes by far more than the sum does
    exchanged = np.linalg.norm(coupled.spin_momentum[-1] - coupled.spin_momentum[0])
    assert exchanged > 0.3 * spin_momentum
    np.testing.assert_allclose(coupled.orbit_momentum[-1],
                               -(coupled.spin_momentum[-1] - coupled.spin_momentum[0]),
                               rtol=0, atol=1e-12 * spin_momentum)
    assert np.max(np.linalg.norm(coupled.momentum_change, axis=1)) < 1e-12 * spin_momentum
    assert abs(coupled.spin_energy[-1]) > 0.1 * spin_energy
    assert np.max(np.abs(coupled.energy_change)) < 2e-12 * spin_energy


def test_without_coupling_the_spin_is_the_fixed_hyperbolas(runs):
    _, _, uncoupled = runs
    fixed = simulate(APOPHIS)
    scale = np.linalg.norm(fixed.omega, axis=1)
    # the project's integrators at rtol 1e-11: measured 2.6e-11
    assert np.max(np.linalg.norm(uncoupled.omega - fixed.omega, axis=1) / scale) < 1e-10
    np.testing.assert_array_equal(uncoupled.deviation, 0.0)


def test_the_point_mass_limit_is_the_fixed_hyperbola():
    """Degree 0: Encke's deviation stays 0; an independent Cowell integration agrees."""
    point = propagate_coupled(APOPHIS, apophis_body(degree=0))
    orbit = APOPHIS.orbit
    np.testing.assert_array_equal(point.deviation, 0.0)
    np.testing.assert_array_equal(point.position, orbit.position(point.t))
    gm = orbit.gm_per_yr2

    def two_body(t, y):
        return np.concatenate([y[3:], -gm * y[:3] / np.linalg.norm(y[:3]) ** 3])

    y0 = np.concatenate([orbit.position([0.0])[0], orbit.velocity([0.0])[0] * SECONDS_PER_YEAR])
    cowell = solve_ivp(two_body, (0.0, point.t[-1]), y0, method='DOP853', t_eval=point.t,
                       rtol=1e-13, atol=1e-9)
    distance = np.linalg.norm(point.position, axis=1)
    error = np.linalg.norm(cowell.y[:3].T - point.position, axis=1) / distance
    assert np.max(error) < 1e-11          # measured 2026-12-04: 2.1e-13
    # and the spin is torque-free: |L| and the energy constant
    a = np.asarray(point.spin_momentum)
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), np.linalg.norm(a[0]), rtol=1e-12)


def test_the_coupling_of_apophis_is_tiny(runs):
    """
    The orbit moves by ~1 mm from the hyperbola; the spin after the flyby changes by ~5e-13.

    Measured 2026-12-04: max |dR| = 1.19e-6 km; |w_coupled - w_fixed| / |w| = 4.4e-13 at the end
    (7.5e-13 at most; the final difference the same to 5 % at rtol 1e-11 ... 3e-14: resolved),
    against the flyby's own change of |w| by 30 %.
    """
    _, coupled, uncoupled = runs
    deviation = np.max(np.linalg.norm(coupled.deviation, axis=1))
    assert 1e-7 < deviation < 1e-5
    scale = np.linalg.norm(uncoupled.omega, axis=1)
    coupling = np.linalg.norm(coupled.omega - uncoupled.omega, axis=1) / scale
    assert 1e-14 < coupling[-1] < 1e-11


def test_a_scenario_with_more_than_one_torque_is_refused():
    moon = Perturber('moon', KeplerOrbit(gm=4902.800066, a=4e5, e=0.05))
    with pytest.raises(ValueError, match=r'^coupled: needs a scenario whose only torque is one '
                                         r"perturber.*\['kepler_orbit', 'moon'\]"):
        propagate_coupled(APOPHIS.replace(perturbers=(moon,)), apophis_body())
    with pytest.raises(ValueError, match=r'^coupled.degree: must be 0 \(a point mass\) or in '
                                         r'\[2, 2\]'):
        CoupledBody(apophis_body().field, degree=3)


def test_to_degree_4_the_totals_are_conserved_as_well():
    """
    The ellipsoid as 4,224 equal point masses on a grid, its field to degree 4.

    Measured 2026-12-04: the balance closes to 8.7e-13 of the spin energy and 4.2e-13 of the
    spin's angular momentum, as at degree 2; degree 4 moves the spin after the flyby by 1.7e-12
    of |w| from degree 2.
    """
    semi = np.sqrt(np.sum(APOPHIS.inertia) - 2.0 * np.asarray(APOPHIS.inertia))
    semi *= 0.17 / np.prod(semi) ** (1.0 / 3.0)
    grid = (np.arange(20) + 0.5) / 10.0 - 1.0
    points = np.stack(np.meshgrid(grid, grid, grid, indexing='ij'), -1).reshape(-1, 3)
    points = points[np.sum(points ** 2, axis=1) <= 1.0] * semi
    mass = np.full(len(points), apophis_body().field.mass / len(points))
    r, _, _ = principal_frame(mass, points)
    field = GravityField.from_point_masses(mass, r, 4, float(semi.max()))
    assert abs(field.C[4, 0]) > 1e-3                       # it has degree-4 moments
    runs = {degree: propagate_coupled(APOPHIS, CoupledBody(field, degree)) for degree in (2, 4)}
    four = runs[4]
    a = np.asarray(CoupledBody(field).inertia_per_mass)
    spin_energy = 0.5 * np.sum(a * four.omega[0] ** 2)
    spin_momentum = np.linalg.norm(four.spin_momentum[0])
    assert np.max(np.abs(four.energy_change)) <= 1e-12 * abs(four.energy)
    assert np.max(np.abs(four.energy_change)) < 2e-12 * spin_energy
    assert np.max(np.linalg.norm(four.momentum_change, axis=1)) < 1e-12 * spin_momentum
    change = np.linalg.norm(four.omega[-1] - runs[2].omega[-1]) / np.linalg.norm(four.omega[-1])
    assert 1e-14 < change < 1e-10


@pytest.mark.parametrize('gm, semi_axes, match', [
    (0.0, (0.2, 0.15, 0.1), r"^coupled\.gm: the asteroid's GM must be a finite number > 0 "
                            r'km\^3/s\^2, got 0\.0$'),
    (float('nan'), (0.2, 0.15, 0.1), r'^coupled\.gm: .*got nan$'),
    (1e-9, (0.0, 0.0, 0.0), r'^coupled\.semi_axes: must be 3 finite numbers > 0 km, got '
                            r'\(0\.0, 0\.0, 0\.0\)$'),
    (1e-9, (0.2, 0.15), r'^coupled\.semi_axes: must be 3 '),
])
def test_a_body_of_gm_0_or_semi_axes_0_is_refused_naming_it(gm, semi_axes, match):
    """Issue 48: these were a ZeroDivisionError deep inside."""
    with pytest.raises(ValueError, match=match):
        CoupledBody.ellipsoid(gm, semi_axes)


def test_a_body_reaching_beyond_the_perigee_is_refused():
    """Issue 48: a body larger than its perigee distance (38,326 km) was integrated."""
    big = CoupledBody.ellipsoid(1e-9, (50000.0, 40000.0, 30000.0))
    with pytest.raises(ValueError, match=r"^coupled\.field: the body's reference radius 50000 km "
                                         r'.* inside the pericentre 38326 km'):
        propagate_coupled(APOPHIS, big)
    assert APOPHIS.orbit.pericentre == pytest.approx(38326.0)

"""The Jacobi integral of the circular-orbit problem (docs/paper.md, conventions)."""
import numpy as np

from tumble_ros.core import IntegratorSettings, jacobi_integral, Scenario, simulate
from tumble_ros.core.model.rotation import quaternion_to_matrix

# Paper Figs 7/8: a = 3, theta = 0.9, phi = 0.5, wx0 = wy0 = 0.1, wz0 = 30, ws = 1.
FIG7 = Scenario(inertia=(1.0, 1.0, 4.0), allow_unphysical_inertia=True, orbit_rate=1.0,
                omega0=(0.1, 0.1, 30.0), euler0=(0.5, 0.0, 0.9), duration=20.0,
                output_interval=0.01,
                integrator=IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-12))


def relative_drift(j):
    return np.max(np.abs(j - j[0])) / abs(j[0])


def test_jacobi_integral_conserved_over_20_years_fig7():
    r = simulate(FIG7)
    assert r.success, r.message
    assert relative_drift(r.jacobi) <= 1e-9
    # ... while the pieces it is made of change a thousand times more: the test could fail.
    energy = 0.5 * np.sum(r.omega**2 * np.array(FIG7.inertia), axis=1)
    assert relative_drift(energy) > 1e-6


def test_wrong_sign_of_the_orbital_term_is_not_conserved():
    """The orbit turns clockwise (R0 = [sin ws t, cos ws t, 0]): +ws (Iw).z', not -ws."""
    r = simulate(FIG7.replace(duration=2.0))
    c = np.array([quaternion_to_matrix(q) for q in r.quaternion])
    h = r.omega * np.array(FIG7.inertia)
    flipped = (jacobi_integral(r.t, r.omega, c, FIG7.inertia, FIG7.orbit_rate)
               - 2 * np.sum(h * c[:, 2, :], axis=1))
    assert relative_drift(flipped) > 1e-4
    assert relative_drift(r.jacobi) < 1e-10


def test_a_symmetric_body_also_conserves_wz_only_without_torque():
    """With the Sun on, wz of a symmetric body is not constant (Mz = 0 only if Ix = Iy)."""
    r = simulate(FIG7.replace(inertia=(1.0, 1.2, 4.0), duration=2.0))
    assert np.ptp(r.omega[:, 2]) > 1e-6
    assert relative_drift(r.jacobi) < 1e-10

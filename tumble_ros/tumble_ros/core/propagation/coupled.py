"""
Coupled orbit and attitude: the asteroid's flyby orbit integrated together with its rotation.

Elsewhere the perturber moves on a fixed Kepler orbit and only the spin feels the encounter.
Here the relative orbit feels the body's shape too: the perturber (a point mass M, GM_p) and the
asteroid (mass m, its gravity field to degree N: ``model.gravity_field.GravityField``, principal
moments per unit mass A = I / m [km^2]) attract each other with the body's field beyond its
monopole, so the orbit's and the spin's angular momentum exchange. With R the perturber's
position relative to the asteroid (orbital, inertial frame, as everywhere in core), C(q) the
attitude (body -> orbital):

    R'' = -G(M + m) R / R^3 + G(M + m) C g_N(C^T R)
    A w' = (A w) x w + T / m,    T / m = -GM_p (C^T R) x g_N(C^T R)
    q' = q (0, w) / 2

g_N is the body's field beyond its monopole per unit G m (``multipole.field_acceleration`` with
C_00 = 0): the relative acceleration is its reaction at the perturber times (M + m) / m
(two-body reduction), and the torque is the same field's, -m_p R x a(R) (``multipole.
field_torque``, the law of every perturber with a field). Force and torque come from one mutual
potential, U / m = -GM_p / R + GM_p Phi_N(C^T R), Phi_N the field's potential beyond the
monopole per unit G m, so the total energy E / m = (M / (M + m)) V^2 / 2 + w.A w / 2 + U / m
and the total angular momentum L / m = (M / (M + m)) R x V + C A w are conserved
(docs/physics.md, "Coupled orbit and attitude"). ``degree`` 0 is the point-mass limit: no
torque, no back-reaction, the fixed hyperbola.

The orbit is integrated by Encke's method: the deviation dR = R - R_k from the scenario's Kepler
orbit R_k(t) (``torques.orbits.KeplerOrbit``, whose ``gm`` is G(M + m), the relative orbit's),
so that a deviation of millimetres on 38,000 km keeps its own relative precision, and the
exchanged energy and angular momentum are computed from the deviations without cancellation.
Integrated with scipy's DOP853 (rtol 3e-14 by default, just above its floor of 100 ulp).

Units: km, yr (velocities in km/yr inside, km/s in :attr:`CoupledResult.velocity`), rad/yr;
energies per unit asteroid mass [km^2/yr^2], angular momenta per unit mass [km^2/yr].
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.model.gravity_field import G_KM3, GravityField
from tumble_ros.core.model.rotation import euler_to_quaternion, quaternion_to_matrix
from tumble_ros.core.model.scenario import Scenario
from tumble_ros.core.torques.multipole import field_acceleration, field_torque
from tumble_ros.core.torques.orbits import KeplerOrbit
from tumble_ros.core.units import SECONDS_PER_YEAR

__all__ = ['CoupledBody', 'CoupledResult', 'propagate_coupled', 'field_potential']

FloatArray = npt.NDArray[np.float64]
_YR2 = SECONDS_PER_YEAR * SECONDS_PER_YEAR
_acceleration: Callable[..., tuple[float, float, float]] = python_source(field_acceleration)
_torque: Callable[..., tuple[float, float, float]] = python_source(field_torque)


def field_potential(x: complex, y: complex, z: complex, radius: float, degree: int,
                    coefficients: Sequence[float] | FloatArray) -> complex:
    """
    Return the field's potential U per unit GM at (x, y, z): (1/a) sum C_nm V_nm + S_nm W_nm.

    Montenbruck & Gill (2000) eq 3.29 with the recursions of ``multipole``'s docstring;
    ``coefficients`` packed as ``GravityField.packed`` (C_00 = 0 leaves the monopole out);
    the acceleration is grad U (``multipole.field_acceleration``). Complex arguments pass
    through (the tests differentiate it by complex steps).
    """
    r2 = x * x + y * y + z * z
    xs, ys, zs, q = x * radius / r2, y * radius / r2, z * radius / r2, radius * radius / r2
    tri = (degree + 1) * (degree + 2) // 2
    total: complex = 0.0
    vmm: complex = radius / r2 ** 0.5
    wmm: complex = 0.0
    for m in range(degree + 1):
        if m > 0:
            f = 2.0 * m - 1.0
            vmm, wmm = f * (xs * vmm - ys * wmm), f * (xs * wmm + ys * vmm)
        v1, w1 = vmm, wmm
        v2: complex = 0.0
        w2: complex = 0.0
        for n in range(m, degree + 1):
            if n > m:
                c1 = (2.0 * n - 1.0) / (n - m)
                c2 = (n + m - 1.0) / (n - m)
                v1, v2 = c1 * zs * v1 - c2 * q * v2, v1
                w1, w2 = c1 * zs * w1 - c2 * q * w2, w1
            row = n * (n + 1) // 2 + m
            total += coefficients[row] * v1 + coefficients[tri + row] * w1
    return total / radius


@dataclass(frozen=True)
class CoupledBody:
    """
    The asteroid as the coupled problem needs it: its gravity field and how far to take it.

    Attributes
    ----------
    field : GravityField
        Its field to degree N (mass, reference radius, Stokes coefficients, principal
        moments), e.g. a mass model's ``gravity_field(N)``.
    degree : int or None
        The degree used: None (the field's), 2 ... N, or 0 (a point mass: no torque, no
        back-reaction).

    """

    field: GravityField
    degree: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.field, GravityField):
            raise ValueError(f'coupled.field: must be a GravityField, got {self.field!r}')
        degree = self.field.degree if self.degree is None else self.degree
        if isinstance(degree, bool) or not isinstance(degree, int) or not (
                degree == 0 or 2 <= degree <= self.field.degree):
            raise ValueError(f'coupled.degree: must be 0 (a point mass) or in [2, '
                             f"{self.field.degree}] (the field's), got {self.degree!r}")
        object.__setattr__(self, 'degree', degree)

    @property
    def gm(self) -> float:
        """Return the asteroid's GM [km^3/s^2]."""
        return float(self.field.gm)

    @property
    def inertia_per_mass(self) -> tuple[float, float, float]:
        """Return the principal moments per unit mass [km^2]."""
        a, b, c = (float(v) / self.field.mass for v in self.field.principal_moments)
        return a, b, c

    def packed(self) -> FloatArray:
        """
        Return the coefficients to :attr:`degree` from degree 2 (C_00, C_1m, S_1m = 0).

        The monopole acts in the Kepler term; the dipole is zero about the centre of mass, and
        its rounding-level coefficients (1e-17) would weigh R/a more than degree 2 in the
        potential (3e-11 of it at 40,000 km from a 0.2-km body), where the force
        (``field_acceleration(..., lowest=2)``) leaves them out.
        """
        degree = max(int(self.degree or 0), 2)
        packed = np.array(self.field.truncated(degree).packed())
        tri = (degree + 1) * (degree + 2) // 2
        packed[[0, 1, 2, tri, tri + 1, tri + 2]] = 0.0
        if self.degree == 0:
            packed[:] = 0.0
        return packed

    @classmethod
    def ellipsoid(cls, gm: float, semi_axes: Sequence[float], degree: int = 2) -> 'CoupledBody':
        """
        Return a homogeneous ellipsoid of semi-axes (a, b, c) [km] to degree 2 (MacCullagh).

        Its moments ((b^2 + c^2) / 5, ...) per unit mass; the degree-4 field of an ellipsoid
        is a mass model's (``gravity_field``). ``degree`` 0: the point mass.
        """
        if not _real(gm) > 0.0:
            raise ValueError(f"coupled.gm: the asteroid's GM must be a finite number > 0 "
                             f'km^3/s^2, got {gm!r}')
        axes = [_real(v) for v in semi_axes] if not isinstance(semi_axes, (str, bytes)) else []
        if len(axes) != 3 or not all(v > 0.0 for v in axes):
            raise ValueError('coupled.semi_axes: must be 3 finite numbers > 0 km, got '
                             f'{semi_axes!r}')
        a2, b2, c2 = (float(v) ** 2 for v in axes)
        mass = float(gm) / G_KM3
        moments = (mass * (b2 + c2) / 5.0, mass * (a2 + c2) / 5.0, mass * (a2 + b2) / 5.0)
        radius = math.sqrt(max(a2, b2, c2))
        return cls(GravityField.from_principal_moments(mass, radius, moments, 2), degree)


@dataclass(frozen=True)
class CoupledResult:
    """
    Samples of a coupled run at n times.

    Attributes
    ----------
    t : (n,) [yr].
    omega : (n, 3) [rad/yr], body axes. quaternion : (n, 4) body -> orbital, scalar first.
    position : (n, 3) the perturber relative to the asteroid [km], orbital frame.
    velocity : (n, 3) its velocity [km/s].
    deviation : (n, 3) position - the fixed Kepler orbit's [km] (Encke's dR).
    orbit_energy, spin_energy, potential_energy : (n,) [km^2/yr^2 per unit asteroid mass]
        The changes since t[0] of the orbit's two-body energy, of w.A w / 2, and of the
        orientation-dependent potential -GM_p (tr A - 3 u.A u) / (2 R^3).
    orbit_momentum, spin_momentum : (n, 3) [km^2/yr per unit mass], orbital frame
        The change of (M / (M + m)) R x V since t[0], and C A w.
    energy, momentum : float
        The total energy and the norm of the total angular momentum at t[0] (the scales of
        the conservation: E = (M / (M + m)) (V^2 / 2 - G(M + m) / R) + the rest).
    success : bool; message : str; nfev : int.

    """

    t: FloatArray
    omega: FloatArray
    quaternion: FloatArray
    position: FloatArray
    velocity: FloatArray
    deviation: FloatArray
    orbit_energy: FloatArray
    spin_energy: FloatArray
    potential_energy: FloatArray
    orbit_momentum: FloatArray
    spin_momentum: FloatArray
    energy: float
    momentum: float
    success: bool
    message: str
    nfev: int

    @property
    def energy_change(self) -> FloatArray:
        """Return the change of the total energy since t[0] (0 but for the integration)."""
        change: FloatArray = self.orbit_energy + self.spin_energy + self.potential_energy
        return change

    @property
    def momentum_change(self) -> FloatArray:
        """Return the change of the total angular momentum since t[0], (n, 3)."""
        change: FloatArray = self.orbit_momentum + self.spin_momentum - self.spin_momentum[0]
        return change


def _real(value: object) -> float:
    """Return ``value`` as a float, NaN unless a finite real number (not a bool)."""
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return math.nan
    return number if math.isfinite(number) and not isinstance(value, bool) else math.nan


def _quaternion_rate(q: FloatArray, w: FloatArray) -> FloatArray:
    q0, q1, q2, q3 = q
    wx, wy, wz = w
    return 0.5 * np.array([-q1 * wx - q2 * wy - q3 * wz, q0 * wx + q2 * wz - q3 * wy,
                           q0 * wy - q1 * wz + q3 * wx, q0 * wz + q1 * wy - q2 * wx])


def _inverse_cube_difference(rk: FloatArray, dr: FloatArray) -> tuple[float, float, float]:
    """Return (|R|, |R_k|, 1/|R|^3 - 1/|R_k|^3) for R = R_k + dR, without cancellation."""
    r_k = float(np.linalg.norm(rk))
    r = float(np.linalg.norm(rk + dr))
    closer = -(2.0 * float(rk @ dr) + float(dr @ dr)) / (r + r_k)      # r_k - r
    return r, r_k, closer * (r_k * r_k + r_k * r + r * r) / (r ** 3 * r_k ** 3)


def propagate_coupled(scenario: Scenario, body: CoupledBody,
                      t_eval: Sequence[float] | FloatArray | None = None, *,
                      coupled: bool = True, rtol: float = 3e-14) -> CoupledResult:
    """
    Integrate the scenario's flyby with the orbit and the spin coupled (module docstring).

    ``scenario``: its first perturber's Kepler orbit (``orbit`` or ``perturbers[0]``), whose
    ``gm`` is G(M + m); no other torque (other perturbers, ``torques``, ``impacts``, the
    circular orbit): refused with a ValueError. Its ``inertia`` is not used: ``body`` gives the
    moments (their ratios should be the scenario's). ``t_eval``: sample times [yr] (default the
    output grid). ``coupled`` False: the same equations without the back-reaction on the orbit
    (the fixed hyperbola), to measure the coupling.
    """
    orbit = scenario.primary_orbit
    if orbit is None or len(scenario.all_perturbers) != 1 or scenario.torques \
            or scenario.impacts or scenario.orbit_rate != 0.0:
        raise ValueError('coupled: needs a scenario whose only torque is one perturber on a '
                         'Kepler orbit (orbit.kind kepler or flyby), got perturbers '
                         f'{[p.name for p in scenario.all_perturbers]}, '
                         f'{len(scenario.torques)} torques, {len(scenario.impacts)} impacts, '
                         f'orbit_rate {scenario.orbit_rate!r}')
    gm_total = orbit.gm_per_yr2
    gm_p = (orbit.gm - body.gm) * _YR2
    if not gm_p > 0.0:
        raise ValueError(f"coupled.gm: the asteroid's GM must be below the orbit's G(M + m) = "
                         f'{orbit.gm!r} km^3/s^2, got {body.gm!r}')
    radius = float(body.field.reference_radius)
    if not orbit.pericentre > radius:
        raise ValueError(f"coupled.field: the body's reference radius {radius:.6g} km (its "
                         f'field converges outside that sphere) must lie inside the pericentre '
                         f'{orbit.pericentre:.6g} km: the perturber would pass through the body')
    share = gm_p / gm_total                              # M / (M + m)
    a = np.asarray(body.inertia_per_mass)
    field = body.degree != 0
    packed = body.packed()
    radius, degree = float(body.field.reference_radius), max(int(body.degree or 0), 2)
    times = np.asarray(scenario.output_times if t_eval is None else t_eval, dtype=float)
    from scipy.integrate import solve_ivp

    def kepler(t: float) -> tuple[FloatArray, FloatArray]:
        return orbit.position([t])[0], orbit.velocity([t])[0] * SECONDS_PER_YEAR

    def rhs(t: float, y: FloatArray) -> FloatArray:
        dr, dv, w, q = y[0:3], y[3:6], y[6:9], y[9:13]
        rk, _ = kepler(t)
        r_vec = rk + dr
        c = quaternion_to_matrix(q)
        rb = c.T @ r_vec
        out = np.empty(13)
        out[0:3] = dv
        r, r_k, difference = _inverse_cube_difference(rk, dr)
        # Encke: -G(M+m) (R / r^3 - R_k / r_k^3), then the body's field (its reaction)
        accel = -gm_total * (dr / r ** 3 + rk * difference)
        if field and coupled:
            accel += gm_total * (c @ np.array(_acceleration(*rb, 1.0, radius, degree, packed,
                                                            0, 2)))
        out[3:6] = accel
        torque = (np.array(_torque(*rb, gm_p, radius, degree, packed, 0)) if field
                  else np.zeros(3))
        out[6:9] = (np.cross(a * w, w) + torque) / a
        out[9:13] = _quaternion_rate(q, w)
        return out

    q0 = euler_to_quaternion(*scenario.euler0)
    y0 = np.concatenate([np.zeros(6), scenario.omega0, q0])
    t0 = float(times[0]) if times.size and times[0] < 0.0 else 0.0
    scale_v = float(np.linalg.norm(kepler(t0)[1]))
    atol = np.concatenate([np.full(3, 1e-17), np.full(3, 1e-17 * scale_v / 1e3),
                           np.full(3, 1e-15 * float(np.linalg.norm(scenario.omega0)) + 1e-300),
                           np.full(4, 1e-16)])
    sol = solve_ivp(rhs, (t0, float(times[-1])), y0, method='DOP853', t_eval=times, rtol=rtol,
                    atol=atol)
    y = sol.y.T
    return _result(scenario, orbit, body, share, gm_p, sol.t, y, bool(sol.success),
                   str(sol.message) if not sol.success else '', int(sol.nfev))


def _result(scenario: Scenario, orbit: KeplerOrbit, body: CoupledBody, share: float,
            gm_p: float, t: FloatArray, y: FloatArray, success: bool, message: str,
            nfev: int) -> CoupledResult:
    """Return the samples with the energies and angular momenta (module docstring)."""
    a = np.asarray(body.inertia_per_mass)
    packed = body.packed()
    radius, degree = float(body.field.reference_radius), max(int(body.degree or 0), 2)
    dr, dv, w, q = y[:, 0:3], y[:, 3:6], y[:, 6:9], y[:, 9:13]
    rk = orbit.position(t)
    vk = orbit.velocity(t) * SECONDS_PER_YEAR
    r_vec = rk + dr
    n = len(t)
    orbit_energy = np.empty(n)
    potential = np.empty(n)
    spin_momentum = np.empty((n, 3))
    gm_total = orbit.gm_per_yr2
    for k in range(n):
        r = float(np.linalg.norm(r_vec[k]))
        r_k = float(np.linalg.norm(rk[k]))
        inverse_difference = (2.0 * float(rk[k] @ dr[k]) + float(dr[k] @ dr[k])) \
            / (r + r_k) / (r * r_k)                       # 1/r_k - 1/r
        orbit_energy[k] = share * (float(vk[k] @ dv[k]) + 0.5 * float(dv[k] @ dv[k])
                                   + gm_total * inverse_difference)
        c = quaternion_to_matrix(q[k])
        rb = c.T @ r_vec[k]
        potential[k] = -gm_p * float(np.real(field_potential(rb[0], rb[1], rb[2], radius,
                                                             degree, packed)))
        spin_momentum[k] = c @ (a * w[k])
    spin = 0.5 * np.sum(a * w * w, axis=1)
    orbit_momentum = share * (np.cross(dr, vk) + np.cross(rk, dv) + np.cross(dr, dv))
    energy = (share * (0.5 * float(vk[0] @ vk[0]) - gm_total / float(np.linalg.norm(rk[0])))
              + spin[0] + potential[0])
    momentum = float(np.linalg.norm(share * np.cross(rk[0], vk[0]) + spin_momentum[0]))
    return CoupledResult(
        t=t, omega=w, quaternion=q, position=r_vec, velocity=(vk + dv) / SECONDS_PER_YEAR,
        deviation=dr, orbit_energy=orbit_energy, spin_energy=spin - spin[0],
        potential_energy=potential - potential[0], orbit_momentum=orbit_momentum,
        spin_momentum=spin_momentum, energy=energy, momentum=momentum, success=success,
        message=message, nfev=nfev)

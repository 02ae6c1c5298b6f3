"""
Keplerian orbits of the torquing body, and their tidal torque as a torque component.

The paper's circular orbit (``gravity_gradient``) keeps the Sun at a constant distance. Here the
perturber (the Sun on an eccentric orbit, or a planet on a hyperbolic flyby) moves on a
two-body Kepler orbit relative to the asteroid, and the torque is

    M = 3 GM / R(t)^3  u x (I u)          (paper eq 12 with the instantaneous distance R)

with u the unit direction to the perturber in body axes. Frame and time as for the circular
orbit: the orbital frame (X', Y' in the orbit plane, Z' its normal, inertial), the perturber's
direction s = (sin lambda, cos lambda, 0) with lambda = nu + lambda_p (nu the true anomaly,
lambda_p the direction of pericentre, both measured from +Y' clockwise about Z', as the paper's
R0(t) = R0 [sin ws t, cos ws t, 0]); so e = 0, t_p = 0, lambda_p = 0 is the circular orbit with
ws = n. Units: time [yr], distances in any unit L, GM in L^3/yr^2, angles [rad].

Kepler's equation: elliptic (0 <= e < 1) M = E - e sin E, hyperbolic (e > 1) M = e sinh H - H,
with the mean anomaly M = n (t - t_p), n = sqrt(GM / |a|^3). Both are solved by Newton's method
from a starter that converges for every e in range (Danby 1987 for the ellipse, M = 0.85 e
offset; the logarithmic starter for the hyperbola) to a few ulp; the solvers are compiled
(``core.jit``) and called by the torque function inside the integrators' loops.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .component import torque_function, TorqueComponent
from .frames import orbital_to_body
from .gravity_gradient import tidal_torque
from ..jit import jit

__all__ = ['KeplerOrbit', 'eccentric_anomaly', 'hyperbolic_anomaly', 'orbit_state',
           'kepler_tidal_torque', 'MAX_ECCENTRICITY']

_TWO_PI = 2.0 * math.pi
#: Largest eccentricity of an ellipse accepted (the solver is tested up to it), and the
#: smallest of a hyperbola: 1 +- 1e-6 (parabolic orbits are not modelled).
MAX_ECCENTRICITY = 0.99
_NEAR_PARABOLIC = 1e-6


@jit
def eccentric_anomaly(mean_anomaly, e):
    """Return E with E - e sin E = M (0 <= e < 1), E in (-pi, pi] + the turns of M."""
    turns = _TWO_PI * math.floor((mean_anomaly + math.pi) / _TWO_PI)
    m = mean_anomaly - turns                       # in [-pi, pi)
    big = m + (0.85 * e if math.sin(m) >= 0.0 else -0.85 * e)   # Danby's starter
    x = big
    for _ in range(64):
        s = math.sin(x)
        c = math.cos(x)
        f = x - e * s - m
        fp = 1.0 - e * c
        step = f / fp
        # Halley's correction (cubic convergence), Newton's step where it would not help
        denominator = fp - 0.5 * step * e * s
        if denominator != 0.0:
            step = f / denominator
        x -= step
        if abs(step) <= 4e-16 * (1.0 + abs(x)):
            break
    return x + turns


@jit
def hyperbolic_anomaly(mean_anomaly, e):
    """Return H with e sinh H - H = M (e > 1)."""
    m = abs(mean_anomaly)
    x = math.log(2.0 * m / e + 1.8)               # the logarithmic starter, x >= 0
    for _ in range(200):
        s = math.sinh(x)
        c = math.cosh(x)
        f = e * s - x - m
        fp = e * c - 1.0
        step = f / fp
        if step > 1.0:                            # far out: damp the first steps
            step = 1.0
        x -= step
        if abs(step) <= 4e-16 * (1.0 + abs(x)):
            break
    return x if mean_anomaly >= 0.0 else -x


@jit
def orbit_state(t, gm, a, e, t_p, lambda_p):
    """
    Return (R, lambda): the perturber's distance [L] and direction angle [rad] at time t [yr].

    ``a`` is the semi-major axis (> 0 for both kinds, |a| for the hyperbola), ``e`` the
    eccentricity, ``t_p`` the time of pericentre [yr], ``lambda_p`` the direction of
    pericentre [rad] (clockwise from +Y' about Z').
    """
    n = math.sqrt(gm / (a * a * a))
    mean = n * (t - t_p)
    if e < 1.0:
        big = eccentric_anomaly(mean, e)
        # the turns E carries, put back on nu (atan2 gives one turn): lambda stays continuous
        turns = _TWO_PI * math.floor((big + math.pi) / _TWO_PI)
        half = 0.5 * (big - turns)
        nu = 2.0 * math.atan2(math.sqrt(1.0 + e) * math.sin(half),
                              math.sqrt(1.0 - e) * math.cos(half)) + turns
        distance = a * (1.0 - e * math.cos(big))
    else:
        h = hyperbolic_anomaly(mean, e)
        nu = 2.0 * math.atan(math.sqrt((e + 1.0) / (e - 1.0)) * math.tanh(0.5 * h))
        distance = a * (e * math.cosh(h) - 1.0)
    return distance, nu + lambda_p


@torque_function
def kepler_tidal_torque(par, t, q0, q1, q2, q3):
    """
    Return the tidal torque of a perturber on a Kepler orbit, body axes.

    par = (GM, a, e, t_p, lambda_p, Ix, Iy, Iz): see :func:`orbit_state`.
    """
    distance, angle = orbit_state(t, par[0], par[1], par[2], par[3], par[4])
    ux, uy, uz = orbital_to_body(math.sin(angle), math.cos(angle), 0.0, q0, q1, q2, q3)
    k = 3.0 * par[0] / (distance * distance * distance)
    return tidal_torque(k * (par[7] - par[6]), k * (par[5] - par[7]), k * (par[6] - par[5]),
                        ux, uy, uz)


@dataclass(frozen=True)
class KeplerOrbit:
    """
    The torquing body's two-body orbit relative to the asteroid.

    Attributes
    ----------
    gm : float
        The perturber's GM [L^3/yr^2] (L: the unit of ``a``).
    a : float
        Semi-major axis [L], > 0 (for a hyperbola its absolute value).
    e : float
        Eccentricity: 0 <= e <= 0.99 (ellipse) or e >= 1 + 1e-6 (hyperbola).
    t_p : float
        Time of pericentre [yr].
    lambda_p : float
        Direction of pericentre in the orbit plane [rad], clockwise from +Y' about Z'.

    """

    gm: float
    a: float
    e: float = 0.0
    t_p: float = 0.0
    lambda_p: float = 0.0

    def __post_init__(self) -> None:
        for name in ('gm', 'a', 'e', 't_p', 'lambda_p'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
                    value):
                raise ValueError(f'orbit.{name}: must be a finite number, got {value!r}')
            object.__setattr__(self, name, float(value))
        if self.gm <= 0.0:
            raise ValueError(f'orbit.gm: must be > 0, got {self.gm!r}')
        if self.a <= 0.0:
            raise ValueError(f'orbit.a: must be > 0 (|a| for a hyperbola), got {self.a!r}')
        if not (0.0 <= self.e <= MAX_ECCENTRICITY or self.e >= 1.0 + _NEAR_PARABOLIC):
            raise ValueError(f'orbit.e: must be in [0, {MAX_ECCENTRICITY}] (ellipse) or '
                             f'>= {1.0 + _NEAR_PARABOLIC} (hyperbola); parabolic orbits are not '
                             f'modelled, got {self.e!r}')

    @property
    def mean_motion(self) -> float:
        """Return n = sqrt(GM / a^3) [rad/yr]."""
        return math.sqrt(self.gm / self.a ** 3)

    @property
    def pericentre(self) -> float:
        """Return the pericentre distance a |1 - e| [L]."""
        return self.a * abs(1.0 - self.e)

    def state(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Return the distances R [L] and directions lambda [rad] at times ``t`` [yr] (arrays)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.array([orbit_state(float(x), self.gm, self.a, self.e, self.t_p, self.lambda_p)
                        for x in t])
        return out[:, 0], out[:, 1]

    def position(self, t) -> np.ndarray:
        """Return where the perturber is in the orbital frame: (n, 3) coordinates [L]."""
        distance, angle = self.state(t)
        return np.stack([distance * np.sin(angle), distance * np.cos(angle),
                         np.zeros_like(angle)], axis=-1)

    def torque_component(self, inertia) -> TorqueComponent:
        """Return this orbit's tidal torque on a body of principal moments ``inertia``."""
        ix, iy, iz = (float(v) for v in inertia)
        return TorqueComponent('kepler_orbit', kepler_tidal_torque,
                               (self.gm, self.a, self.e, self.t_p, self.lambda_p, ix, iy, iz))

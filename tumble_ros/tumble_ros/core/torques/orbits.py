"""
Keplerian orbits of a torquing body relative to the asteroid (a perturber's source).

The paper's circular orbit (``gravity_gradient``) keeps the Sun at a constant distance. Here the
perturber (the Sun on an eccentric orbit, or a planet on a hyperbolic flyby) moves on a
two-body Kepler orbit relative to the asteroid, and the torque is

    M = 3 GM / R(t)^3  u x (I u)          (paper eq 12 with the instantaneous distance R)

with u the unit direction to the perturber in body axes. Frame and time as for the circular
orbit: in the perturber's orbit plane the direction is (sin lambda, cos lambda, 0) with
lambda = nu + lambda_p (nu the true anomaly, lambda_p the direction of pericentre, both measured
from +Y' clockwise about Z', as the paper's R0(t) = R0 [sin ws t, cos ws t, 0]); that plane is
then tilted by ``inclination`` about X' and turned by ``node`` about Z' into the scenario's
(inertial) orbital frame, where the body's attitude is given:

    s = Rz(node) Rx(inclination) (sin lambda, cos lambda, 0)

so e = 0, t_p = 0, lambda_p = inclination = node = 0 is the circular orbit with ws = n.

Units: the astrodynamics ones, as every table states them: GM [km^3/s^2], distances [km],
speeds [km/s]; times [yr] (the core's unit; ``t_p``), angles [rad]. The mean motion and the
torque coefficient are converted to years inside (``units.SECONDS_PER_YEAR``).

Kepler's equation: elliptic (0 <= e < 1) M = E - e sin E, hyperbolic (e > 1) M = e sinh H - H,
with the mean anomaly M = n (t - t_p), n = sqrt(GM / |a|^3). Both are solved by Newton's method
from a starter that converges for every e in range (Danby 1987 for the ellipse, M = 0.85 e
offset; for the hyperbola the smaller of the logarithmic starter and the root of the
equation's cubic approximation, close to the solution near a parabola's pericentre) to a few
ulp, or until the residual is rounding noise; the solvers are compiled (``core.compiling.jit``) and
called by the torque function inside the integrators' loops
(:func:`.perturbers.kepler_perturber_torque`: a Kepler orbit is a perturber's source).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit, jit_inline, python_source
from tumble_ros.core.torques.gravity_gradient import sun_direction_orbital
from tumble_ros.core.units import GM_SUN, PERTURBER_RADII, SECONDS_PER_YEAR

__all__ = ['KeplerOrbit', 'eccentric_anomaly', 'hyperbolic_anomaly', 'orbit_state',
           'plane_to_orbital', 'perturber_position', 'orientation_from_elements',
           'perturber_radius', 'MAX_ECCENTRICITY', 'MAX_GM', 'MAX_SEMI_MAJOR_AXIS',
           'GM_MATCH', 'MAX_PERICENTRE_SPEED', 'pericentre_speed']

_TWO_PI = 2.0 * math.pi
#: The rounding noise of Kepler's equation's residual, relative to the sum of its terms' sizes
#: (4 ulp): the solvers stop once the residual is that small, after applying that last step.
#: Without it, they stopped only when Newton's step fell below 4e-16 (1 + |x|), which where the
#: equation is ill-conditioned (e near 1 at pericentre, or a step dithering by an ulp) never
#: came, and they ran all their iterations (64 or 200 instead of 2-6: a runaway flyby's
#: ``simulate`` took 12.7 s instead of 1.2 s).
_NOISE = 4.0 * 2.220446049250313e-16
#: Largest eccentricity of an ellipse accepted (the solver is tested up to it), and the
#: smallest of a hyperbola: 1 +- 1e-6 (parabolic orbits are not modelled).
MAX_ECCENTRICITY = 0.99
_NEAR_PARABOLIC = 1e-6
#: Largest GM [km^3/s^2]: 1e21, ~7.5e9 solar masses (the heaviest black holes known). Above
#: ~1e293 GM in km^3/yr^2 is no longer finite (gm: 1e300 failed deep inside as a non-finite
#: torque parameter).
MAX_GM = 1e21
#: Largest semi-major axis |a| [km]: 1e16 km, about a light-year (the Oort cloud is within
#: ~1e13 km); a^3 stays finite (a = 1e300 made the mean motion 0: a perturber that never moves).
MAX_SEMI_MAJOR_AXIS = 1e16
#: Relative agreement of ``gm`` with a known body's GM (``units.PERTURBER_RADII``) for the
#: perturber to take that body's radius: 1e-3 accepts every published value of the Sun's, the
#: Earth's and the Moon's GM, and no other body's.
GM_MATCH = 1e-3
#: The speed of light [km/s]: the bound of a flyby's speeds (a Newtonian model).
SPEED_OF_LIGHT = 299792.458
#: Largest speed at pericentre [km/s]: 1 % of the speed of light. The model is Newtonian: its
#: relative errors are of order (v/c)^2 ~ GM / (R c^2), 1e-4 here; a perturber of that GM whose
#: surface lies below such a pericentre is relativistically compact (a neutron star, a black
#: hole). Such passages also spin the body up to its pericentre's angular rate (the Sun's mass
#: 1,496 km away: ~1e7 rad/yr after the passage, a few hundred seconds of work a simulated
#: year); every known solar-system encounter is far below (grazing the Sun: 618 km/s, 0.2 %).
MAX_PERICENTRE_SPEED = 0.01 * SPEED_OF_LIGHT


def perturber_radius(gm: float) -> tuple[float, str]:
    """
    Return (radius [km], name) of the known body whose GM [km^3/s^2] ``gm`` is.

    The Sun, the Earth or the Moon (``units.PERTURBER_RADII``) when ``gm`` matches its GM to
    :data:`GM_MATCH` relative; (0.0, '') otherwise (a point mass, unless ``orbit.radius`` says).
    """
    for name, (body_gm, radius) in PERTURBER_RADII.items():
        if abs(gm - body_gm) <= GM_MATCH * body_gm:
            return radius, name
    return 0.0, ''


def pericentre_speed(gm: float, pericentre: float, e: float) -> float:
    """Return the speed at pericentre sqrt(GM (1 + e) / q) [km/s] (GM [km^3/s^2], q [km])."""
    return math.sqrt(gm * (1.0 + e) / pericentre)


def _speed_problem(gm: float, pericentre: float, e: float) -> str:
    """Return why the pericentre is too fast for the Newtonian model, or '' when it is not."""
    speed = pericentre_speed(gm, pericentre, e)
    if speed <= MAX_PERICENTRE_SPEED:
        return ''
    return (f'the speed at the pericentre {pericentre:.6g} km, sqrt(gm (1 + e) / pericentre) = '
            f'{speed:.6g} km/s ({speed / SPEED_OF_LIGHT:.2%} of light), exceeds '
            f'{MAX_PERICENTRE_SPEED:.6g} km/s (1 % of light: the model is Newtonian, and a body '
            'of this gm with its surface below the pericentre is relativistically compact)')


def _number(name: str, value: object, unit: str) -> float:
    """Return ``value`` as a float; ValueError naming ``name`` unless a finite number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f'orbit.{name}: must be a finite number{unit}, got {value!r}')
    return float(value)


def _check_gm(gm: object) -> float:
    """Return the validated GM [km^3/s^2] (``orbit.gm``)."""
    gm = _number('gm', gm, ' [km^3/s^2]')
    if not 0.0 < gm <= MAX_GM:
        raise ValueError(f'orbit.gm: must be in (0, {MAX_GM:g}] km^3/s^2 (the Sun: '
                         f'{GM_SUN:g}; {MAX_GM:g} is ~7.5e9 solar masses), got {gm!r}')
    return gm


def _resolve_radius(gm: float, radius: object) -> tuple[float, str]:
    """
    Return (the perturber's radius [km], where it comes from) for ``orbit.radius``.

    ``radius`` 0: the known body's whose GM ``gm`` is (:func:`perturber_radius`), else 0 (a
    point mass); > 0: that radius.
    """
    radius = _number('radius', radius, ' [km]')
    if radius < 0.0:
        raise ValueError(f"orbit.radius: must be >= 0 km (0: the Sun's, the Earth's or the "
                         f"Moon's by orbit.gm, else a point mass), got {radius!r}")
    if radius > 0.0:
        return radius, 'orbit.radius'
    radius, name = perturber_radius(gm)
    return radius, (f"the {name}'s, by orbit.gm; orbit.radius sets another" if name
                    else 'a point mass')


@jit
def eccentric_anomaly(mean_anomaly: float, e: float) -> float:
    """
    Return E with E - e sin E = M (0 <= e < 1), E in (-pi, pi] + the turns of M.

    Halley's method from Danby's starter, stopping once the residual is rounding noise
    (``_NOISE``) or the step is below 4e-16 (1 + |E|).
    """
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
        noise = _NOISE * (abs(x) + abs(e * s) + abs(m))
        if abs(step) <= 4e-16 * (1.0 + abs(x)) or abs(f) <= noise:
            break
    return x + turns


@jit
def hyperbolic_anomaly(mean_anomaly: float, e: float) -> float:
    """
    Return H with e sinh H - H = M (e > 1).

    Newton's method from the smaller of two starters: the logarithmic one (far from pericentre)
    and the root of the cubic (e - 1) H + e H^3 / 6 = |M| (near a parabola and near pericentre,
    where Newton from the logarithmic starter crawled: e sinh H - H is nearly cubic there, and
    Newton's steps on a cubic shrink the distance by only a third each). The cubic's root lies
    at or above the solution (sinh H >= H + H^3 / 6 for H >= 0), and the function is convex
    and increasing there, so Newton's steps from it decrease to the solution. It stops once the
    residual is rounding noise (``_NOISE``).
    """
    m = abs(mean_anomaly)
    x = math.log(2.0 * m / e + 1.8)               # the logarithmic starter, x >= 0
    # the cubic H^3 + 3 s^2 H = 6 |M| / e with s^2 = 2 (e - 1) / e, solved in closed form:
    # H = 2 s sinh(asinh(3 |M| / (e s^3)) / 3)
    s = math.sqrt(2.0 * (e - 1.0) / e)
    cubic = 2.0 * s * math.sinh(math.asinh(3.0 * m / (e * s * s * s)) / 3.0)
    if cubic < x:
        x = cubic
    for _ in range(200):
        s = math.sinh(x)
        c = math.cosh(x)
        f = e * s - x - m
        fp = e * c - 1.0
        step = f / fp
        if step > 1.0:                            # far out: damp the first steps
            step = 1.0
        x -= step
        if abs(step) <= 4e-16 * (1.0 + abs(x)) or abs(f) <= _NOISE * (e * s + x + m):
            break
    return x if mean_anomaly >= 0.0 else -x


@jit
def orbit_state(t: float, gm: float, a: float, e: float, t_p: float,
                lambda_p: float) -> tuple[float, float]:
    """
    Return (R, lambda): the perturber's distance [L] and in-plane angle [rad] at time t [yr].

    ``gm`` in L^3/yr^2 (the core's units; :attr:`KeplerOrbit.gm_per_yr2`), ``a`` the
    semi-major axis [L] (> 0 for both kinds, |a| for the hyperbola), ``e`` the eccentricity,
    ``t_p`` the time of pericentre [yr], ``lambda_p`` the direction of pericentre [rad]
    (clockwise from +Y' about Z' in the orbit plane).
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
        # a (e cosh H - 1) without its cancellation near a parabola (e cosh H -> 1 at perigee):
        # (e - 1) + 2 e sinh^2(H/2), with e - 1 exact (Sterbenz) for 1 < e <= 2
        sh = math.sinh(0.5 * h)
        distance = a * ((e - 1.0) + 2.0 * e * sh * sh)
    return distance, nu + lambda_p


@jit_inline
def plane_to_orbital(sin_angle: float, cos_angle: float, cos_i: float, sin_i: float,
                     cos_node: float, sin_node: float) -> tuple[float, float, float]:
    """Return s = Rz(node) Rx(i) (sin lambda, cos lambda, 0): the orbit plane's direction."""
    y = cos_angle * cos_i
    return (sin_angle * cos_node - y * sin_node, sin_angle * sin_node + y * cos_node,
            cos_angle * sin_i)


@dataclass(frozen=True)
class KeplerOrbit:
    """
    The torquing body's two-body orbit relative to the asteroid.

    Attributes
    ----------
    gm : float
        The perturber's GM [km^3/s^2] (the Sun 1.32712440018e11, the Earth 398600.4418:
        ``units.GM_SUN``, ``units.GM_EARTH``).
    a : float
        Semi-major axis [km], > 0 (for a hyperbola its absolute value).
    e : float
        Eccentricity: 0 <= e <= 0.99 (ellipse) or e >= 1 + 1e-6 (hyperbola).
    t_p : float
        Time of pericentre [yr].
    lambda_p : float
        Direction of pericentre in the orbit plane [rad], clockwise from +Y' about Z'.
    inclination, node : float
        The orbit plane's orientation in the orbital frame [rad]: tilted by ``inclination``
        about X', then turned by ``node`` about Z' (0, 0: the plane X'Y' of the paper).
    radius : float
        The perturber's radius [km]: the pericentre must lie outside it. 0 (default): the
        Sun's, the Earth's or the Moon's when ``gm`` is theirs (:func:`perturber_radius`), else
        0 (a point mass); the resolved value is kept.

    Every field is checked where it is read; the ValueError names it (``orbit.<field>``), its
    value and the range (the Scenario passes it on as a ScenarioError).

    """

    gm: float
    a: float
    e: float = 0.0
    t_p: float = 0.0
    lambda_p: float = 0.0
    inclination: float = 0.0
    node: float = 0.0
    radius: float = 0.0

    def __post_init__(self) -> None:
        units = {'gm': ' [km^3/s^2]', 'a': ' [km]', 'e': '', 't_p': ' [yr]', 'lambda_p': ' [rad]',
                 'inclination': ' [rad]', 'node': ' [rad]'}
        for name, unit in units.items():
            object.__setattr__(self, name, _number(name, getattr(self, name), unit))
        _check_gm(self.gm)
        if not 0.0 < self.a <= MAX_SEMI_MAJOR_AXIS:
            raise ValueError(f'orbit.a: must be in (0, {MAX_SEMI_MAJOR_AXIS:g}] km (|a| for a '
                             f'hyperbola), got {self.a!r}')
        if not (0.0 <= self.e <= MAX_ECCENTRICITY or self.e >= 1.0 + _NEAR_PARABOLIC):
            raise ValueError(f'orbit.e: must be in [0, {MAX_ECCENTRICITY}] (ellipse) or '
                             f'>= {1.0 + _NEAR_PARABOLIC} (hyperbola); parabolic orbits are '
                             f'not modelled, got {self.e!r}')
        radius, source = _resolve_radius(self.gm, self.radius)
        object.__setattr__(self, 'radius', radius)
        if not self.pericentre > radius:
            raise ValueError(
                f'orbit.e: the pericentre a |1 - e| = {self.pericentre:.6g} km (orbit.a = '
                f'{self.a!r} km) must lie outside the perturber, radius {radius!r} km '
                f'({source}), got {self.e!r}')
        problem = _speed_problem(self.gm, self.pericentre, self.e)
        if problem:
            raise ValueError(f'orbit.e: {problem}, got {self.e!r} (orbit.a = {self.a!r} km)')

    @classmethod
    def flyby(cls, gm: float, perigee: float, *, v_inf: float = 0.0, v_perigee: float = 0.0,
              t_p: float = 0.0, lambda_p: float = 0.0, inclination: float = 0.0,
              node: float = 0.0, radius: float = 0.0) -> 'KeplerOrbit':
        """
        Return the hyperbola of a flyby.

        Given GM [km^3/s^2], the perigee distance [km], and either the hyperbolic excess speed
        ``v_inf`` or the speed at perigee ``v_perigee`` [km/s]:

        a = GM / v_inf^2, e = 1 + perigee v_inf^2 / GM (vis-viva: v_inf^2 = v_p^2 - 2 GM / r_p).

        Each of them is checked here, before any is used, and a refusal names the field given
        (``orbit.perigee``, ``orbit.v_inf``...), not the a or e derived from it. ``radius``:
        as :attr:`radius`; the perigee must lie outside it.
        """
        gm = _check_gm(gm)
        perigee = _number('perigee', perigee, ' [km]')
        v_inf = _number('v_inf', v_inf, ' [km/s]')
        v_perigee = _number('v_perigee', v_perigee, ' [km/s]')
        if not perigee > 0.0:
            raise ValueError(f'orbit.perigee: must be > 0 km, got {perigee!r}')
        body, source = _resolve_radius(gm, radius)
        if not perigee > body:
            raise ValueError(f'orbit.perigee: must lie outside the perturber, radius '
                             f'{body!r} km ({source}), got {perigee!r} km')
        for name, value in (('v_inf', v_inf), ('v_perigee', v_perigee)):
            if not value < SPEED_OF_LIGHT:
                raise ValueError(f'orbit.{name}: must be below the speed of light, '
                                 f'{SPEED_OF_LIGHT} km/s (the model is Newtonian), got '
                                 f'{value!r}')
        if v_inf < 0.0 or v_perigee < 0.0 or (v_inf > 0.0) == (v_perigee > 0.0):
            raise ValueError('orbit.v_inf, orbit.v_perigee: give exactly one of them (> 0 '
                             f'km/s), got {v_inf!r} and {v_perigee!r}')
        speed = 'v_inf'
        if v_perigee > 0.0:
            speed = 'v_perigee'
            escape = 2.0 * gm / perigee
            if not v_perigee * v_perigee > escape:
                raise ValueError(f'orbit.v_perigee: must exceed the escape speed '
                                 f'{math.sqrt(escape):.6g} km/s at perigee (a flyby is a '
                                 f'hyperbola), got {v_perigee!r}')
            v_inf = math.sqrt(v_perigee * v_perigee - escape)
        v2 = v_inf * v_inf
        given = v_perigee if speed == 'v_perigee' else v_inf
        if not (v2 > 0.0 and gm / v2 <= MAX_SEMI_MAJOR_AXIS):
            raise ValueError(
                f'orbit.{speed}: gives v_inf = {v_inf:.6g} km/s, below '
                f'{math.sqrt(gm / MAX_SEMI_MAJOR_AXIS):.6g} km/s at this gm (a = gm / v_inf^2 '
                f'must be <= {MAX_SEMI_MAJOR_AXIS:g} km), got {given!r}')
        if not perigee * v2 / gm >= _NEAR_PARABOLIC:
            raise ValueError(
                f'orbit.perigee, orbit.{speed}: e - 1 = perigee v_inf^2 / gm = '
                f'{perigee * v2 / gm:.3g} must be >= {_NEAR_PARABOLIC:g} (near-parabolic orbits '
                f'are not modelled), got perigee = {perigee!r} km, {speed} = {given!r} km/s')
        problem = _speed_problem(gm, perigee, 1.0 + perigee * v2 / gm)
        if problem:
            raise ValueError(f'orbit.perigee, orbit.{speed}: {problem}, got perigee = '
                             f'{perigee!r} km, {speed} = {given!r} km/s')
        return cls(gm=gm, a=gm / v2, e=1.0 + perigee * v2 / gm, t_p=t_p, lambda_p=lambda_p,
                   inclination=inclination, node=node, radius=body)

    @property
    def gm_per_yr2(self) -> float:
        """Return GM in the core's units, km^3/yr^2."""
        return self.gm * SECONDS_PER_YEAR * SECONDS_PER_YEAR

    @property
    def mean_motion(self) -> float:
        """Return n = sqrt(GM / |a|^3) [rad/yr]."""
        return math.sqrt(self.gm_per_yr2 / self.a ** 3)

    @property
    def pericentre(self) -> float:
        """Return the pericentre distance a |1 - e| [km]."""
        return self.a * abs(1.0 - self.e)

    def time_from_pericentre(self, distance: float) -> float:
        """
        Return tau >= 0 [yr]: a hyperbola is at ``distance`` [km] at t_p - tau and t_p + tau.

        R = a (e cosh H - 1) gives H, Kepler's equation the time; ``distance`` at or inside
        the pericentre gives 0. Raises ValueError for an ellipse (it never leaves).
        """
        if self.e < 1.0:
            raise ValueError('time_from_pericentre: an ellipse has no encounter (e < 1)')
        if distance <= self.pericentre:
            return 0.0
        h = math.acosh((distance / self.a + 1.0) / self.e)
        return (self.e * math.sinh(h) - h) / self.mean_motion

    def _plane(self) -> tuple[float, float, float, float]:
        return (math.cos(self.inclination), math.sin(self.inclination), math.cos(self.node),
                math.sin(self.node))

    def state(self, t: npt.ArrayLike) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Return the distances R [km] and in-plane angles lambda [rad] at times ``t`` [yr]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        gm = self.gm_per_yr2
        out = np.array([orbit_state(float(x), gm, self.a, self.e, self.t_p, self.lambda_p)
                        for x in t])
        return out[:, 0], out[:, 1]

    def direction(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return the unit direction to the perturber in the orbital frame: (n, 3)."""
        return self._direction(self.state(t)[1])

    def position(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return where the perturber is in the orbital frame: (n, 3) coordinates [km]."""
        distance, angle = self.state(t)
        position: npt.NDArray[np.float64] = distance[:, None] * self._direction(angle)
        return position

    def velocity(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """
        Return the perturber's velocity relative to the asteroid, orbital frame: (n, 3) [km/s].

        Radial speed sqrt(GM / p) e sin nu, transverse sqrt(GM / p) (1 + e cos nu) along
        d/dlambda of the direction, p = a |1 - e^2| the semi-latus rectum.
        """
        distance, angle = self.state(t)
        nu = angle - self.lambda_p
        scale = math.sqrt(self.gm / (self.a * abs(1.0 - self.e * self.e)))
        radial = scale * self.e * np.sin(nu)
        transverse = scale * (1.0 + self.e * np.cos(nu))
        on_arrays: Callable[..., Any] = python_source(plane_to_orbital)
        along = np.stack(on_arrays(np.cos(angle), -np.sin(angle), *self._plane()), axis=-1)
        velocity: npt.NDArray[np.float64] = (radial[:, None] * self._direction(angle)
                                             + transverse[:, None] * along)
        return velocity

    def _direction(self, angle: np.ndarray) -> np.ndarray:
        """Return the orbital-frame unit vectors of in-plane angles lambda [rad]: (n, 3)."""
        s = python_source(plane_to_orbital)(np.sin(angle), np.cos(angle), *self._plane())
        stacked: npt.NDArray[np.float64] = np.stack(s, axis=-1)
        return stacked


def orientation_from_elements(inclination: float, node: float,
                              argument_of_pericentre: float) -> dict[str, float]:
    """
    Return this module's (lambda_p, inclination, node) of the standard orbital elements [rad].

    The standard elements (i, Omega, omega: the ones ephemerides such as JPL Horizons print)
    place the perturber at Rz(Omega) Rx(i) (cos u, sin u, 0), u = omega + nu, counter-clockwise
    about the orbit's normal. This module's direction (sin lambda, cos lambda, 0) runs clockwise
    from +Y' (the paper's convention), and (sin x, cos x, 0) = Rx(pi) (cos(x - pi/2),
    sin(x - pi/2), 0); so lambda_p = omega + pi/2, inclination = i - pi, node = Omega. The
    orbital frame is then the ephemeris' frame (e.g. ecliptic J2000).
    """
    return {'lambda_p': argument_of_pericentre + 0.5 * math.pi,
            'inclination': inclination - math.pi, 'node': node}


def perturber_position(orbit_rate: float, orbit: KeplerOrbit | None,
                       t: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """
    Return where the torquing body is, in the orbital frame: (n, 3) [km] at times ``t`` [yr].

    With a Kepler orbit, its position. On the paper's circular orbit (``orbit`` None), the Sun:
    the direction R0(t)/R0 at the distance R0 = (GM_sun / ws^2)^(1/3) that Kepler's third law
    gives for the orbit rate ws (the paper states ws only; this assumes the perturber is the
    Sun). Without a torque (ws = 0) the Sun is taken infinitely far along +Y'.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if orbit is not None:
        return orbit.position(t)
    if orbit_rate == 0.0:
        far: npt.NDArray[np.float64] = np.tile([0.0, math.inf, 0.0], (t.size, 1))
        return far
    ws = orbit_rate / SECONDS_PER_YEAR
    distance = (GM_SUN / (ws * ws)) ** (1.0 / 3.0)
    position: npt.NDArray[np.float64] = distance * sun_direction_orbital(t, orbit_rate)
    return position

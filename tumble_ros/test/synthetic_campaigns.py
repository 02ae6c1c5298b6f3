"""
Synthetic photometric campaigns of tumbling asteroids, made independently of the project's code.

The proof of the inversion (issue 49) injects a known spin state into a campaign and asks the
fit to recover it. A campaign the fit's own forward model made would prove nothing about that
model, so nothing here imports ``tumble_ros.core`` or ``tumble_ros.inversion`` except the
:class:`~tumble_ros.inversion.campaign.Campaign` dataclass it returns. Every piece is its own:

* **the spin state** (:class:`TrueSpin`): the literature's mode, P_phi, P_psi, I1/I3, I2/I3,
  L's ecliptic (lambda, beta), the phases (phi0, psi0) and the sign of cos theta0, in the
  convention ``core/model/observables.py``'s docstring states (re-derived here from that text:
  ``R = Rz(psi) Rx(theta) Rz(phi)``, passive z-x-z rotations, maps L-frame components to the
  body's (a, b, r): (I1, I2, I3) in a SAM, (I2, I3, I1) in a LAM; the L frame has z_L along L,
  x_L = (-sin lambda, cos lambda, 0); cos^2 theta0 = (1/D - S) / (1/I_r - S),
  S = sin^2 psi0 / I_a + cos^2 psi0 / I_b); and 'PA', a principal-axis rotator about I3;
* **periods -> (D, |L|)**: P_psi by the complete elliptic integral K (Landau & Lifshitz,
  Mechanics, sec. 37: P_psi = 4 K(k) sqrt(I1 I2 I3 D / ((I3 - I2)(D - I1))) / L for a SAM,
  k^2 = (I2 - I1)(I3 - D) / ((I3 - I2)(D - I1)), I1 <-> I3 for a LAM; Samarasinha & A'Hearn
  1991, Kaasalainen 2001) and P_phi as 2 pi over the time mean of
  phi' = L (Ia wa^2 + Ib wb^2) / (Ia^2 wa^2 + Ib^2 wb^2) along the Jacobi-function polhode,
  by the trapezoid rule (periodic: exponentially convergent). P_psi / P_phi fixes D (Brent),
  P_psi then fixes L. Not the project's Carlson-integral closed form;
* **the motion**: Euler's equations and dC/dt = C [w]x (C: body -> ecliptic J2000) integrated by
  ``scipy.integrate.solve_ivp(method='DOP853', rtol=1e-12)`` from the epoch, forwards and
  backwards, read at the emission times;
* **the brightness**: a triaxial ellipsoid (semi-axes along the body axes x, y, z = the principal
  axes of I1, I2, I3; by default the uniform ellipsoid of the inertia ratios) integrated over its
  surface on a parametric (u, v) grid (midpoint in v, uniform in u), the Kaasalainen law
  S = mu0 mu / (mu0 + mu) + c mu0 mu over the points both lit and seen; magnitudes
  -2.5 log10(B / B_ref) + 5 log10(r Delta) + slope * alpha[deg] (a linear phase function);
* **the geometry**: the asteroid and the Earth on two-body Kepler ellipses about the Sun
  (ecliptic J2000 elements; the Earth's of Standish's mean elements at J2000), the observer at
  the geocentre, light time by iteration (the emission time t_e of a reception at t:
  |r_obs(t) - r_ast(t_e)| = c (t - t_e));
* **the sampling**: nights inside apparition windows where the solar elongation allows, a
  deterministic lunar gap (nights within 3.5 d of a full moon are dropped), weather (a random
  choice of the nights left), runs of a few hours, 1-sigma errors 0.01-0.03 mag per night,
  Gaussian noise and a free magnitude offset per night.

Units: time [d] (JD TDB), periods [h] in :class:`TrueSpin`, angles [deg] in the public
parameters unless said [rad], distances [au], w [rad/d].
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Callable, Sequence

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipj, ellipk

from tumble_ros.inversion.campaign import Campaign

__all__ = ['TrueSpin', 'Apparition', 'SyntheticCampaign', 'ellipsoid_of_inertia',
           'dynamic_inertia_and_momentum', 'rotation_period', 'mean_precession_rate',
           'initial_state', 'integrate_attitude', 'ellipsoid_brightness', 'sphere_brightness',
           'KeplerElements', 'EARTH', 'APOPHIS', 'kepler_position', 'observing_nights',
           'make_campaign', 'draw', 'APOPHIS_PRAVEC_2014', 'APOPHIS_LEE_2022',
           'APOPHIS_2012_13', 'APOPHIS_2020_21']

#: Gaussian gravitational constant squared: GM of the Sun [au^3 / d^2].
GM_SUN = 0.01720209895 ** 2
#: Speed of light [au / d] (IAU 2012 au, c = 299792.458 km/s).
C_AU_PER_DAY = 299792.458 * 86400.0 / 149597870.7
#: JD TDB of J2000.0.
J2000 = 2451545.0
#: Weight c of the Lambert term of the Kaasalainen law.
LAMBERT_WEIGHT = 0.1
#: A full moon [JD] (2000-01-21 04:40 UT) and the synodic month [d].
FULL_MOON_JD = 2451564.694
SYNODIC_MONTH = 29.530589
#: The integrator's relative tolerance (the brief: DOP853 at rtol 1e-12).
RTOL = 1e-12


# -- the spin state -------------------------------------------------------------------------

@dataclass(frozen=True)
class TrueSpin:
    """
    An injected spin state, as the literature states it.

    ``mode`` 'SAM', 'LAM' or 'PA' (a principal-axis rotation about I3 with period
    ``precession_period_h``; ``rotation_period_h`` is then unused); ``precession_period_h``
    P_phi [h]; ``rotation_period_h`` P_psi [h]; ``inertia_ratios`` (I1/I3, I2/I3);
    ``pole_deg`` L's ecliptic J2000 (lambda, beta) [deg]; ``phases`` (phi0, psi0) [rad] at
    ``epoch_jd`` [JD TDB]; ``anti_aligned`` theta0 > 90 deg.
    """

    mode: str
    precession_period_h: float
    rotation_period_h: float
    inertia_ratios: tuple[float, float]
    pole_deg: tuple[float, float]
    phases: tuple[float, float] = (0.0, 0.0)
    anti_aligned: bool = False
    epoch_jd: float = J2000

    def __post_init__(self) -> None:
        if self.mode not in ('SAM', 'LAM', 'PA'):
            raise ValueError(f'TrueSpin.mode: SAM, LAM or PA, got {self.mode!r}')
        r1, r2 = self.inertia_ratios
        if not 0.0 < r1 < r2 < 1.0:
            raise ValueError(f'TrueSpin.inertia_ratios: 0 < I1/I3 < I2/I3 < 1, got '
                             f'{self.inertia_ratios}')

    @property
    def moments(self) -> np.ndarray:
        """(I1, I2, I3) / I3 along the body axes x, y, z."""
        return np.array([self.inertia_ratios[0], self.inertia_ratios[1], 1.0])


def _rz(angle: float) -> np.ndarray:
    """Passive rotation about z: the components of a vector in a frame turned by ``angle``."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(angle: float) -> np.ndarray:
    """Passive rotation about x."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def _abr_to_body(mode: str) -> np.ndarray:
    """Columns: the body (x, y, z) components of a, b, r (SAM, PA: e1, e2, e3; LAM: e2, e3, e1)."""
    if mode == 'LAM':
        return np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return np.eye(3)


def l_frame(pole_deg: Sequence[float]) -> np.ndarray:
    """Columns x_L, y_L, z_L in ecliptic components: z_L along L, x_L its equator's node."""
    lon, lat = np.radians(pole_deg[0]), np.radians(pole_deg[1])
    z = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    x = np.array([-math.sin(lon), math.cos(lon), 0.0])
    return np.column_stack([x, np.cross(z, x), z])


def _sam_k2(i: np.ndarray, d: float) -> float:
    i1, i2, i3 = i
    return float((i2 - i1) * (i3 - d) / ((i3 - i2) * (d - i1)))


def _lam_k2(i: np.ndarray, d: float) -> float:
    i1, i2, i3 = i
    return float((i3 - i2) * (d - i1) / ((i2 - i1) * (i3 - d)))


def rotation_period(i: np.ndarray, d: float, momentum: float, mode: str) -> float:
    """P_psi [d] of moments ``i`` (I1 < I2 < I3), D = L^2/2E, |L| = ``momentum`` (w [rad/d])."""
    i1, i2, i3 = i
    if mode == 'SAM':
        k2, scale = _sam_k2(i, d), (i3 - i2) * (d - i1)
    else:
        k2, scale = _lam_k2(i, d), (i2 - i1) * (i3 - d)
    return float(4.0 * ellipk(k2) * math.sqrt(i1 * i2 * i3 * d / scale) / momentum)


def _polhode(i: np.ndarray, d: float, momentum: float, mode: str,
             samples: int) -> np.ndarray:
    """Return w (samples, 3) [rad/d] at equal time steps over one polhode period (Jacobi)."""
    i1, i2, i3 = i
    l2 = momentum * momentum
    e2 = l2 / d
    w1m = math.sqrt((e2 * i3 - l2) / (i1 * (i3 - i1)))
    w3m = math.sqrt((l2 - e2 * i1) / (i3 * (i3 - i1)))
    if mode == 'SAM':
        k2 = _sam_k2(i, d)
        w2m = math.sqrt((e2 * i3 - l2) / (i2 * (i3 - i2)))
    else:
        k2 = _lam_k2(i, d)
        w2m = math.sqrt((l2 - e2 * i1) / (i2 * (i2 - i1)))
    u = np.arange(samples) * 4.0 * ellipk(k2) / samples
    sn, cn, dn, _ = ellipj(u, k2)
    if mode == 'SAM':
        return np.column_stack([w1m * cn, w2m * sn, w3m * dn])
    return np.column_stack([w1m * dn, w2m * sn, w3m * cn])


def mean_precession_rate(i: np.ndarray, d: float, momentum: float, mode: str,
                         samples: int = 512) -> float:
    """<phi'> [rad/d]: the time mean of L (Ia wa^2 + Ib wb^2) / (Ia^2 wa^2 + Ib^2 wb^2)."""
    w = _polhode(i, d, momentum, mode, samples)
    a, b = (0, 1) if mode == 'SAM' else (1, 2)
    num = i[a] * w[:, a] ** 2 + i[b] * w[:, b] ** 2
    den = i[a] ** 2 * w[:, a] ** 2 + i[b] ** 2 * w[:, b] ** 2
    return float(momentum * np.mean(num / den))


def dynamic_inertia_and_momentum(spin: TrueSpin) -> tuple[float, float]:
    """(D, |L|) of ``spin``: D = L^2/2E in units of I3, |L| [I3 rad/d]."""
    i = spin.moments
    if spin.mode == 'PA':
        return 1.0, 2.0 * math.pi / (spin.precession_period_h / 24.0)
    target = spin.rotation_period_h / spin.precession_period_h
    lo, hi = (i[1], i[2]) if spin.mode == 'SAM' else (i[0], i[1])
    margin = 1e-9 * (hi - lo)

    def excess(d: float) -> float:
        return (rotation_period(i, d, 1.0, spin.mode)
                * mean_precession_rate(i, d, 1.0, spin.mode) / (2.0 * math.pi) - target)

    a, b = lo + margin, hi - margin
    if excess(a) * excess(b) > 0.0:
        raise ValueError(f'TrueSpin: no {spin.mode} of ratios {spin.inertia_ratios} has '
                         f'P_psi / P_phi = {target:.6g}')
    d = brentq(excess, a, b, xtol=1e-15 * hi, rtol=1e-15, maxiter=200)
    momentum = rotation_period(i, d, 1.0, spin.mode) / (spin.rotation_period_h / 24.0)
    return float(d), float(momentum)


def initial_state(spin: TrueSpin) -> tuple[np.ndarray, np.ndarray]:
    """(w0 [rad/d] body axes, C0 body -> ecliptic J2000) at the epoch."""
    i = spin.moments
    d, momentum = dynamic_inertia_and_momentum(spin)
    frame = _abr_to_body(spin.mode)
    ia, ib, ir = frame.T @ i       # the moments about a, b, r
    phi, psi = spin.phases
    if spin.mode == 'PA':
        theta = math.pi if spin.anti_aligned else 0.0
    else:
        s = math.sin(psi) ** 2 / ia + math.cos(psi) ** 2 / ib
        cos2 = (1.0 / d - s) / (1.0 / ir - s)
        if not -1e-12 <= cos2 <= 1.0 + 1e-12:
            raise ValueError(f'TrueSpin: no theta0 for psi0 = {psi} (cos^2 = {cos2})')
        cos_theta = math.sqrt(min(1.0, max(0.0, cos2)))
        theta = math.acos(-cos_theta if spin.anti_aligned else cos_theta)
    to_abr = _rz(psi) @ _rx(theta) @ _rz(phi)          # L frame -> (a, b, r)
    l_body = frame @ (momentum * to_abr[:, 2])
    omega = l_body / i
    body_to_ecliptic = l_frame(spin.pole_deg) @ to_abr.T @ frame.T
    return omega, body_to_ecliptic


def _euler_rhs(moments: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """d/dt (w, C) of the free rigid body: Euler's equations, dC/dt = C [w]x (C row-major)."""
    i1, i2, i3 = (float(v) for v in moments)
    k1, k2, k3 = (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3
    out = np.empty(12)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        w1, w2, w3 = float(y[0]), float(y[1]), float(y[2])
        out[0], out[1], out[2] = k1 * w2 * w3, k2 * w3 * w1, k3 * w1 * w2
        c0, c1, c2 = y[3::3], y[4::3], y[5::3]     # the columns of C
        out[3::3] = c1 * w3 - c2 * w2
        out[4::3] = c2 * w1 - c0 * w3
        out[5::3] = c0 * w2 - c1 * w1
        return out.copy()
    return rhs


def integrate_attitude(spin: TrueSpin, jd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return w (n, 3) [rad/d] body axes, C (n, 3, 3) body -> ecliptic at ``jd`` [JD TDB].

    Euler's equations and dC/dt = C [w]x by DOP853 (rtol 1e-12, atol 1e-14 of the scale), from
    the epoch forwards to the later times and backwards to the earlier ones.
    """
    jd = np.asarray(jd, dtype=float)
    omega0, c0 = initial_state(spin)
    y0 = np.concatenate([omega0, c0.ravel()])
    scale = np.concatenate([np.full(3, np.linalg.norm(omega0)), np.ones(9)])
    rhs = _euler_rhs(spin.moments)
    out = np.empty((jd.size, 12))
    t = jd - spin.epoch_jd
    for select in (t >= 0.0, t < 0.0):
        if not np.any(select):
            continue
        times = t[select]
        order = np.argsort(np.abs(times), kind='stable')
        end = float(times[order[-1]])
        sol = solve_ivp(rhs, (0.0, end if end != 0.0 else 1e-9), y0, method='DOP853',
                        t_eval=times[order], rtol=RTOL, atol=1e-14 * scale)
        if not sol.success:
            raise RuntimeError(f'DOP853: {sol.message}')
        values = np.empty((times.size, 12))
        values[order] = sol.y.T
        out[select] = values
    return out[:, :3], out[:, 3:].reshape(-1, 3, 3)


# -- the brightness ----------------------------------------------------------------------------

def ellipsoid_of_inertia(inertia_ratios: Sequence[float]) -> np.ndarray:
    """Semi-axes (a, b, c) of the uniform ellipsoid of (I1/I3, I2/I3, 1), a = 1 (a > b > c)."""
    i1, i2, i3 = inertia_ratios[0], inertia_ratios[1], 1.0
    axes = np.sqrt(np.array([i2 + i3 - i1, i1 + i3 - i2, i1 + i2 - i3]))
    return axes / axes[0]


def _surface_grid(semi_axes: Sequence[float], nu: int,
                  nv: int) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals (m, 3) and area weights (m,) of the (u, v) midpoint grid."""
    a, b, c = semi_axes
    u = (np.arange(nu) + 0.5) * 2.0 * math.pi / nu
    v = (np.arange(nv) + 0.5) * math.pi / nv
    uu, vv = np.meshgrid(u, v, indexing='ij')
    su, cu, sv, cv = np.sin(uu), np.cos(uu), np.sin(vv), np.cos(vv)
    # r(u, v) = (a sv cu, b sv su, c cv); r_v x r_u = sv (bc sv cu, ac sv su, ab cv)
    normal = np.stack([b * c * sv * sv * cu, a * c * sv * sv * su, a * b * sv * cv], axis=-1)
    area = np.linalg.norm(normal, axis=-1)
    weight = area * (2.0 * math.pi / nu) * (math.pi / nv)
    return (normal / area[..., None]).reshape(-1, 3), weight.ravel()


def kaasalainen_law(mu0: np.ndarray, mu: np.ndarray, lambert: float = LAMBERT_WEIGHT
                    ) -> np.ndarray:
    """S = mu0 mu / (mu0 + mu) + c mu0 mu where both are > 0, else 0."""
    lit = (mu0 > 0.0) & (mu > 0.0)
    m0, m = np.where(lit, mu0, 0.0), np.where(lit, mu, 0.0)
    total = np.where(lit, m0 + m, 1.0)
    return np.where(lit, m0 * m / total + lambert * m0 * m, 0.0)


def ellipsoid_brightness(sun_body: np.ndarray, observer_body: np.ndarray,
                         semi_axes: Sequence[float], nu: int = 256, nv: int = 128,
                         lambert: float = LAMBERT_WEIGHT) -> np.ndarray:
    """
    Return the brightness B (n,) of the ellipsoid: the surface integral of S(mu0, mu).

    ``sun_body``, ``observer_body`` (n, 3) unit directions in body axes; semi-axes along x, y, z.
    """
    normals, weights = _surface_grid(semi_axes, nu, nv)
    out = np.empty(len(sun_body))
    block = max(1, 2 ** 21 // weights.size)
    for start in range(0, len(out), block):
        mu0 = sun_body[start:start + block] @ normals.T
        mu = observer_body[start:start + block] @ normals.T
        out[start:start + block] = kaasalainen_law(mu0, mu, lambert) @ weights
    return out


def sphere_brightness(phase: np.ndarray, radius: float = 1.0,
                      lambert: float = LAMBERT_WEIGHT) -> np.ndarray:
    """
    Return :func:`ellipsoid_brightness` of a sphere at phase angles ``phase`` [rad], exactly.

    Lommel-Seeliger: (pi R^2 / 2) (1 - sin(a/2) tan(a/2) ln cot(a/4)); Lambert:
    (2 R^2 / 3) (sin a + (pi - a) cos a).
    """
    a = np.asarray(phase, dtype=float)
    with np.errstate(divide='ignore', invalid='ignore'):
        ls = 1.0 - np.sin(a / 2) * np.tan(a / 2) * np.log(1.0 / np.tan(a / 4))
    ls = np.where(a == 0.0, 1.0, ls)
    lam = np.sin(a) + (math.pi - a) * np.cos(a)
    return radius ** 2 * (math.pi / 2.0 * ls + lambert * 2.0 / 3.0 * lam)


# -- the geometry ------------------------------------------------------------------------------

@dataclass(frozen=True)
class KeplerElements:
    """Heliocentric ecliptic J2000 elements: a [au], e, i, node, peri, M [deg] at the epoch."""

    a: float
    e: float
    i: float
    node: float
    peri: float
    mean_anomaly: float
    epoch_jd: float


#: The Earth-Moon barycentre, Standish's mean elements at J2000 (a, e, i, node, varpi - node,
#: L - varpi): 1.00000261 au, 0.01671123, -0.00001531 deg, 0, 102.93768193, 100.46457166 -
#: 102.93768193 deg.
EARTH = KeplerElements(1.00000261, 0.01671123, -0.00001531, 0.0, 102.93768193,
                       100.46457166 - 102.93768193, J2000)
#: (99942) Apophis, osculating elements at JD 2460200.5 (2023-09-13) as listed by Wikipedia's
#: infobox (from JPL): a 0.9227 au, e 0.19144, i 3.339, node 203.96, peri 126.60, M 142.9 deg.
#: Two-body propagation to 2012 or 2021 is only roughly Apophis's path (the close approaches
#: shift it): the geometry is realistic in kind, not an ephemeris.
APOPHIS = KeplerElements(0.9227, 0.19144, 3.339, 203.96, 126.60, 142.9, 2460200.5)


def kepler_position(elements: KeplerElements, jd: np.ndarray) -> np.ndarray:
    """Heliocentric ecliptic J2000 positions (n, 3) [au] at ``jd`` [JD TDB], two-body."""
    jd = np.asarray(jd, dtype=float)
    n = math.sqrt(GM_SUN / elements.a ** 3)
    m = np.radians(elements.mean_anomaly) + n * (jd - elements.epoch_jd)
    e = elements.e
    big_e = m.copy()
    for _ in range(50):
        step = (big_e - e * np.sin(big_e) - m) / (1.0 - e * np.cos(big_e))
        big_e -= step
        if np.max(np.abs(step)) < 1e-15:
            break
    x = elements.a * (np.cos(big_e) - e)
    y = elements.a * math.sqrt(1.0 - e * e) * np.sin(big_e)
    orbit = (_rz(-math.radians(elements.node)) @ _rx(-math.radians(elements.i))
             @ _rz(-math.radians(elements.peri)))
    return np.stack([x, y, np.zeros_like(x)], axis=-1) @ orbit.T


def _emission_geometry(asteroid: KeplerElements, jd_received: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t_e, asteroid -> Sun, asteroid -> observer) of reception times, light time iterated."""
    earth = kepler_position(EARTH, jd_received)
    t_e = jd_received.copy()
    for _ in range(5):
        ast = kepler_position(asteroid, t_e)
        t_e = jd_received - np.linalg.norm(earth - ast, axis=1) / C_AU_PER_DAY
    ast = kepler_position(asteroid, t_e)
    return t_e, -ast, earth - ast


def solar_elongation(asteroid: KeplerElements, jd: np.ndarray) -> np.ndarray:
    """Return the Sun-Earth-asteroid angle [deg] at ``jd``."""
    earth = kepler_position(EARTH, jd)
    ast = kepler_position(asteroid, jd)
    to_sun, to_ast = -earth, ast - earth
    cos = np.sum(to_sun * to_ast, axis=1) / (np.linalg.norm(to_sun, axis=1)
                                             * np.linalg.norm(to_ast, axis=1))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


@dataclass(frozen=True)
class Apparition:
    """
    One observing season: ``nights`` nights between ``start_jd`` and ``end_jd`` [JD].

    ``points`` in all (shared by the nights in proportion to their length); each night's run
    lasts ``hours`` (low, high) [h], drawn uniformly; ``min_elongation`` [deg].
    """

    start_jd: float
    end_jd: float
    nights: int
    points: int
    hours: tuple[float, float] = (2.0, 7.0)
    min_elongation: float = 60.0


def observing_nights(apparition: Apparition, asteroid: KeplerElements,
                     rng: np.random.Generator) -> list[np.ndarray]:
    """Return the reception times [JD] of each night: moon and elongation gaps, weather, runs."""
    candidates = np.arange(math.ceil(apparition.start_jd), math.floor(apparition.end_jd)) + 0.8
    lunar_age = (candidates - FULL_MOON_JD) % SYNODIC_MONTH
    dark = np.minimum(lunar_age, SYNODIC_MONTH - lunar_age) > 3.5
    visible = solar_elongation(asteroid, candidates) >= apparition.min_elongation
    usable = candidates[dark & visible]
    if usable.size < apparition.nights:
        raise ValueError(f'Apparition: {usable.size} usable nights in the window, '
                         f'{apparition.nights} asked')
    chosen = np.sort(rng.choice(usable, apparition.nights, replace=False))
    hours = rng.uniform(*apparition.hours, size=chosen.size)
    counts = np.maximum(3, np.round(apparition.points * hours / hours.sum())).astype(int)
    counts[-1] = max(3, counts[-1] + apparition.points - counts.sum())
    start = chosen + rng.uniform(-0.1, 0.1, size=chosen.size)
    return [s + np.linspace(0.0, h / 24.0, k) for s, h, k in zip(start, hours, counts)]


# -- the campaign ------------------------------------------------------------------------------

@dataclass(frozen=True)
class SyntheticCampaign:
    """
    A campaign's truth and its noiseless photometry; :func:`draw` adds noise and offsets.

    ``jd`` emission times [JD TDB]; ``sun``, ``observer`` (n, 3) [au] ecliptic J2000 from the
    asteroid; ``model`` (n,) noiseless magnitudes [mag] (no offsets); ``block`` (n,) night
    index; ``sigma`` (n,) the 1-sigma errors [mag] of each night; ``omega``, ``attitude`` the
    integrated w [rad/d] and C (body -> ecliptic); ``semi_axes`` the ellipsoid's.
    """

    truth: TrueSpin
    jd: np.ndarray
    sun: np.ndarray
    observer: np.ndarray
    model: np.ndarray
    block: np.ndarray
    sigma: np.ndarray
    omega: np.ndarray
    attitude: np.ndarray
    semi_axes: np.ndarray
    phase_slope: float
    names: tuple[str, ...] = field(default=())


def magnitudes(attitude: np.ndarray, sun: np.ndarray, observer: np.ndarray,
               semi_axes: Sequence[float], phase_slope: float, nu: int = 256,
               nv: int = 128) -> np.ndarray:
    """
    Return m = -2.5 log10(B / B_ref) + 5 log10(r Delta) + slope * alpha [deg].

    B_ref: the zero-phase brightness of the sphere of the ellipsoid's volume (closed form).
    """
    r = np.linalg.norm(sun, axis=1)
    delta = np.linalg.norm(observer, axis=1)
    s_body = np.einsum('nji,nj->ni', attitude, sun / r[:, None])
    o_body = np.einsum('nji,nj->ni', attitude, observer / delta[:, None])
    b = ellipsoid_brightness(s_body, o_body, semi_axes, nu, nv)
    radius = float(np.prod(semi_axes)) ** (1.0 / 3.0)
    reference = float(sphere_brightness(np.array([0.0]), radius)[0])
    alpha = np.degrees(np.arccos(np.clip(np.sum(s_body * o_body, axis=1), -1.0, 1.0)))
    return -2.5 * np.log10(b / reference) + 5.0 * np.log10(r * delta) + phase_slope * alpha


def make_campaign(truth: TrueSpin, apparitions: Sequence[Apparition], seed: int = 0,
                  asteroid: KeplerElements = APOPHIS, semi_axes: Sequence[float] | None = None,
                  phase_slope: float = 0.03, sigma: tuple[float, float] = (0.01, 0.03),
                  nu: int = 256, nv: int = 128) -> SyntheticCampaign:
    """
    Make the noiseless campaign of ``truth`` over ``apparitions`` (sampling from ``seed``).

    ``semi_axes`` default: the uniform ellipsoid of the inertia ratios; ``sigma`` the range of
    each night's 1-sigma error [mag].
    """
    rng = np.random.default_rng(seed)
    nights: list[np.ndarray] = []
    for apparition in apparitions:
        nights.extend(observing_nights(apparition, asteroid, rng))
    received = np.concatenate(nights)
    block = np.concatenate([np.full(t.size, k) for k, t in enumerate(nights)])
    night_sigma = rng.uniform(*sigma, size=len(nights))
    t_e, sun, observer = _emission_geometry(asteroid, received)
    if not t_e[0] - 30.0 <= truth.epoch_jd <= t_e[-1] + 30.0:
        raise ValueError(f'make_campaign: the epoch JD {truth.epoch_jd} is outside the campaign '
                         f'(JD {t_e[0]:.1f} to {t_e[-1]:.1f}): integrating to it would take long')
    axes = np.asarray(ellipsoid_of_inertia(truth.inertia_ratios) if semi_axes is None
                      else semi_axes, dtype=float)
    omega, attitude = integrate_attitude(truth, t_e)
    model = magnitudes(attitude, sun, observer, axes, phase_slope, nu, nv)
    names = tuple(f'synthetic night {k} (JD {t[0]:.1f})' for k, t in enumerate(nights))
    return SyntheticCampaign(truth, t_e, sun, observer, model, block, night_sigma[block],
                             omega, attitude, axes, phase_slope, names)


def draw(synthetic: SyntheticCampaign, rng: np.random.Generator, offset_sigma: float = 0.3,
         free_offsets: bool = True) -> Campaign:
    """
    Return one noise draw: Gaussian noise of each point's sigma, an offset per night [mag].

    ``free_offsets`` False: no offsets, the blocks calibrated (absolute magnitudes).
    """
    nights = len(synthetic.names)
    offsets = rng.normal(0.0, offset_sigma, size=nights) if free_offsets else np.zeros(nights)
    noise = rng.normal(0.0, 1.0, size=synthetic.jd.size) * synthetic.sigma
    return Campaign(synthetic.jd, synthetic.model + offsets[synthetic.block] + noise,
                    synthetic.sigma, synthetic.sun, synthetic.observer, synthetic.block,
                    synthetic.names, (free_offsets,) * nights, source='synthetic_campaigns',
                    light_time_corrected=True,
                    notes=(f'injected {synthetic.truth}',))


# -- the literature's Apophis ------------------------------------------------------------------

#: Pravec et al. 2014 (Icarus 233, 48): SAM, P_phi = 27.38 +- 0.07 h, P_psi = 263 +- 6 h (3
#: sigma), L at ecliptic (250, -75) deg, I1/I3 = 0.61, I2/I3 = 0.965 (as the project's
#: config/tumbling_from_observables.yaml cites them); phases ours.
APOPHIS_PRAVEC_2014 = TrueSpin('SAM', 27.38, 263.0, (0.61, 0.965), (250.0, -75.0),
                               (0.3, 1.1), epoch_jd=2456293.5)
#: Lee et al. 2022 (A&A 661, L3, abstract): SAM, P_phi = 27.38547 h, P_psi = 264.178 h,
#: L at (275, -85) deg, Ia : Ib : Ic = 0.64 : 0.97 : 1; phases ours.
APOPHIS_LEE_2022 = replace(APOPHIS_PRAVEC_2014, precession_period_h=27.38547,
                           rotation_period_h=264.178, inertia_ratios=(0.64, 0.97),
                           pole_deg=(275.0, -85.0))
#: 2012 Dec 23 - 2013 Apr 15 (Pravec et al. 2014's campaign, several telescopes).
APOPHIS_2012_13 = Apparition(2456284.5, 2456397.5, 40, 800)
#: 2020 Nov 16 - 2021 May 6: one telescope's 1280 points on 67 nights (the Danish 1.54 m at
#: La Silla, Durech et al., EPSC 2024-257 abstract).
APOPHIS_2020_21 = Apparition(2459169.5, 2459340.5, 67, 1280)

"""
Apophis at the new depth: the encounter past the quadrupole, with the Moon and the Sun.

What the encounter ensemble (:mod:`.encounter`) needs to go past a rigid quadrupole under a
point-mass Earth:

* :func:`degree3_sensitivity`: the change of the spin state after the flyby (P_phi, P_psi [s],
  pole [deg], |w|) per unit change of each degree-3 Stokes coefficient of the body's field
  (C30, C31, S31, C32, S32, C33, S33), by central finite differences at two steps (the
  second a check of linearity), for given initial states (:func:`phase_states`: phases of the
  tumbling cycle). Degree-3 moments do not move the centre of mass (degree 1) nor change the
  inertia (degree 2), so the field stays in its centre-of-mass principal frame
  (:func:`with_coefficient`; ``GravityField`` checks degrees 1 and 2 only).
* :func:`stokes_per_k`: the unnormalised C_nm (or S_nm) of a change of 1 in Dinsmore & de Wit's
  K_nm (2023, MNRAS 520, 3459, app. A; for a uniform density):
  K_nm = (-1)^m (M a_A^2 / I_A) (R / a_A)^n (C_nm + i S_nm) / ((2 - delta_m0) (n - m)!),
  I_A = (A + B + C) / 2 and a_A^2 = I_A / M.
* :func:`lunisolar_perturbers`: the Moon and the Sun relative to the asteroid as tabulated
  ephemerides: the Earth's position relative to the asteroid (the scenario's hyperbola) plus
  the geocentric Moon and Sun of the Astronomical Almanac's low-precision formulae
  (:func:`moon_geocentric`, :func:`sun_geocentric`).
* :func:`coupling_size`: the coupled orbit-attitude run (:mod:`~tumble_ros.core.propagation.
  coupled`) against the same equations on the fixed hyperbola, after the flyby.

Units: times [yr] inside (the scenario's), periods reported in seconds, angles in degrees;
positions [km] in the scenario's orbital frame (ecliptic J2000 for Apophis).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core import IntegratorSettings, Scenario, simulate_ensemble
from tumble_ros.core.model.gravity_field import GravityField
from tumble_ros.core.model.rotation import euler_to_quaternion
from tumble_ros.core.model.spinstate import spin_state
from tumble_ros.core.torques.ephemeris import Ephemeris
from tumble_ros.core.torques.perturbers import Perturber
from tumble_ros.core.units import GM_MOON, GM_SUN, HOURS_PER_YEAR, KM_PER_AU

from .encounter import EncounterResult, tumbler_states

__all__ = ['DEGREE3', 'OUTPUTS', 'with_coefficient', 'stokes_per_k', 'phase_states',
           'Sensitivity', 'degree3_sensitivity', 'moon_geocentric', 'sun_geocentric',
           'lunisolar_perturbers', 'coupling_size', 'after_state', 'EARTH_RADIUS_KM',
           'J2000_JD', 'distribution_table', 'paired_differences', 'depth_figure']

#: The degree-3 coefficients: (C or S, n, m).
DEGREE3 = (('C', 3, 0), ('C', 3, 1), ('S', 3, 1), ('C', 3, 2), ('S', 3, 2), ('C', 3, 3),
           ('S', 3, 3))
#: What is differentiated: P_phi [s], P_psi [s], the pole [deg], |w| after / |w| before.
OUTPUTS = ('P_phi [s]', 'P_psi [s]', 'pole [deg]', '|w| ratio')
#: The Earth's equatorial radius [km] of the Moon's horizontal parallax.
EARTH_RADIUS_KM = 6378.14
#: Julian date of J2000.0 (TT).
J2000_JD = 2451545.0
_SECONDS_PER_YEAR = HOURS_PER_YEAR * 3600.0


def with_coefficient(field: GravityField, kind: str, n: int, m: int,
                     value: float) -> GravityField:
    """Return ``field`` with C_nm (``kind`` 'C') or S_nm ('S') set to ``value``, n >= 3."""
    if kind not in ('C', 'S') or not 3 <= n <= field.degree or not 0 <= m <= n or (
            kind == 'S' and m == 0):
        raise ValueError(f'coefficient: must be C or S of degree 3 ... {field.degree}, order '
                         f'0 ... n (S: 1 ... n), got {kind}{n}{m}')
    c, s = field.C.copy(), field.S.copy()
    (c if kind == 'C' else s)[n, m] = value
    return GravityField(field.mass, field.reference_radius, c, s, field.principal_moments)


def stokes_per_k(field: GravityField, n: int, m: int) -> float:
    """
    Return |C_nm| (or |S_nm|) of |K_nm| = 1 (Dinsmore & de Wit's moments), uniform density.

    (2 - delta_m0) (n - m)! (a_A / R)^n with a_A^2 = (A + B + C) / (2 M) [km^2] (I_A = M a_A^2
    for a uniform body) and R the field's reference radius.
    """
    a_a = math.sqrt(sum(field.principal_moments) / (2.0 * field.mass))
    return (2.0 - (m == 0)) * math.factorial(n - m) * (a_a / field.reference_radius) ** n


def phase_states(scenario: Scenario, phases: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (omega0, euler0) of the scenario's observed spin state at ``phases`` of P_psi.

    The periods and pole of the scenario's ``omega0``/``euler0``, turn 0 about L
    (:func:`~.encounter.tumbler_states`).
    """
    observed = spin_state(scenario.omega0, scenario.inertia,
                          euler_to_quaternion(*scenario.euler0))
    phase = np.atleast_1d(np.asarray(phases, dtype=float))
    assert observed.pole is not None    # (a spin state with an attitude has its pole)
    return tumbler_states(scenario.inertia, observed.precession_period,
                          observed.rotation_period, observed.pole, phase, np.zeros(phase.size))


def after_state(omega: npt.ArrayLike, quaternion: npt.ArrayLike,
                inertia: Sequence[float]) -> np.ndarray:
    """
    Return (P_phi [s], P_psi [s], pole x, y, z, |w| [rad/yr]) of samples (n, 3), (n, 4).

    Periods NaN where not defined (a rotation about a principal axis).
    """
    w = np.atleast_2d(np.asarray(omega, dtype=float))
    q = np.atleast_2d(np.asarray(quaternion, dtype=float))
    out = np.full((len(w), 6), math.nan)
    for k in range(len(w)):
        state = spin_state(w[k], inertia, q[k])
        for j, value in enumerate((state.precession_period, state.rotation_period)):
            if value is not None and math.isfinite(value):
                out[k, j] = value * _SECONDS_PER_YEAR
        assert state.pole is not None
        out[k, 2:5] = state.pole
        out[k, 5] = float(np.linalg.norm(w[k]))
    return out


@dataclass(frozen=True)
class Sensitivity:
    """
    d(output)/d(coefficient) after the flyby, per unit change of each degree-3 coefficient.

    ``derivative``: (7, len(deltas), n_states, 4): :data:`DEGREE3` x steps x initial states x
    :data:`OUTPUTS` (P_phi, P_psi [s per unit C], pole [deg per unit C]: the angle between
    the poles of +delta and -delta over 2 delta, |w| ratio per unit C). ``base``: (n_states, 6)
    the nominal field's :func:`after_state`. ``per_k``: (7,) |C| of |K| = 1 per coefficient.
    """

    deltas: tuple[float, ...]
    derivative: np.ndarray
    base: np.ndarray
    per_k: np.ndarray

    @property
    def median(self) -> np.ndarray:
        """Return the median over the states of |derivative| at the first step, (7, 4)."""
        out: np.ndarray = np.nanmedian(np.abs(self.derivative[:, 0]), axis=1)
        return out

    @property
    def linearity(self) -> np.ndarray:
        """Return max over states of |d(2 delta) - d(delta)| / |d(delta)|, (7, 4)."""
        d1, d2 = self.derivative[:, 0], self.derivative[:, -1]
        with np.errstate(invalid='ignore', divide='ignore'):
            out: np.ndarray = np.nanmax(np.abs(d2 - d1) / np.abs(d1), axis=1)
        return out


def degree3_sensitivity(scenario: Scenario, omega0: npt.ArrayLike, euler0: npt.ArrayLike,
                        deltas: Sequence[float] = (0.01, 0.02), *, rtol: float = 1e-13,
                        ) -> Sensitivity:
    """
    Return the :class:`Sensitivity` of the state after the flyby to the degree-3 moments.

    ``scenario``: with ``gravity_degree`` >= 3 and its ``gravity_field`` (the nominal body);
    ``omega0`` (n, 3) [rad/yr], ``euler0`` (n, 3) [rad]: the initial states (e.g.
    :func:`phase_states`). Each coefficient is set to nominal +- delta (central differences)
    and the n bodies integrated by the compiled ensemble with DOP853 at ``rtol`` (and atol
    ``rtol`` times the largest |w0|).
    """
    field = scenario.gravity_field
    if field is None or scenario.gravity_degree < 3:
        raise ValueError(f'gravity.degree: the sensitivity to degree 3 needs a field to degree '
                         f'>= 3, got degree {scenario.gravity_degree}')
    w0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    e0 = np.atleast_2d(np.asarray(euler0, dtype=float))
    scale = float(np.max(np.linalg.norm(w0, axis=1)))
    tight = scenario.replace(integrator=IntegratorSettings(method='dop853', rtol=rtol,
                                                           atol=rtol * scale))
    before = np.linalg.norm(w0, axis=1)

    def after(sc: Scenario) -> np.ndarray:
        run = simulate_ensemble(sc, [0.0, sc.duration], omega0=w0, euler0=e0)
        return after_state(run.omega[:, -1], run.quaternion[:, -1], sc.inertia)

    base = after(tight)
    derivative = np.empty((len(DEGREE3), len(deltas), len(w0), 4))
    for i, (kind, n, m) in enumerate(DEGREE3):
        nominal = float((field.C if kind == 'C' else field.S)[n, m])
        for j, delta in enumerate(deltas):
            plus, minus = (after(tight.replace(gravity_field=with_coefficient(
                field, kind, n, m, nominal + sign * delta))) for sign in (1.0, -1.0))
            derivative[i, j, :, :2] = (plus[:, :2] - minus[:, :2]) / (2.0 * delta)
            derivative[i, j, :, 2] = _angle(plus[:, 2:5], minus[:, 2:5]) / (2.0 * delta)
            derivative[i, j, :, 3] = (plus[:, 5] - minus[:, 5]) / before / (2.0 * delta)
    per_k = np.array([stokes_per_k(field, n, m) for _, n, m in DEGREE3])
    return Sensitivity(tuple(float(d) for d in deltas), derivative, base, per_k)


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the angle between unit vectors [deg] (atan2 of |a x b| and a.b: exact near 0)."""
    out: np.ndarray = np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1),
                                            np.sum(a * b, axis=-1)))
    return out


def _spherical(lon_deg: np.ndarray, lat_deg: np.ndarray, distance: np.ndarray) -> np.ndarray:
    lon, lat = np.radians(lon_deg), np.radians(lat_deg)
    return np.stack([distance * np.cos(lat) * np.cos(lon), distance * np.cos(lat) * np.sin(lon),
                     distance * np.sin(lat)], axis=-1)


def _precession(jd: np.ndarray) -> np.ndarray:
    """Return the general precession in longitude since J2000 [deg] (1.396971 deg/century)."""
    return 1.396971 * (jd - J2000_JD) / 36525.0


def moon_geocentric(jd: npt.ArrayLike) -> np.ndarray:
    """
    Return the Moon's geocentric position [km], ecliptic J2000, at Julian dates ``jd`` (TT).

    The Astronomical Almanac's low-precision formulae (longitude, latitude and horizontal
    parallax, mean ecliptic and equinox of date; good to ~0.3 deg in longitude, ~0.2 deg in
    latitude and ~0.003 deg in parallax, i.e. ~0.3 % in distance), the longitude turned back to
    J2000 by the general precession (0.41 deg by 2029).
    """
    jd = np.asarray(jd, dtype=float)
    t = (jd - J2000_JD) / 36525.0

    def s(a: float, b: float) -> np.ndarray:
        return np.sin(np.radians(a + b * t))

    def c(a: float, b: float) -> np.ndarray:
        return np.cos(np.radians(a + b * t))

    lon = (218.32 + 481267.881 * t + 6.29 * s(135.0, 477198.87) - 1.27 * s(259.3, -413335.36)
           + 0.66 * s(235.7, 890534.22) + 0.21 * s(269.9, 954397.74)
           - 0.19 * s(357.5, 35999.05) - 0.11 * s(186.5, 966404.03))
    lat = (5.13 * s(93.3, 483202.02) + 0.28 * s(228.2, 960400.89) - 0.28 * s(318.3, 6003.15)
           - 0.17 * s(217.6, -407332.21))
    parallax = (0.9508 + 0.0518 * c(135.0, 477198.87) + 0.0095 * c(259.3, -413335.36)
                + 0.0078 * c(235.7, 890534.22) + 0.0028 * c(269.9, 954397.74))
    distance = EARTH_RADIUS_KM / np.sin(np.radians(parallax))
    return _spherical(lon - _precession(jd), lat, distance)


def sun_geocentric(jd: npt.ArrayLike) -> np.ndarray:
    """
    Return the Sun's geocentric position [km], ecliptic J2000, at Julian dates ``jd`` (TT).

    The Astronomical Almanac's low-precision formulae (ecliptic longitude of date to ~0.01 deg,
    distance R = 1.00014 - 0.01671 cos g - 0.00014 cos 2g au, latitude 0), the longitude turned
    back to J2000 by the general precession.
    """
    jd = np.asarray(jd, dtype=float)
    n = jd - J2000_JD
    g = np.radians(357.528 + 0.9856003 * n)
    lon = 280.460 + 0.9856474 * n + 1.915 * np.sin(g) + 0.020 * np.sin(2.0 * g)
    distance = (1.00014 - 0.01671 * np.cos(g) - 0.00014 * np.cos(2.0 * g)) * KM_PER_AU
    return _spherical(lon - _precession(jd), np.zeros_like(lon), distance)


def lunisolar_perturbers(scenario: Scenario, perigee_jd: float,
                         step: float = 5.0 / 60.0 / HOURS_PER_YEAR,
                         ) -> tuple[Perturber, Perturber]:
    """
    Return the Moon and the Sun as perturbers of the scenario's flyby (tabulated).

    Their position relative to the asteroid is the Earth's (the scenario's first perturber's
    Kepler orbit, whose pericentre time ``t_p`` is at Julian date ``perigee_jd``, TT/TDB) plus
    their geocentric one (:func:`moon_geocentric`, :func:`sun_geocentric`), in the scenario's
    orbital frame (it must be ecliptic J2000, as ``apophis_2029.yaml``'s), tabulated every
    ``step`` [yr] (default 5 min: a table that fine is the Kepler orbit to ~1e-12,
    docs/physics.md "Ephemerides") from one step before the start to one after the end.
    """
    orbit = scenario.primary_orbit
    if orbit is None:
        raise ValueError('lunisolar_perturbers: needs a flyby (orbit.kind flyby), got none')
    t = np.arange(-step, scenario.duration + 2.0 * step, step)
    earth = orbit.position(t)
    jd = perigee_jd + (t - orbit.t_p) * HOURS_PER_YEAR / 24.0
    out = []
    for name, gm, geocentric in (('moon', GM_MOON, moon_geocentric),
                                 ('sun', GM_SUN, sun_geocentric)):
        position = earth + geocentric(jd)
        table = Ephemeris(tuple(float(v) for v in t), tuple(map(tuple, position)))
        out.append(Perturber(name, table, gm=gm))
    return out[0], out[1]


def coupling_size(scenario: Scenario, field: GravityField, omega0: npt.ArrayLike,
                  euler0: npt.ArrayLike, *, rtol: float = 1e-13) -> np.ndarray:
    """
    Return |coupled - fixed hyperbola| after the flyby: (n, 4) P_phi, P_psi [s], pole [deg], |w|.

    Each initial state (``omega0`` (n, 3) [rad/yr], ``euler0`` (n, 3) [rad]) run by
    :func:`~tumble_ros.core.propagation.coupled.propagate_coupled` with the body ``field`` to
    its degree, with and without the orbit's reaction; the scenario must have the Earth alone
    (its flyby). |w| as the relative difference.
    """
    from tumble_ros.core.propagation.coupled import CoupledBody, propagate_coupled

    body = CoupledBody(field)
    w0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    e0 = np.atleast_2d(np.asarray(euler0, dtype=float))
    plain = scenario.replace(gravity_degree=2, gravity_field=None, body=type(scenario.body)())
    out = np.empty((len(w0), 4))
    for k in range(len(w0)):
        sc = plain.replace(omega0=tuple(w0[k]), euler0=tuple(e0[k]))
        states = []
        for coupled in (True, False):
            run = propagate_coupled(sc, body, [0.0, sc.duration], coupled=coupled, rtol=rtol)
            if not run.success:
                raise RuntimeError(f'coupled: the run failed: {run.message}')
            states.append(after_state(run.omega[-1], run.quaternion[-1], sc.inertia)[0])
        a, b = states
        out[k] = (abs(a[0] - b[0]), abs(a[1] - b[1]), float(_angle(a[2:5], b[2:5])),
                  abs(a[5] - b[5]) / b[5])
    return out


def _row(values: np.ndarray, fmt: str) -> list[str]:
    v = values[np.isfinite(values)]
    p = np.percentile(v, [5, 50, 95, 0, 100])
    return [fmt.format(p[0]), fmt.format(p[1]), fmt.format(p[2]),
            f'{fmt.format(p[3])} – {fmt.format(p[4])}']


def distribution_table(results: dict[str, EncounterResult]) -> str:
    """
    Return a Markdown table of the ensembles side by side: 5 %, median, 95 %, range.

    Rows: P_phi [h], P_psi [h], |w| after / before, pole shift [deg], then the short-axis
    fraction and the fraction of poles moved by 10 deg or more; one group of columns per
    ensemble (``results``: name -> :class:`~.encounter.EncounterResult`).
    """
    h = HOURS_PER_YEAR
    names = list(results)
    quantities = (
        ('P_phi [h]', lambda r: r.precession_after * h, '{:.2f}'),
        ('P_psi [h]', lambda r: r.rotation_after * h, '{:.1f}'),
        ('|w| after / before', lambda r: r.spin_rate_after / r.spin_rate_before, '{:.4f}'),
        ('pole shift [deg]', lambda r: np.degrees(r.pole_shift), '{:.3f}'),
    )
    head = '| after the flyby | ' + ' | '.join(
        f'{n}: 5 % | median | 95 % | range' for n in names) + ' |'
    lines = [head, '|---' * (1 + 4 * len(names)) + '|']
    for label, get, fmt in quantities:
        cells = [c for n in names for c in _row(get(results[n]), fmt)]
        lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
    for label, get in (('SAM after [%]', lambda r: 100 * np.mean(r.mode_after == 'SAM')),
                       ('pole shift >= 10 deg [%]',
                        lambda r: 100 * np.mean(np.degrees(r.pole_shift) >= 10.0))):
        cells = [c for n in names for c in (f'{get(results[n]):.1f}', '', '', '')]
        lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def paired_differences(a: EncounterResult, b: EncounterResult) -> dict[str, np.ndarray]:
    """
    Return body-by-body |b - a| after the flyby (the same draws): P_phi, P_psi [s], pole [deg].

    Also 'mode' (bool: the mode after differs) and '|w|' (relative). The two ensembles must
    have the same bodies (same seed, draws and phases).
    """
    if not (np.array_equal(a.phase, b.phase) and np.array_equal(a.turn, b.turn)):
        raise ValueError('paired_differences: the ensembles do not have the same bodies')
    s = HOURS_PER_YEAR * 3600.0
    return {'P_phi [s]': np.abs(b.precession_after - a.precession_after) * s,
            'P_psi [s]': np.abs(b.rotation_after - a.rotation_after) * s,
            'pole [deg]': _angle(a.pole_after, b.pole_after),
            '|w|': np.abs(b.spin_rate_after - a.spin_rate_after) / a.spin_rate_after,
            'mode': a.mode_after != b.mode_after}


def depth_figure(results: dict[str, EncounterResult],
                 steps: dict[str, dict[str, np.ndarray]], precision: float = 0.27) -> bytes:
    """
    Return a PNG: the ensembles' distributions after the flyby, and their paired differences.

    Top: the cumulative distributions of P_phi, P_psi and the pole shift of each ensemble;
    bottom: body-by-body |differences| of each step (``steps``: name ->
    :func:`paired_differences`) in P_phi, P_psi [s] and the pole [deg], with the period
    precision ``precision`` [s] marked.
    """
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    h = HOURS_PER_YEAR
    fig = Figure(figsize=(13, 8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 3)
    styles = ('-', '--', ':', '-.')
    for ax, label, get in ((axes[0, 0], '$P_\\phi$ after [h]', lambda r: r.precession_after * h),
                           (axes[0, 1], '$P_\\psi$ after [h]', lambda r: r.rotation_after * h),
                           (axes[0, 2], 'pole shift [deg]',
                            lambda r: np.degrees(r.pole_shift))):
        for (name, result), ls in zip(results.items(), styles):
            v = np.sort(get(result)[np.isfinite(get(result))])
            ax.plot(v, np.arange(1, v.size + 1) / v.size, ls=ls, label=name)
        ax.set_xlabel(label)
        ax.set_ylabel('fraction of bodies')
        ax.legend(fontsize=8)
    for ax, key in zip(axes[1], ('P_phi [s]', 'P_psi [s]', 'pole [deg]')):
        for (name, diff), ls in zip(steps.items(), styles):
            v = np.sort(np.maximum(diff[key][np.isfinite(diff[key])], 1e-12))
            ax.plot(v, np.arange(1, v.size + 1) / v.size, ls=ls, label=name)
        if key != 'pole [deg]':
            ax.axvline(precision, color='k', lw=0.8, label=f'{precision:g} s')
        ax.set_xscale('log')
        ax.set_xlabel(f'|difference| body by body, {key}')
        ax.set_ylabel('fraction of bodies')
        ax.legend(fontsize=8)
    fig.suptitle('Apophis 2029 at the new depth: the ensembles after the flyby (top) and what '
                 'each step changes body by body (bottom)')
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format='png', dpi=100)
    return buffer.getvalue()

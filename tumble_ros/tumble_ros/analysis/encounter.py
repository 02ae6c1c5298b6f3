"""
What an encounter does to a tumbler: the spin state before and after, over what is uncertain.

A close planetary flyby (the scenario's ``orbit.kind: flyby``, e.g. Apophis and the Earth on
2029-04-13: config/apophis_2029.yaml) changes a tumbler's spin by the tidal torque near perigee.
How much depends on where the body is in its tumbling cycle at perigee, which photometry does
not pin down, and on its moments of inertia. This module runs that Monte Carlo:

* the observables are kept: every body has the nominal scenario's precession and rotation
  periods and pole (the photometric solution), recomputed from its ``omega0``/``euler0`` with
  :func:`~tumble_ros.core.model.spinstate.spin_state`;
* what is drawn: the moments of inertia (a uniform spread around the nominal ratios), the phase
  of the tumbling cycle (the polhode, a uniform fraction of P_psi) and the body's turn about its
  angular momentum (uniform in [0, 2 pi));
* each body is integrated through the encounter by the compiled ensemble
  (:func:`~tumble_ros.core.simulate_ensemble`, one call per inertia sample; or the run layer's
  :func:`tumble_ros.ensembles.run_ensemble` on a Dask client, given as ``run``), and its spin
  state at the start and the end is compared: mode, periods, spin rate |w|, pole shift.

Units: times [yr] inside, periods shown in hours; angles [rad] inside, degrees in the report.
Frames: the scenario's orbital frame (for Apophis, ecliptic J2000), body principal axes.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math
import os
from pathlib import Path
from typing import Callable

import numpy as np
import numpy.typing as npt

from tumble_ros.core import (EnsembleResult, IntegratorSettings, Scenario, ScenarioError, simulate,
                             simulate_ensemble)
from tumble_ros.core.model.mass_models import Ellipsoid
from tumble_ros.core.model.rotation import (euler_to_quaternion, matrix_to_euler,
                                            quaternion_to_matrix)
from tumble_ros.core.model.spinstate import omega_for_periods, spin_state
from tumble_ros.core.units import HOURS_PER_YEAR

from .display import longitude_degrees

__all__ = ['EncounterResult', 'encounter_ensemble', 'tumbler_states', 'format_encounter',
           'encounter_figure', 'draw_encounter', 'encounter_memory', 'MAX_INERTIA_SPREAD',
           'BYTES_PER_BODY', 'with_inertia']

#: Memory one body of an encounter ensemble holds while it runs and is reported [bytes]: its
#: inputs, its two samples, its spin states before and after and the saved arrays (measured
#: 3.2 kB: peak RSS 234 MB with 2,000 bodies, 290 MB with 20,000; rounded up: docs/ros.md
#: "Limits of the inputs").
BYTES_PER_BODY = 4_000
#: Largest half-width of the spread of I_a/I_c and I_b/I_c (both ratios lie in (0, 1]).
MAX_INERTIA_SPREAD = 0.5


def _available_memory() -> int:
    """Return the memory this machine can give a process now [bytes] (MemAvailable)."""
    try:
        with open('/proc/meminfo', encoding='ascii') as meminfo:
            for line in meminfo:
                if line.startswith('MemAvailable:'):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES')


def encounter_memory(n_bodies: int) -> int:
    """Return the memory an encounter ensemble of ``n_bodies`` needs [bytes] (an estimate)."""
    return int(n_bodies) * BYTES_PER_BODY


def _check_size(n_bodies: int, n_inertia: int, inertia_spread) -> None:
    """Refuse, before any work, an ensemble that cannot fit in memory or bad spreads."""
    if n_bodies < 1 or n_inertia < 1 or n_inertia > n_bodies:
        raise ScenarioError(f'encounter_ensemble: needs 1 <= n_inertia <= n_bodies, got '
                            f'{n_inertia}, {n_bodies}')
    for name, value in zip(('I_a/I_c', 'I_b/I_c'), inertia_spread):
        if not (math.isfinite(value) and 0.0 <= value <= MAX_INERTIA_SPREAD):
            raise ScenarioError(f'inertia spread of {name}: must be a finite number in '
                                f'[0, {MAX_INERTIA_SPREAD:g}], got {value!r}')
    need, have = encounter_memory(n_bodies), _available_memory()
    if need > have:
        raise ScenarioError(f'bodies: {n_bodies:,} bodies would need about {need / 1e9:,.1f} GB '
                            f'of memory ({BYTES_PER_BODY:,} bytes a body), {have / 1e9:.3g} GB '
                            'are available here; use fewer bodies')


@dataclass(frozen=True)
class EncounterResult:
    """
    The spin state of N bodies before (t = 0) and after (t = duration) the encounter.

    Attributes
    ----------
    inertia : (N, 3) principal moments (the nominal I3 kept).
    phase : (N,) phase in the tumbling cycle at t = 0, fraction of P_psi.
    turn : (N,) turn about the angular momentum at t = 0 [rad].
    mode_before, mode_after : N strings ('SAM', 'LAM', ...).
    precession_before, precession_after, rotation_before, rotation_after : (N,) P_phi, P_psi
        [yr].
    spin_rate_before, spin_rate_after : (N,) |w| [rad/yr].
    pole_before, pole_after : (N, 3) unit L in the orbital frame.
    success : (N,) bool (a body whose integration failed has NaN after).
    scenario : the nominal scenario.

    """

    inertia: np.ndarray
    phase: np.ndarray
    turn: np.ndarray
    mode_before: np.ndarray
    mode_after: np.ndarray
    precession_before: np.ndarray
    precession_after: np.ndarray
    rotation_before: np.ndarray
    rotation_after: np.ndarray
    spin_rate_before: np.ndarray
    spin_rate_after: np.ndarray
    pole_before: np.ndarray
    pole_after: np.ndarray
    success: np.ndarray
    scenario: Scenario

    @property
    def pole_shift(self) -> np.ndarray:
        """Return the angle between the pole before and after [rad], (N,)."""
        cosine = np.sum(self.pole_before * self.pole_after, axis=1)
        return np.arccos(np.clip(cosine, -1.0, 1.0))


def _pole_frame(pole) -> np.ndarray:
    """Return a rotation matrix whose third column is the unit vector ``pole``."""
    z = np.asarray(pole, dtype=float) / np.linalg.norm(pole)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _about(axis, angle: float) -> np.ndarray:
    """Return the rotation matrix by ``angle`` [rad] about the unit vector ``axis``."""
    k = np.asarray(axis, dtype=float)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def tumbler_states(inertia: npt.ArrayLike, precession_period: float, rotation_period: float,
                   pole: npt.ArrayLike, phase: npt.ArrayLike,
                   turn: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (omega0 (n, 3) [rad/yr], euler0 (n, 3) [rad]) of tumblers with the given spin state.

    Each has the short-axis mode of periods P_phi, P_psi [yr]
    (:func:`~tumble_ros.core.model.spinstate.omega_for_periods`) and its angular momentum along
    ``pole`` (unit vector, orbital frame), at ``phase`` (fraction of P_psi) of its tumbling
    cycle and turned by ``turn`` [rad] about the pole. Phase 0, turn 0: w at the polhode point
    of :func:`omega_for_periods`, the body's L turned onto the pole by a fixed rotation.
    """
    moments = np.asarray(inertia, dtype=float)
    phase, turn = np.atleast_1d(phase).astype(float), np.atleast_1d(turn).astype(float)
    pole = np.asarray(pole, dtype=float) / np.linalg.norm(pole)
    w0 = omega_for_periods(moments, precession_period, rotation_period)
    momentum = moments * w0
    # body -> orbital at phase 0: the body's L frame onto the pole's frame
    c0 = _pole_frame(pole) @ _pole_frame(momentum).T
    # the polhode phases: one torque-free run through all of them (no torque: orbit_rate 0)
    order = np.argsort(phase % 1.0, kind='stable')
    times = (phase % 1.0)[order] * rotation_period
    free = Scenario(inertia=tuple(moments), orbit_rate=0.0, omega0=tuple(w0),
                    euler0=matrix_to_euler(c0.T), duration=max(rotation_period, 1e-9),
                    output_interval=max(rotation_period, 1e-9),
                    integrator=IntegratorSettings(method='dop853', rtol=1e-12, atol=1e-12))
    run = simulate(free, times)
    omega = np.empty((phase.size, 3))
    euler = np.empty((phase.size, 3))
    for k, j in enumerate(order):
        c = _about(pole, turn[j]) @ quaternion_to_matrix(run.quaternion[k])
        omega[j] = run.omega[k]
        euler[j] = matrix_to_euler(c.T)
    return omega, euler


def _states(omega, quaternion, inertia):
    states = [spin_state(w, inertia, q) for w, q in zip(omega, quaternion)]
    return (np.array([s.mode for s in states]),
            np.array([s.precession_period for s in states]),
            np.array([s.rotation_period for s in states]),
            np.array([s.pole for s in states]))


def _draw_inertia(nominal: np.ndarray, spread, observed, rng, tries: int = 1000) -> np.ndarray:
    """
    Return moments drawn around ``nominal`` that can have the observed periods.

    The ratios I_a/I_c, I_b/I_c (smallest, middle over largest) uniform within +- ``spread``;
    a draw for which no short-axis mode has the observed P_psi/P_phi is rejected (the periods
    constrain the moments), so the draws follow the spread conditioned on the observation.
    """
    order = np.argsort(nominal, kind='stable')
    ratios = nominal[order] / nominal[order][2]
    for _ in range(tries):
        r = ratios + np.array([rng.uniform(-spread[0], spread[0]),
                               rng.uniform(-spread[1], spread[1]), 0.0])
        moments = np.empty(3)
        moments[order] = r * nominal[order][2]
        if not 0.0 < r[0] < r[1] < 1.0:
            continue
        try:
            omega_for_periods(moments, observed.precession_period, observed.rotation_period)
        except ValueError:
            continue
        return moments
    raise ValueError(f'encounter_ensemble: no moments within +- {spread} of {nominal.tolist()} '
                     f'have the observed periods in {tries} draws')


def with_inertia(scenario: Scenario, moments: npt.ArrayLike) -> Scenario:
    """
    Return ``scenario`` with the normalised principal ``moments`` (the nominal I3 kept).

    A body given by its inertia alone takes them as they are. With a gravity field beyond the
    quadrupole, the field must follow (its moments proportional to the inertia):

    * a homogeneous ellipsoid (``body.model: ellipsoid``) is rebuilt with the semi-axes of
      those moments (``a^2 = 5/(2m) (Iy + Iz - Ix)``... , core/model/shape.py), its volume
      and density kept, so its whole field (C_40, C_42, C_44 too) is the new ellipsoid's;
    * a field given directly (``gravity_field``, ``body.model: inertia``) keeps every
      coefficient but degree 2, which is made the moments' (C_20, C_22;
      :meth:`~tumble_ros.core.model.gravity_field.GravityField.with_principal_moments`), its
      largest moment kept [kg km^2];
    * a polyhedron or density moments cannot be re-derived from moments: refused
      (ScenarioError naming ``body.model``) unless the moments are the nominal ones.
    """
    moments = tuple(float(v) for v in np.asarray(moments, dtype=float))
    if moments == tuple(scenario.inertia):
        return scenario
    body = scenario.body
    if body.model == 'ellipsoid':
        model = body.mass_model
        assert isinstance(model, Ellipsoid)
        i = np.asarray(moments)
        squares = np.array([i[1] + i[2] - i[0], i[0] + i[2] - i[1], i[0] + i[1] - i[2]])
        if not np.all(squares > 0.0):
            raise ScenarioError(f'inertia: no ellipsoid has the moments {list(moments)}')
        axes = np.sqrt(squares)
        axes *= (float(np.prod(model.semi_axes)) / float(np.prod(axes))) ** (1.0 / 3.0)
        spec = replace(body, semi_axes=tuple(float(v) for v in axes))
        return scenario.replace(inertia=moments, body=spec, gravity_field=None)
    if body.model != 'inertia':
        raise ScenarioError(f'body.model: {body.model} cannot take drawn moments of inertia '
                            f'(only an ellipsoid or a field given directly can), got moments '
                            f'{list(moments)} for {list(scenario.inertia)}')
    field = scenario.gravity_field
    if field is None:
        return scenario.replace(inertia=moments)
    scale = field.inertia_scale(scenario.inertia)
    return scenario.replace(inertia=moments, gravity_field=field.with_principal_moments(
        tuple(scale * v for v in moments)))


def encounter_ensemble(scenario: Scenario, n_bodies: int, *, seed: int = 0,
                       inertia_spread: tuple[float, float] = (0.0, 0.0), n_inertia: int = 1,
                       progress: Callable[[int, int], None] | None = None,
                       run: Callable[..., EnsembleResult] = simulate_ensemble
                       ) -> EncounterResult:
    """
    Run ``n_bodies`` tumblers of ``scenario``'s observed spin state through its encounter.

    ``scenario``: the nominal body (its ``omega0``, ``euler0`` and ``inertia`` give the periods
    and pole every body keeps). ``inertia_spread`` = (dA, dB): the ratios I_a/I_c and I_b/I_c of
    the smallest and middle moments are drawn uniformly within +- dA and +- dB of the nominal
    ones, keeping the draws that can have the observed periods (:func:`_draw_inertia`);
    ``n_inertia`` draws, the first the nominal moments, the bodies split evenly between them;
    a scenario with a gravity field takes each draw's field (:func:`with_inertia`).
    The phase and the turn about L are uniform. Reproducible from ``seed``. Refused before any
    work (ScenarioError, one line): a spread that is not finite or above
    :data:`MAX_INERTIA_SPREAD`, more bodies than the memory available holds
    (:func:`encounter_memory`).
    ``progress(done, total)`` after each inertia draw. ``run``: what integrates each draw's
    bodies, called as :func:`~tumble_ros.core.simulate_ensemble` (the default: in this
    process); ``functools.partial(tumble_ros.ensembles.run_ensemble, client=client)`` runs them
    as chunks on a Dask client's workers, with the same results bit for bit.
    """
    _check_size(n_bodies, n_inertia, inertia_spread)
    nominal = np.asarray(scenario.inertia, dtype=float)
    q0 = euler_to_quaternion(*scenario.euler0)
    observed = spin_state(scenario.omega0, nominal, q0)
    assert observed.pole is not None  # (a spin state with an attitude has its pole)
    if observed.mode != 'SAM':
        raise ValueError(f'encounter_ensemble: the nominal state is {observed.mode}; the '
                         "ensemble keeps a short-axis mode's periods")
    rng = np.random.default_rng(seed)
    draws = [nominal] + [_draw_inertia(nominal, inertia_spread, observed, rng)
                         for _ in range(n_inertia - 1)]
    sizes = np.full(n_inertia, n_bodies // n_inertia)
    sizes[:n_bodies % n_inertia] += 1
    phase, turn = rng.uniform(0.0, 1.0, n_bodies), rng.uniform(0.0, 2.0 * math.pi, n_bodies)
    parts = []
    start = 0
    for k, (moments, size) in enumerate(zip(draws, sizes)):
        body = slice(start, start + size)
        start += size
        omega0, euler0 = tumbler_states(moments, observed.precession_period,
                                        observed.rotation_period, observed.pole, phase[body],
                                        turn[body])
        sc = with_inertia(scenario, moments)
        parts.append((np.tile(moments, (size, 1)),
                      run(sc, [0.0, sc.duration], omega0=omega0, euler0=euler0)))
        if progress is not None:
            progress(k + 1, n_inertia)
    return _collect(scenario, parts, phase, turn)


def _collect(scenario, parts, phase, turn) -> EncounterResult:
    columns: dict[str, list] = {name: [] for name in (
        'inertia', 'mode_before', 'mode_after', 'precession_before', 'precession_after',
        'rotation_before', 'rotation_after', 'spin_rate_before', 'spin_rate_after',
        'pole_before', 'pole_after', 'success')}
    for moments, run in parts:
        columns['inertia'].append(moments)
        columns['success'].append(run.success)
        for when, k in (('before', 0), ('after', -1)):
            omega, quaternion = run.omega[:, k], run.quaternion[:, k]
            good = np.all(np.isfinite(omega), axis=1)
            mode = np.full(len(omega), 'failed', dtype=object)
            precession = np.full(len(omega), math.nan)
            rotation = np.full(len(omega), math.nan)
            pole = np.full((len(omega), 3), math.nan)
            if np.any(good):
                m, p, r, d = _states(omega[good], quaternion[good], moments[0])
                mode[good], precession[good], rotation[good], pole[good] = m, p, r, d
            columns[f'mode_{when}'].append(mode.astype(str))
            columns[f'precession_{when}'].append(precession)
            columns[f'rotation_{when}'].append(rotation)
            columns[f'spin_rate_{when}'].append(np.linalg.norm(omega, axis=1))
            columns[f'pole_{when}'].append(pole)
    joined = {name: np.concatenate(values) for name, values in columns.items()}
    return EncounterResult(phase=phase, turn=turn, scenario=scenario, **joined)


def _percentiles(values: np.ndarray, scale: float = 1.0) -> str:
    v = values[np.isfinite(values)] * scale
    if not v.size:
        return 'n/a'
    p = np.percentile(v, [0, 5, 50, 95, 100])
    return ('min {:.4g}, 5% {:.4g}, median {:.4g}, 95% {:.4g}, max {:.4g}'.format(*p))


def format_encounter(result: EncounterResult) -> str:
    """Return a plain-text report of the ensemble: modes, periods [h], spin rate, pole shift."""
    n = result.success.size
    h = HOURS_PER_YEAR
    modes, counts = np.unique(result.mode_after, return_counts=True)
    lines = [
        f'bodies: {n} ({int(np.sum(~result.success))} failed)',
        'before: mode ' + ', '.join(sorted(set(result.mode_before.tolist())))
        + f'; P_phi {_percentiles(result.precession_before, h)} h; '
        f'P_psi {_percentiles(result.rotation_before, h)} h',
        'after:  mode ' + ', '.join(f'{m} {c} ({100 * c / n:.1f} %)'
                                    for m, c in zip(modes, counts)),
        f'  precession period P_phi [h]: {_percentiles(result.precession_after, h)}',
        f'  rotation period P_psi [h]:   {_percentiles(result.rotation_after, h)}',
        '  spin rate |w| after / before: '
        + _percentiles(result.spin_rate_after / result.spin_rate_before),
        f'  pole shift [deg]: {_percentiles(np.degrees(result.pole_shift))}',
        '  pole shift >= 10 deg: '
        f'{100 * np.mean(np.degrees(result.pole_shift) >= 10.0):.1f} % of the bodies',
    ]
    rate = result.spin_rate_after / result.spin_rate_before
    lines.append(f'  |w| halved or less: {100 * np.mean(rate <= 0.5):.1f} %, doubled or more: '
                 f'{100 * np.mean(rate >= 2.0):.1f} %')
    return '\n'.join(lines)


def _ecliptic(pole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (longitude, latitude) [deg] of unit vectors (n, 3)."""
    return (longitude_degrees(np.arctan2(pole[:, 1], pole[:, 0])),
            np.degrees(np.arcsin(np.clip(pole[:, 2], -1.0, 1.0))))


def encounter_figure(result: EncounterResult, path: str | Path, title: str = '') -> Path:
    """Draw the distributions after the encounter (periods, spin rate, pole) to ``path`` (PNG)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(draw_encounter(result, title))
    return path


def draw_encounter(result: EncounterResult, title: str = '') -> bytes:
    """Return the PNG of :func:`encounter_figure` (the distributions after the encounter)."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    from .display import frame_name

    def plain_log(axis) -> None:
        # log ticks read 20, 50, 100 (hours, ratios), not 2x10^1
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda x, _: f'{x:g}'))
        axis.set_minor_formatter(NullFormatter())

    h = HOURS_PER_YEAR
    fig = Figure(figsize=(11, 8))          # no pyplot: no global backend, nothing to close
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    sam = result.mode_after == 'SAM'
    for ax, after, before, name in (
            (axes[0, 0], result.precession_after, result.precession_before,
             'precession period $P_\\phi$ [h]'),
            (axes[0, 1], result.rotation_after, result.rotation_before,
             'rotation period $P_\\psi$ [h]')):
        values = after * h
        bins = np.geomspace(max(np.nanmin(values), 1e-3), np.nanmax(values), 40)
        ax.hist([values[sam], values[~sam]], bins=bins, stacked=True,
                label=['SAM after', 'LAM after'], color=['tab:blue', 'tab:orange'])
        ax.axvline(np.nanmedian(before) * h, color='k', ls='--', label='before')
        ax.set_xscale('log')
        plain_log(ax.xaxis)
        ax.set_xlabel(name)
        ax.set_ylabel('bodies')
        ax.legend()
    rate = result.spin_rate_after / result.spin_rate_before
    ax = axes[1, 0]
    ax.hist(rate[np.isfinite(rate)], bins=np.geomspace(max(np.nanmin(rate), 1e-3),
                                                       np.nanmax(rate), 40), color='tab:green')
    ax.axvline(1.0, color='k', ls='--', label='unchanged')
    ax.axvline(0.5, color='k', ls=':', label='halved, doubled')
    ax.axvline(2.0, color='k', ls=':')
    ax.set_xscale('log')
    plain_log(ax.xaxis)
    ax.legend(fontsize=8)
    ax.set_xlabel('spin rate $|\\omega|$ after / before')
    ax.set_ylabel('bodies')
    axes[1, 1].remove()
    ax = fig.add_subplot(2, 2, 4, projection='polar')
    # the pole around the frame's pole of its hemisphere: angle = longitude, radius = distance
    hemisphere = 1.0 if result.pole_before[0, 2] >= 0.0 else -1.0
    lon, _ = _ecliptic(result.pole_after)
    lon0, _ = _ecliptic(result.pole_before[:1])
    radius = np.degrees(np.arccos(np.clip(hemisphere * result.pole_after[:, 2], -1.0, 1.0)))
    radius0 = np.degrees(np.arccos(np.clip(hemisphere * result.pole_before[0, 2], -1.0, 1.0)))
    points = ax.scatter(np.radians(lon), radius, c=np.degrees(result.pole_shift), s=6,
                        cmap='viridis')
    ax.plot(np.radians(lon0), [radius0], 'r*', ms=14, label='before')
    fig.colorbar(points, ax=ax, label='pole shift [deg]', pad=0.1)
    ax.set_title(f'pole of L after, {frame_name(result.scenario)}: longitude (angle), '
                 f"degrees from the {'north' if hemisphere > 0 else 'south'} pole (radius)",
                 fontsize=9)
    ax.legend(loc='lower left', fontsize=8)
    fig.suptitle(title or f'{result.success.size} tumblers through the encounter')
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format='png', dpi=110)
    return buffer.getvalue()

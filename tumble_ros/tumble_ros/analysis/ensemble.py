"""
Analysis of an ensemble store: distributions of the final spin, periods, mode and pole.

    python -m tumble_ros.analysis.ensemble ens.zarr [--figures DIR] [--time T]

Works on what :func:`tumble_ros.io.open_ensemble` returns (any run written by
``tumble_ros.ensembles.run_ensemble_to_store`` or ``ensemble --out X.zarr``), reading the store
chunk by chunk: the final angular velocity of every succeeded body, and the torque-free spin
state (:func:`tumble_ros.core.model.spinstate.spin_state`: SAM/LAM mode, rotation and precession
periods [yr], pole of L in the orbital frame) of up to ``max_spin_states`` bodies spread evenly
over the ensemble (the spin state costs ~1 ms per body). The dicts are in those units; the
printout and the figure in the store's display units (``display``: rates and periods in the
unit of its time span, the pole in degrees, its frame named).
"""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
import sys
from typing import Any, Sequence, TYPE_CHECKING

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np
from tumble_ros.core import parse_scenario
from tumble_ros.core.model.spinstate import spin_state
from tumble_ros.core.units import HOURS_PER_YEAR
from tumble_ros.errors import AnalysisError, TumbleRosError
from tumble_ros.io import open_ensemble
from tumble_ros.io.ensemble_store import SCENARIO_ATTR

from .display import display_units, DisplayUnits, longitude_degrees

if TYPE_CHECKING:
    import xarray as xr

__all__ = ['ensemble_statistics', 'final_spin', 'plot_ensemble', 'format_statistics',
           'ensemble_units', 'main']

#: Bodies whose spin state is computed by default (evenly spread over the ensemble).
MAX_SPIN_STATES = 2000


def _index(ds, time) -> int:
    if time is None:
        return ds.sizes['time'] - 1
    k = int(np.argmin(np.abs(ds.time.values - float(time))))
    return k


def final_spin(ds: xr.Dataset, time: float | None = None,
               max_spin_states: int = MAX_SPIN_STATES) -> dict[str, Any]:
    """
    Return per-body arrays of the spin at ``time`` [yr] (default the last sample).

    Keys: ``body`` (the succeeded bodies), ``omega`` (n, 3) [rad/yr, body axes]; and for up to
    ``max_spin_states`` of them (``spin_body``): ``mode`` (str), ``rotation_period`` and
    ``precession_period`` [yr], ``pole_longitude`` and ``pole_latitude`` [rad, orbital frame].
    """
    k = _index(ds, time)
    good = np.flatnonzero(ds.status.values == 1)
    omega = ds.omega.isel(time=k).values[good]
    quat = ds.quaternion.isel(time=k).values[good]
    inertia = parse_scenario(ds.attrs[SCENARIO_ATTR]).inertia
    pick = (np.unique(np.linspace(0, good.size - 1, max_spin_states).astype(int))
            if good.size > max_spin_states else np.arange(good.size))
    states = [spin_state(omega[i], inertia, quat[i]) for i in pick]
    return {'time': float(ds.time.values[k]), 'body': good, 'omega': omega,
            'spin_body': good[pick], 'mode': np.array([s.mode for s in states], dtype=object),
            'rotation_period': np.array([s.rotation_period for s in states]),
            'precession_period': np.array([s.precession_period for s in states]),
            'pole_longitude': np.array([s.pole_longitude for s in states]),
            'pole_latitude': np.array([s.pole_latitude for s in states])}


def _stats(x: np.ndarray) -> dict:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return {'n': 0}
    p5, p50, p95 = np.percentile(x, [5, 50, 95])
    return {'n': int(x.size), 'mean': float(x.mean()), 'std': float(x.std()), 'p5': float(p5),
            'median': float(p50), 'p95': float(p95)}


def ensemble_statistics(ds: xr.Dataset, time: float | None = None,
                        max_spin_states: int = MAX_SPIN_STATES) -> dict[str, Any]:
    """
    Return the distributions of the spin at ``time`` [yr] (default the last sample).

    Counts by status; mean, std, 5/50/95 percentiles of |omega|, omega_z and
    omega_perp = |(omega_x, omega_y)| [rad/yr], of the rotation and precession periods [yr]
    and of the pole latitude [rad]; counts of the spin modes (of the bodies whose spin state
    was computed).
    """
    status = ds.status.values
    spin = final_spin(ds, time, max_spin_states)
    w = spin['omega']
    modes, counts = np.unique(spin['mode'].astype(str), return_counts=True)
    return {'time': spin['time'], 'bodies': int(status.size),
            'succeeded': int(np.sum(status == 1)), 'failed': int(np.sum(status == 2)),
            'pending': int(np.sum(status == 0)),
            'omega_norm': _stats(np.linalg.norm(w, axis=1)), 'omega_z': _stats(w[:, 2]),
            'omega_perp': _stats(np.hypot(w[:, 0], w[:, 1])),
            'spin_states': int(spin['spin_body'].size),
            'modes': {str(m): int(c) for m, c in zip(modes, counts)},
            'rotation_period': _stats(spin['rotation_period']),
            'precession_period': _stats(spin['precession_period']),
            'pole_latitude': _stats(spin['pole_latitude'])}


def ensemble_units(ds: xr.Dataset) -> DisplayUnits:
    """Return the units a store is shown in: its time span's, its scenario's frame."""
    t = ds.time.values
    span = float(t[-1] - t[0]) if t.size else 0.0
    return display_units(span, parse_scenario(ds.attrs[SCENARIO_ATTR]))


def _periods_text(name: str, st: dict, units: DisplayUnits) -> list[str]:
    """Return the lines of a period's statistics [yr]: in ``units``, then in hours."""
    lines = [f'  {name} [{units.time}]: {_stats_text(st, 1.0 / units.years_per_time)}']
    if units.time != 'h' and st.get('n'):
        lines.append(f'  {name} [h]: {_stats_text(st, HOURS_PER_YEAR)}')
    return lines


def _stats_text(st: dict, scale: float = 1.0) -> str:
    if not st.get('n'):
        return 'none'
    return (f"n {st['n']}, mean {st['mean'] * scale:.6g}, std {st['std'] * scale:.4g}, "
            f"5% {st['p5'] * scale:.6g}, median {st['median'] * scale:.6g}, "
            f"95% {st['p95'] * scale:.6g}")


def format_statistics(stats: dict, units: DisplayUnits) -> str:
    """
    Return :func:`ensemble_statistics` as text, each quantity with its unit.

    Rates and periods in ``units`` (the scenario's time unit: rad/yr and yr for the paper's runs,
    rad/h and h for a flyby), periods in hours too, the pole latitude in degrees, its frame named.
    """
    modes = ', '.join(f'{m} {c}' for m, c in stats['modes'].items()) or 'none'
    return '\n'.join([
        f"time: {units.time_text(stats['time'])}",
        f"bodies: {stats['bodies']} ({stats['succeeded']} succeeded, {stats['failed']} failed, "
        f"{stats['pending']} pending)",
        f"|omega| [{units.rate}]: {_stats_text(stats['omega_norm'], units.years_per_time)}",
        f'omega_z [{units.rate}, body z]: '
        f"{_stats_text(stats['omega_z'], units.years_per_time)}",
        f'omega_perp = |(omega_x, omega_y)| [{units.rate}]: '
        f"{_stats_text(stats['omega_perp'], units.years_per_time)}",
        f"spin states (torque-free, of {stats['spin_states']} bodies): modes {modes}",
        *_periods_text('rotation period P_psi', stats['rotation_period'], units),
        *_periods_text('precession period P_phi', stats['precession_period'], units),
        f'  pole latitude [deg, {units.frame}]: '
        f"{_stats_text(stats['pole_latitude'], math.degrees(1.0))}",
    ])


def plot_ensemble(ds: xr.Dataset, out_dir: str | os.PathLike[str], time: float | None = None,
                  max_spin_states: int = MAX_SPIN_STATES) -> Path:
    """Draw the distributions of :func:`ensemble_statistics` into ``out_dir/ensemble.png``."""
    spin = final_spin(ds, time, max_spin_states)
    u = ensemble_units(ds)
    w = u.w(spin['omega'])
    fig = Figure(figsize=(10, 7), dpi=100, layout='constrained')
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    axes[0, 0].hist(w[:, 2], bins=50)
    axes[0, 0].set_xlabel(f'final $\\omega_z$ [{u.rate}]')
    axes[0, 1].hist(np.hypot(w[:, 0], w[:, 1]), bins=50)
    axes[0, 1].set_xlabel(f'final $|\\omega_\\perp|$ [{u.rate}]')
    periods = u.t(spin['rotation_period'][np.isfinite(spin['rotation_period'])])
    axes[1, 0].hist(periods, bins=50)
    axes[1, 0].set_xlabel(f'rotation period $P_\\psi$ [{u.time}] (torque-free, from the final '
                          'state)')
    axes[1, 1].scatter(longitude_degrees(spin['pole_longitude']),
                       np.degrees(spin['pole_latitude']), s=4)
    axes[1, 1].set_xlabel(f'pole longitude [deg, 0-360] ({u.frame})')
    axes[1, 1].set_ylabel(f'pole latitude [deg] ({u.frame})')
    for ax in axes.flat[:3]:
        ax.set_ylabel('bodies')
    fig.suptitle(f"{int(np.sum(ds.status.values == 1))} of {ds.sizes['body']} bodies at "
                 f"t = {u.time_text(spin['time'], 4)} ({spin['spin_body'].size} spin states)")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / 'ensemble.png'
    fig.savefig(path)
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """Print the statistics of a store (and draw its figure with --figures DIR)."""
    p = argparse.ArgumentParser(prog='python -m tumble_ros.analysis.ensemble',
                                description='Distributions of the spin of an ensemble store.')
    p.add_argument('store', help='an ensemble store (X.zarr)')
    p.add_argument('--time', type=float, help='sample time [yr] (default: the last)')
    p.add_argument('--figures', help='write ensemble.png into this directory')
    p.add_argument('--spin-states', type=int, default=MAX_SPIN_STATES,
                   help=f'bodies whose spin state is computed (default {MAX_SPIN_STATES})')
    args = p.parse_args(argv)
    try:
        ds = open_ensemble(args.store)
        stats = ensemble_statistics(ds, args.time, args.spin_states)
        if stats['succeeded'] == 0:
            raise AnalysisError(f'{args.store}: no succeeded body to analyse')
        print(format_statistics(stats, ensemble_units(ds)))
        if args.figures:
            print(f'wrote {plot_ensemble(ds, args.figures, args.time, args.spin_states)}')
    except (TumbleRosError, OSError, ValueError) as err:
        print(f"ERROR: {' '.join(str(err).split())}", file=sys.stderr)
        return 1
    except RuntimeError as err:       # numcodecs: a chunk that does not decompress
        print(f'ERROR: {args.store}: damaged ensemble store: cannot read its data '
              f"({' '.join(str(err).split())})", file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':  # pragma: no cover
    from tumble_ros.exits import call_closing_quietly     # a closed pipe: 141, quietly

    sys.exit(call_closing_quietly(main, sys.argv[1:]))

"""
Python-side builders of the kernels' arrays (not compiled): the one place that fills them.

``problem_arrays`` (segments' problems, layout PR), ``config_array`` (a method's settings,
layout CF) and ``new_state`` (a zeroed state, layout ST).
"""
from __future__ import annotations

import functools
from typing import Any, Iterable, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.kernels.layout import Array, CF, MAX_STAGES, PR, ST
from tumble_ros.core.kernels.methods import kernel_id
from tumble_ros.core.torques.gravity_gradient import tidal_coefficients

__all__ = ['free_flow_split', 'problem_arrays', 'problem_array', 'set_pulses', 'config_array',
           'new_state']


def free_flow_split(inertia: Iterable[float]) -> tuple[float, tuple[float, float, float]]:
    """
    (1/I_r, (c_x, c_y, c_z)) with I_r the middle moment and c_i = 1/I_i - 1/I_r.

    c_r is exactly 0, and so is c_i for a moment equal to I_r (symmetric body: exact free flow).
    """
    moments = tuple(float(v) for v in inertia)
    r = sorted(range(3), key=lambda i: moments[i])[1]
    inv_ref = 1.0 / moments[r]
    cx, cy, cz = (0.0 if i == r else 1.0 / moments[i] - inv_ref for i in range(3))
    return inv_ref, (cx, cy, cz)


def problem_arrays(inertia: Iterable[float], orbit_rate: float,
                   torques: npt.ArrayLike) -> Array:
    """
    Return the problem rows (layout PR) of n segments of one body: (n, PR.SIZE).

    ``torques`` (n, 6): each segment's body pulse torque then orbital pulse torque
    [inertia units * rad/yr^2]. Used by the single-body path and the ensembles alike.
    """
    pulses = np.asarray(torques, dtype=float).reshape(-1, 6)
    p = np.repeat(_body_row(tuple(float(v) for v in inertia), float(orbit_rate))[None, :],
                  len(pulses), axis=0)
    p[:, PR.PULSE_BODY:PR.PULSE_BODY + 3] = pulses[:, :3]
    p[:, PR.PULSE_ORBITAL:PR.PULSE_ORBITAL + 3] = pulses[:, 3:]
    p[:, PR.HAS_ORBITAL] = np.where(np.any(pulses[:, 3:] != 0.0, axis=1), 1.0, 0.0)
    return p


@functools.lru_cache(maxsize=64)
def _body_row(inertia: tuple[float, float, float], orbit_rate: float) -> Array:
    """
    Return the problem row's body part (no pulse): read-only, shared by a body's segments.

    Cached: a run with 10,000 impacts starts 20,001 segments of the same body (25 us each).
    """
    ix, iy, iz = inertia
    p = np.zeros(PR.SIZE)
    p[PR.INERTIA:PR.INERTIA + 3] = ix, iy, iz
    p[PR.INV_INERTIA:PR.INV_INERTIA + 3] = 1.0 / ix, 1.0 / iy, 1.0 / iz
    p[PR.EULER:PR.EULER + 3] = (iy - iz) / ix, (iz - ix) / iy, (ix - iy) / iz
    p[PR.ORBIT_RATE] = orbit_rate
    p[PR.TIDAL:PR.TIDAL + 3] = tidal_coefficients((ix, iy, iz), orbit_rate)
    inv_ref, coeffs = free_flow_split((ix, iy, iz))
    p[PR.INV_REF] = inv_ref
    p[PR.FLOW:PR.FLOW + 3] = coeffs
    p.flags.writeable = False
    return p


def problem_array(inertia: Iterable[float], orbit_rate: float,
                  torque_body: Sequence[float] = (0.0, 0.0, 0.0),
                  torque_orbital: Sequence[float] = (0.0, 0.0, 0.0)) -> Array:
    """Return the problem array of one segment (see :func:`problem_arrays`; the same row)."""
    row: Array = _body_row(tuple(float(v) for v in inertia), float(orbit_rate)).copy()
    set_pulses(row, torque_body, torque_orbital)
    return row


def set_pulses(row: Array, torque_body: Sequence[float],
               torque_orbital: Sequence[float]) -> None:
    """
    Write a segment's pulse torques into its problem row (layout PR), in place.

    ``torque_body``, ``torque_orbital`` [inertia units * rad/yr^2]; the rest of the row (the
    body) is left as it is: a stepper kept across a body's segments rewrites only these.
    """
    # (element by element: numpy converts no tuple, ~4 us less per segment)
    bx, by, bz = torque_body
    ox, oy, oz = torque_orbital
    row[PR.PULSE_BODY], row[PR.PULSE_BODY + 1], row[PR.PULSE_BODY + 2] = bx, by, bz
    row[PR.PULSE_ORBITAL], row[PR.PULSE_ORBITAL + 1], row[PR.PULSE_ORBITAL + 2] = ox, oy, oz
    row[PR.HAS_ORBITAL] = 1.0 if ox != 0.0 or oy != 0.0 or oz != 0.0 else 0.0


def config_array(kernel: str, settings: Any, gammas: Iterable[float] = (), order: int = 0,
                 step_budget: tuple[float, float] = (np.inf, np.inf),
                 euler_angles: bool = True) -> Array:
    """
    Return the config array (layout CF): method, step, tolerances, order, composition.

    ``step_budget``: (window [yr], most steps within it), the work budget of an adaptive
    method (``limits.step_budget``; (inf, inf): none). ``euler_angles`` False: the loops
    neither follow nor write out the Euler angles (the same steps and states otherwise).
    """
    cfg = np.zeros(CF.SIZE)
    cfg[CF.EULER] = 1.0 if euler_angles else 0.0
    cfg[CF.WINDOW], cfg[CF.WINDOW_STEPS] = (float(v) for v in step_budget)
    cfg[CF.METHOD] = kernel_id(kernel)
    cfg[CF.ORDER] = float(order)
    cfg[CF.STEP] = settings.step
    cfg[CF.RTOL] = settings.rtol
    cfg[CF.ATOL] = settings.atol
    cfg[CF.MAX_STEP] = settings.max_step if settings.max_step > 0 else np.inf
    stages = tuple(float(g) for g in gammas)
    if len(stages) > MAX_STAGES:
        raise ValueError(f'at most {MAX_STAGES} composition stages')
    cfg[CF.N_STAGES] = len(stages)
    total = 0.0
    for j, g in enumerate(stages):
        total += g
        cfg[CF.GAMMA + j] = g
        cfg[CF.CUM + j] = total
    if stages:
        cfg[CF.CUM + len(stages) - 1] = 1.0  # the last stage ends exactly at t + h
    return cfg


def new_state() -> Array:
    """Return a zeroed state array (layout ST)."""
    return np.zeros(ST.SIZE)

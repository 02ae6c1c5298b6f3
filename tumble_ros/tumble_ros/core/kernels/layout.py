"""
The named fields of the kernels' flat float64 arrays, with generated offsets.

numba compiles loops over plain float64 arrays best, so a body's integration state, a
segment's problem and a method's settings are each one flat array; the fields below give their
parts names. :func:`layout` turns a list of (name, size, meaning) into a namedtuple of offsets
(numba folds ``ST.TAU`` to a constant) whose last field ``SIZE`` is the array's length, and
:func:`describe` prints the table (``python -m tumble_ros.core.kernels`` shows all three).

Units: times [yr], rates [rad/yr], inertia normalised, torques [inertia units * rad/yr^2].
Frames: omega and torques in body principal axes; the quaternion turns body into orbital
(scalar first).
"""
from __future__ import annotations

from collections import namedtuple
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

__all__ = ['layout', 'describe', 'ST', 'PR', 'CF', 'BK', 'BT', 'BB', 'LI', 'LN', 'N', 'MAX_STAGES',
           'LANE_STAGES',
           'STATUS', 'FAIL', 'Array', 'Extra']

#: The kernels' arrays: flat float64 (a state, a problem, a config, outputs).
Array = npt.NDArray[np.float64]
#: The extra torques (``torques.extra_torque_arrays``): (compiled functions, parameter rows),
#: or None (no loop at all).
Extra = tuple[tuple[Any, ...], npt.NDArray[np.float64]] | None

#: Size of the state vector: omega (3) + quaternion (4).
N = 7
#: Most stages of a composition (splitting) the config holds.
MAX_STAGES = 16
#: Stages of the largest Runge-Kutta tableau (DOP853 with its dense-output stages).
RK_STAGES = 16
#: Stages a step of the lanes loop keeps (DOP853's 12 and f at the step's end; the dense
#: output's three more are taken per body, on its state).
LANE_STAGES = 13


def layout(name: str, fields: list[tuple[str, int, str]]) -> Any:
    """Return a namedtuple ``name`` of the fields' offsets (consecutive), plus ``SIZE``."""
    offsets, at = [], 0
    for _, size, _ in fields:
        offsets.append(at)
        at += size
    make: Any = namedtuple  # (a name known at run time only)
    cls = make(name, [f[0] for f in fields] + ['SIZE'])
    table = cls(*offsets, at)
    _MEANINGS[name] = [(f[0], off, f[1], f[2]) for f, off in zip(fields, offsets)]
    return table


_MEANINGS: dict[str, list[tuple[str, int, int, str]]] = {}


def describe(table: Any) -> str:
    """Return a table (offset, size, name, meaning) of a layout made by :func:`layout`."""
    rows = _MEANINGS[type(table).__name__]
    lines = [f'{type(table).__name__}: {table.SIZE} float64']
    lines += [f'  {off:4d} {size:4d}  {name:<12} {meaning}' for name, off, size, meaning in rows]
    return '\n'.join(lines)


#: One body's integration state (``st``).
ST = layout('State', [
    ('T', 1, 'absolute time t [yr] handed out'),
    ('T_OLD', 1, 'absolute time at the start of the last step'),
    ('T_BOUND', 1, "the segment's end [yr]"),
    ('H', 1, 'step size: fixed step, or the next adaptive step [yr]'),
    ('N_TOTAL', 1, 'fixed-step methods: number of equal steps on the segment'),
    ('N_STEPS', 1, 'accepted steps on the segment'),
    ('NFEV', 1, 'right-hand-side (or torque) evaluations on the segment'),
    ('STATUS', 1, 'STATUS.RUNNING / FINISHED / FAILED'),
    ('FAIL', 1, 'why it failed: a FAIL code'),
    ('FAIL_T', 1, 'time of the last good state when it failed [yr]'),
    ('FAIL_DT', 1, 'the collapsed step [yr] (FAIL.COLLAPSE)'),
    ('F_VALID', 1, 'rk4: 1 if F holds f(t, y)'),
    ('DENSE', 1, 'dop853: 1 if the dense-output coefficients FD are built'),
    ('H_PREV', 1, 'dop853: length of the last step [yr]'),
    ('NFEV_DONE', 1, 'evaluations of earlier segments (ensembles)'),
    ('T0', 1, "the segment's start t0: local time tau = t - t0"),
    ('BUDGET', 1, 'Euler tracking: angle bound accumulated since the last update [rad]'),
    ('COLLAPSE', 1, "16 ulp of the segment's largest tau: no longer step collapses"),
    ('WIN_T', 1, 'work budget: start of the current window [yr] (absolute time)'),
    ('WIN_STEPS', 1, 'work budget: accepted steps since WIN_T'),
    ('TAU', 1, 'local time of the state [yr]'),
    ('TAU_OLD', 1, 'local time at the start of the last step'),
    ('TAU_BOUND', 1, "local time of the segment's end"),
    ('Y', N, 'current state: omega [rad/yr], quaternion'),
    ('Y_OLD', N, 'state at the start of the last step'),
    ('F', N, 'f(t, y) (rk4: valid if F_VALID; dop853: always)'),
    ('F_OLD', N, 'f at the start of the last step (rk4 dense output)'),
    ('TORQUE', 3, 'splitting: body torque at (t, y)'),
    ('TORQUE_OLD', 3, 'splitting: body torque at the start of the last step'),
    ('PI', 3, 'splitting: body angular momentum I w, carried (not recomputed from w: the '
              'round trip would bias |L| at the 1e-17/step level)'),
    ('PI_OLD', 3, 'splitting: momentum at the start of the last step'),
    ('TMP', N, 'stage argument'),
    ('Y_NEW', N, 'candidate state (dop853)'),
    ('SCRATCH', N, 'dense output result'),
    ('K', RK_STAGES * N, 'Runge-Kutta stages, 16 x 7 (dop853: scipy K_extended)'),
    ('FD', 7 * N, 'dop853 dense-output coefficients, 7 x 7'),
])

#: One segment's problem (``p``): the body, the orbit and the constant pulse torques.
PR = layout('Problem', [
    ('INERTIA', 3, 'principal moments Ix, Iy, Iz'),
    ('INV_INERTIA', 3, '1/Ix, 1/Iy, 1/Iz'),
    ('EULER', 3, "Euler's equations: (Iy - Iz)/Ix, (Iz - Ix)/Iy, (Ix - Iy)/Iz"),
    ('ORBIT_RATE', 1, 'ws [rad/yr] of the circular orbit (0: no tidal torque)'),
    ('TIDAL', 3, 'gravity gradient: 3 ws^2 (Iz - Iy), 3 ws^2 (Ix - Iz), 3 ws^2 (Iy - Ix)'),
    ('PULSE_BODY', 3, 'body-fixed pulse torque on the segment'),
    ('PULSE_ORBITAL', 3, 'orbital-frame pulse torque on the segment'),
    ('HAS_ORBITAL', 1, '1 if PULSE_ORBITAL is not zero'),
    ('INV_REF', 1, 'free-flow split: 1/I_ref (the middle moment)'),
    ('FLOW', 3, 'free-flow split: 1/I_i - 1/I_ref'),
])

#: A method and its settings (``cfg``).
CF = layout('Config', [
    ('METHOD', 1, 'the method: its number in the registry (methods.kernel_id)'),
    ('STEP', 1, 'fixed step [yr]'),
    ('RTOL', 1, 'relative tolerance'),
    ('ATOL', 1, 'absolute tolerance'),
    ('MAX_STEP', 1, 'largest adaptive step [yr] (inf: none)'),
    ('N_STAGES', 1, 'splitting: composition stages'),
    ('GAMMA', MAX_STAGES, 'splitting: composition coefficients gamma_j'),
    ('CUM', MAX_STAGES, 'splitting: c_j = gamma_1 + ... + gamma_j (the last exactly 1)'),
    ('ORDER', 1, 'order of the method (splitting: the pulse sub-step rule)'),
    ('WINDOW', 1, 'work budget: window of simulated time [yr] (inf: no budget)'),
    ('WINDOW_STEPS', 1, 'work budget: most accepted steps within one window (inf: no budget)'),
    ('EULER', 1, '1: follow the Euler angles and write them out; 0: neither (an ensemble that '
                 'asks for no Euler angles)'),
])

#: Bodies stepped in lockstep (``kernels.lockstep``), structure of arrays: the rows of one
#: buffer ``(BK.SIZE, B)``, column i = body i of the block (two buffers: the state before and
#: after a step, swapped every step).
BK = layout('BlockState', [
    ('Y', N, 'omega [rad/yr], quaternion'),
    ('PI', 3, 'splitting: angular momentum I w, carried'),
    ('TORQUE', 3, 'splitting: body torque at (t, y)'),
    ('F', N, 'rk4: f(t, y), computed at the start of each step'),
])

#: Scratch rows of a block ``(BT.SIZE, B)``: the sin/cos are taken in a pass of their own
#: (``splitting.block_sincos``: vectorised, then libm for angles beyond its range).
BT = layout('BlockScratch', [
    ('NORM', 1, 'splitting: |pi|'),
    ('ANGLE', 1, 'the angle of the next sin/cos pass [rad]'),
    ('COS', 1, 'its cosine'),
    ('SIN', 1, 'its sine'),
    ('INC', 1, "Euler tracking: the step's angle bound [rad]"),
    ('ACC', 1, '|y|^2 after the step (the finite check)'),
    ('STAGE', N, "rk4: a stage's argument y + a k"),
    ('K2', N, 'rk4: second stage'),
    ('K3', N, 'rk4: third stage'),
    ('K4', N, 'rk4: fourth stage'),
    ('DENSE', BK.TORQUE + 3, "a dense output's state, rows Y, PI, TORQUE as BK (splitting's "
                             'block_dense: samples inside a step)'),
    ('TRACK_I', 1, 'Euler tracking: the bodies whose update a step runs on the columns, '
                   'gathered (lockstep.block_track): their index in the block'),
    ('TRACK_Q_OLD', 4, "their quaternion at the step's start"),
    ('TRACK_OLD', 3, "tracking.track_angles of the step's start: phi, psi, verdict"),
    ('EULER', 4, "a sample's tracking.euler_parts, every body of the block "
                 '(lockstep.block_euler): phi, psi, theta, 1.0 if they hold'),
])

#: Per-body rows of a block ``(BB.SIZE, B)``: what is not shared by the block.
BB = layout('BlockBodies', [
    ('BUDGET', 1, 'Euler tracking: angle bound accumulated since the last update [rad]'),
    ('FAILED', 1, '1 once the body failed (its steps and outputs stop there)'),
    ('FAIL', 1, 'why it failed: a FAIL code'),
    ('FAIL_T', 1, 'time of its last good state [yr]'),
    ('FAIL_DT', 1, 'the collapsed step [yr] (FAIL.COLLAPSE)'),
    ('STEPS', 1, 'its accepted steps when it failed'),
    ('NFEV', 1, 'its evaluations when it failed'),
    ('K', 1, 'its outputs written when it failed'),
    ('F_VALID', 1, 'rk4: 1 if its F holds f(t, y) (a dense output computed it)'),
    ('NFEV_ADJ', 1, 'its evaluations beyond the block count (rk4: dense output, minus skipped)'),
])

#: A block's shared counters (int64): segment, outputs written, current buffer, steps.
LI = layout('BlockCounters', [
    ('SEG', 1, 'the current segment (index into the shared segment table)'),
    ('K', 1, 'outputs written (every body still running)'),
    ('PAR', 1, 'which of the two buffers holds the current state (0 or 1)'),
    ('STEPS', 1, 'steps taken by the block'),
])

#: Bodies stepped as lanes with their own clocks (``kernels.lanes``), structure of arrays: the
#: rows of one buffer ``(LN.SIZE, L)``, column i = lane i; its vectors and the attempt in
#: progress of each lane (the rest of a lane's state is its own ``ST`` state).
LN = layout('Lanes', [
    ('Y', N, 'omega [rad/yr], quaternion'),
    ('Y_OLD', N, 'the state at the start of the last step'),
    ('Y_NEW', N, "the attempt's candidate state"),
    ('F', N, 'f(t, y) at the current state'),
    ('K', LANE_STAGES * N, "the attempt's stages (dop853: scipy's K, f at the end last)"),
    ('TMP', N, "a stage's argument"),
    ('GO', 1, '1 if the lane attempts a step in this iteration'),
    ('TAU', 1, "local time at the step's start [yr]"),
    ('TAU_NEW', 1, "local time at the attempt's end [yr]"),
    ('H', 1, "the attempt's step [yr]"),
    ('H_ABS', 1, "the attempt's |step| [yr]"),
    ('MIN_STEP', 1, "the step's smallest |step| [yr]"),
    ('REJECTED', 1, 'attempts of the step rejected so far'),
    ('T', 1, "a stage's absolute time [yr]"),
    ('SX', 1, "the Sun's direction at that time: X' component"),
    ('SY', 1, "the Sun's direction at that time: Y' component"),
    ('ACC', 1, 'a sum over stages'),
    ('ACC3', 1, 'a second sum over stages'),
    ('E5', 1, "dop853: the 5th-order error's sum of squares"),
    ('E3', 1, "dop853: the 3rd-order error's sum of squares"),
    ('ERR', 1, "the attempt's error norm (< 1: accepted)"),
])


class Status(NamedTuple):
    """ST.STATUS values (floats: they live in the state array)."""

    RUNNING: float
    FINISHED: float
    FAILED: float


class Fail(NamedTuple):
    """ST.FAIL values: why a step failed."""

    NONE: float
    NONFINITE: float
    COLLAPSE: float
    TOO_SMALL: float
    STEP_NAN: float
    REJECTED: float
    BUDGET: float


#: ST.STATUS values.
STATUS = Status(0.0, 1.0, 2.0)
#: ST.FAIL values.
FAIL = Fail(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)

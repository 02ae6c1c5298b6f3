"""
Compiled integration loops: the hot path without interpreter overhead.

Everything here is plain Python written in the subset numba compiles (floats, 1-D/2-D float64
arrays, loops); :mod:`tumble_ros.core.compiling.jit` compiles it, or leaves it as plain Python
(:data:`COMPILED` False: the callers, :class:`~..integrators.compiled.CompiledStepper` and
:mod:`..ensemble`, then take the reference path, which gives the same trajectory).

One module per concern, every arrow downward:

* :mod:`.layout`: the named fields of the three flat arrays a loop works on: a body's
  state ``st`` (:data:`ST`), a segment's problem ``p`` (:data:`PR`), a method's settings
  ``cfg`` (:data:`CF`); :mod:`.arrays` builds them;
* :mod:`.physics`: total torque (the :mod:`..torques` components, plus the ``extra``
  torques from outside core), right-hand side, free rigid-body flow: the physics, once;
* :mod:`.checks`: the failure checks after a step; :mod:`.tracking`: continuous Euler angles;
* one module per method, each with ``start`` / ``step`` / ``dense``: :mod:`.rk4`
  (``integrators.fixed_step.RK4``), :mod:`.dop853` (scipy's DOP853 transcribed),
  :mod:`.splitting` (``integrators.splitting``);
* :mod:`.stepping`: the stepping loop of one body on one segment (set-up, step + checks,
  Euler tracking, output sampling); :mod:`.ensemble`: the loop over bodies and segments;
  :mod:`.lockstep`: a block of bodies sharing one time grid stepped together, structure of
  arrays (the methods that define ``block_step``: :mod:`.splitting`, :mod:`.rk4`);
  :mod:`.lanes`: a block of bodies sharing their segments, each with its own clock (an
  adaptive method's steps, ``lanes_*``: :mod:`.dop853`), stages vectorised across bodies;
* :mod:`.methods`: the registry of the compiled methods (:data:`KERNELS`, one line each) and
  each method's copy of those two loops with its step inlined (:func:`loops`).
* :mod:`.samples`: an ensemble's samples post-processed (Jacobi integral, continuous
  quaternions) in one pass, the formulas ``dynamics.jacobi_integral`` evaluates on arrays.

Quaternion attitude only. ``python -m tumble_ros.core.kernels`` prints the array layouts.
"""
from tumble_ros.core.compiling.jit import COMPILED, NUMBA_VERSION
from tumble_ros.core.kernels.arrays import (config_array, free_flow_split, new_state,
                                            problem_array, problem_arrays, set_pulses)
from tumble_ros.core.kernels.checks import collapsed, finite_norm, MIN_STEP_ULPS
from tumble_ros.core.kernels.dop853 import MAX_REJECTIONS
from tumble_ros.core.kernels.layout import (Array, BB, BK, BT, CF, describe, Extra, FAIL, LI, LN,
                                            N, PR, ST, STATUS)
from tumble_ros.core.kernels.methods import (ensemble_advance, ensemble_init, has_lanes,
                                             has_lockstep, kernel_id, kernel_name, KERNELS,
                                             Loops, loops)
from tumble_ros.core.kernels.physics import body_torque, free_flow, rhs, rhs_called
from tumble_ros.core.kernels.splitting import flow_called, MAX_PULSE_SUBSTEPS, pulse_step_count
from tumble_ros.core.kernels.tracking import (MAX_TRACK_PIECES, set_track, track_pieces,
                                              track_rate, UNWRAP_MIN_SIN, UNWRAP_STEP,
                                              unwrap_towards)

__all__ = ['COMPILED', 'NUMBA_VERSION', 'ST', 'PR', 'CF', 'BK', 'BT', 'BB', 'LI', 'LN', 'N',
           'STATUS', 'FAIL', 'Array', 'Extra', 'has_lockstep', 'has_lanes', 'KERNELS', 'Loops',
           'loops', 'kernel_id',
           'kernel_name', 'describe',
           'config_array', 'free_flow_split', 'new_state',
           'problem_array', 'problem_arrays', 'set_pulses', 'collapsed', 'finite_norm',
           'MIN_STEP_ULPS',
           'MAX_REJECTIONS', 'ensemble_advance', 'ensemble_init', 'body_torque', 'free_flow',
           'rhs', 'rhs_called', 'flow_called', 'MAX_PULSE_SUBSTEPS', 'pulse_step_count',
           'MAX_TRACK_PIECES', 'set_track',
           'track_pieces', 'track_rate', 'UNWRAP_MIN_SIN', 'UNWRAP_STEP', 'unwrap_towards']

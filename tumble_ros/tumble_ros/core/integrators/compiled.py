"""
The fast path: a method's compiled loop (``core/kernels/``) behind the Stepper interface.

:class:`CompiledStepper` integrates one segment like the method's own stepper class (same
steps, same dense output, same failure checks), but can also take many steps per call
(:meth:`CompiledStepper.advance`) with the Propagator's per-step work (continuous Euler
angles, output sampling) done inside the compiled loop. The Propagator uses it when
:func:`fast_path_available` says so; ``fast=False`` keeps the reference path.
"""
from __future__ import annotations

import contextlib
import functools
import math
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from tumble_ros.core import kernels as K
from tumble_ros.core.compiling.jit import first_use, needs_compiling
from tumble_ros.core.integrators.base import (budget_message, FAILED, FINISHED, RUNNING,
                                              SegmentProblem, step_nan_message, Stepper)
from tumble_ros.core.torques import extra_torque_arrays

__all__ = ['CompiledStepper', 'fast_path_available', 'why_no_fast_path', 'failure_message']

_EMPTY_T = np.empty(0)
_EMPTY_Y = np.empty((0, K.N))
_EMPTY_E = np.empty((0, 3))
_STATUS = {K.STATUS.RUNNING: RUNNING, K.STATUS.FINISHED: FINISHED, K.STATUS.FAILED: FAILED}


def failure_message(st: K.Array, method_name: str) -> str:
    """Return the reference path's message for the failure recorded in a kernel state ``st``."""
    t_good = float(st[K.ST.FAIL_T])
    code = st[K.ST.FAIL]
    if code == K.FAIL.NONFINITE:
        return f'non-finite state after t = {t_good:.10g} yr'
    if code == K.FAIL.COLLAPSE:
        return (f'step size collapsed to {float(st[K.ST.FAIL_DT]):.3g} yr at '
                f't = {t_good:.10g} yr: the solution is singular or diverging there')
    if code == K.FAIL.STEP_NAN:
        return step_nan_message(method_name, t_good)
    if code == K.FAIL.BUDGET:
        return budget_message(st[K.ST.WIN_STEPS], float(st[K.ST.FAIL_DT]), t_good)
    if code == K.FAIL.REJECTED:
        return (f'{method_name} failed at t = {t_good:.10g} yr: '
                f'{K.MAX_REJECTIONS} step sizes rejected in a row')
    return (f'{method_name} failed at t = {t_good:.10g} yr: '
            'Required step size is less than spacing between numbers.')


def why_no_fast_path(method: type[Stepper], attitude: str) -> str:
    """Empty if ``method`` has a compiled loop usable for ``attitude``, else the reason."""
    if method.kernel is None:
        return f'method {method.name!r} has no compiled loop'
    if attitude != 'quaternion':
        return f"the compiled loops integrate attitude 'quaternion' only, not {attitude!r}"
    if not K.COMPILED:
        return ('numba is not installed or is disabled (NUMBA_DISABLE_JIT / TUMBLE_ROS_NO_JIT); '
                'the reference path gives the same results, slower')
    return ''


def fast_path_available(method: type[Stepper], attitude: str) -> bool:
    """Return True if the Propagator can run ``method`` through its compiled loop."""
    return not why_no_fast_path(method, attitude)


class CompiledStepper(Stepper):
    """
    One segment of ``method`` run by its compiled kernel (quaternion attitude).

    Parameters are those of :class:`Stepper` plus ``method`` (the registry class whose
    ``kernel`` to run); ``problem`` is required, ``fun`` is not used.
    """

    adaptive = False  # the method's flags: on the class of each method (:func:`_flavour`)

    def __new__(cls, method: type[Stepper], *args: Any, **kwargs: Any) -> CompiledStepper:
        """Return an instance of the subclass carrying ``method``'s flags (:func:`_flavour`)."""
        return super().__new__(_flavour(method))

    def __init__(self, method: type[Stepper], fun: Callable[..., Any], t0: float,
                 y0: npt.NDArray[np.float64], t_bound: float, settings: Any,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        if problem is None:
            raise ValueError('CompiledStepper needs the SegmentProblem')
        if method.kernel is None:
            raise ValueError(f'method {method.name!r} has no compiled loop')
        self.method = method
        gammas = method.composition() if hasattr(method, 'composition') else ()
        self._cfg = K.config_array(method.kernel, settings, gammas, method.order or 0,
                                   problem.step_budget if method.adaptive else
                                   (math.inf, math.inf))
        self._p = K.problem_array(problem.inertia, problem.orbit_rate, problem.torque_body,
                                  problem.torque_orbital)
        self._extra = extra_torque_arrays(problem.extra_torques)
        self.work = 0  # units of work of the last advance()
        self._st = K.new_state()
        self._st[K.ST.Y:K.ST.Y + K.N] = self.y
        self._loops = K.loops(method.kernel)
        self._loops.seg_init(self._p, self._extra, self._cfg, self._st, self.t, self.t_bound)
        self._sync()

    def restart(self, t0: float, y0: npt.NDArray[np.float64], t_bound: float,
                problem: SegmentProblem) -> None:
        """
        Start another segment of the same body from ``t0``, ``y0`` to ``t_bound``.

        What a new ``CompiledStepper(method, None, t0, y0, t_bound, settings, problem)`` would
        be, bit for bit (its arrays hold the same numbers: tests/test_core_segments.py), without
        building one: only the pulse torques of the problem row and the state are rewritten (a
        run with n impacts starts 2n + 1 segments, ~15 us each when built anew). ``problem``
        must differ from this stepper's in its pulse torques only (ValueError otherwise).
        """
        if not self.is_same_body(problem):
            raise ValueError('CompiledStepper.restart: the problem differs in more than its '
                             'pulse torques; build a new stepper')
        self.restart_same_body(t0, y0, t_bound, problem)

    def restart_same_body(self, t0: float, y0: npt.NDArray[np.float64], t_bound: float,
                          problem: SegmentProblem) -> None:
        """:meth:`restart` for a caller that checked :meth:`is_same_body` itself."""
        Stepper.__init__(self, self.fun, t0, y0, t_bound, self.settings, problem=problem)
        K.set_pulses(self._p, problem.torque_body, problem.torque_orbital)
        self.work = 0
        st = self._st
        st.fill(0.0)   # (K.new_state())
        st[K.ST.Y:K.ST.Y + K.N] = self.y
        self._loops.seg_init(self._p, self._extra, self._cfg, st, self.t, self.t_bound)
        # (no _sync: seg_init sets t, tau, y, the step count and the status Stepper.__init__ set)

    def is_same_body(self, problem: SegmentProblem) -> bool:
        """
        Return whether ``problem`` differs from this stepper's in its pulse torques only.

        The extra torques must be the same objects (the Propagator hands every segment the
        scenario's tuple): components holding arrays are not compared by value.
        """
        old = self.problem
        return (old is not None and old.inertia == problem.inertia
                and old.orbit_rate == problem.orbit_rate and old.attitude == problem.attitude
                and old.step_budget == problem.step_budget
                and old.extra_torques is problem.extra_torques)

    @property
    def nfev(self) -> int:
        return int(self._st[K.ST.NFEV])

    def _sync(self) -> None:
        st = self._st
        self.t = float(st[K.ST.T])
        self.tau = float(st[K.ST.TAU])
        self.y = st[K.ST.Y:K.ST.Y + K.N].copy()
        self.n_steps = int(st[K.ST.N_STEPS])
        self.t_old = float(st[K.ST.T_OLD]) if self.n_steps else None
        self.tau_old = float(st[K.ST.TAU_OLD]) if self.n_steps else None
        self.status = _STATUS[st[K.ST.STATUS]]
        if self.status == FAILED and not self.message:
            self.message = self._failure_message()

    def _failure_message(self) -> str:
        return failure_message(self._st, self.name)

    def step(self) -> str:
        """Take one step; returns the new status."""
        if self.status != RUNNING:
            raise RuntimeError(f'step() on a stepper whose status is {self.status!r}')
        self._loops.step(self._p, self._extra, self._cfg, self._st)
        self._sync()
        return self.status

    def advance(self, t_target: float, track: K.Array, t_out: K.Array | None = None,
                y_out: K.Array | None = None, e_out: K.Array | None = None, k: int = 0,
                budget: float = math.inf) -> tuple[int, int]:
        """
        Step in compiled code until t_target, the segment's end, a failure or the ``budget``.

        The run stops at t >= t_target or after ``budget`` units of work. ``track`` (3,) holds the
        continuous Euler angles and is updated in place after every step
        (``Propagator._track_euler``). Outputs: every ``t_out[j]`` (j >= k) passed on the way (up
        to the current t) is written to ``y_out[j]`` (state) and ``e_out[j]`` (unwrapped Euler
        angles). Work (:func:`~tumble_ros.core.kernels.stepping.advance`): a unit per step and per
        dense evaluation of the tracking; ``self.work`` is what this call spent.
        Returns (next output index, steps taken).
        """
        if t_out is None:
            t_out, y_out, e_out = _EMPTY_T, _EMPTY_Y, _EMPTY_E
        if self.status != RUNNING:
            k, steps, work = self._loops.emit(self._p, self._extra, self._cfg, self._st, track,
                                              t_out, y_out, e_out, k), 0, 0
        else:
            advance = self._loops.advance
            # (first_use only where the call may compile: it costs ~2 us, a segment per impact)
            with (first_use(advance, f'{self.kernel} loop') if needs_compiling(advance)
                  else contextlib.nullcontext()):
                k, steps, work = advance(self._p, self._extra, self._cfg, self._st, track,
                                         float(t_target), t_out, y_out, e_out, k, float(budget))
        self.work = int(work)
        self._sync()
        return int(k), int(steps)

    def state_at(self, t: float) -> np.ndarray:
        """State at ``t`` within the last step [t_old, t] (dense output); a new array."""
        if t == self.t or self.t_old is None or not (self.t_old <= t <= self.t):
            return super().state_at(t)  # the end of the step, or the error
        # the kernel maps t to local time as Stepper.state_at does
        self._loops.dense(self._p, self._extra, self._cfg, self._st, float(t))
        return self._st[K.ST.SCRATCH:K.ST.SCRATCH + K.N].copy()

    def _step_impl(self) -> tuple[bool, str]:  # pragma: no cover - step() is overridden
        raise NotImplementedError

    def _state_at_impl(self, tau: float) -> K.Array:  # pragma: no cover - state_at() is overridden
        raise NotImplementedError


@functools.lru_cache(maxsize=None)
def _flavour(method: type[Stepper]) -> type[CompiledStepper]:
    """Return the subclass of :class:`CompiledStepper` with ``method``'s name and flags."""
    return type(f'Compiled{method.__name__}', (CompiledStepper,),
                {'name': method.name, 'adaptive': method.adaptive,
                 'symplectic': method.symplectic, 'order': method.order,
                 'kernel': method.kernel, '__doc__': CompiledStepper.__doc__})

"""
The contract every integrator of tumble_ros fulfils.

Modelled on ``scipy.integrate._ivp.base.OdeSolver``. A *stepper* advances the solution
of y' = fun(t, y) from t0 towards t_bound, one step per call to :meth:`Stepper.step`,
and never steps past ``t_bound``: the propagator gives each stepper one integration
segment on which the right-hand side is smooth (impact pulses start and end on segment
edges), so no method can step over a pulse.

Local time
----------
Every stepper integrates its segment in *local time* tau = t - t0 (t0: the segment's start):
the method's own time variable, its step-size arithmetic and its dense output see tau, the
right-hand side gets t = t0 + tau (:meth:`Stepper.local_fun`), and ``t``/``t_old`` are handed
out in absolute time (``t0 + tau``, and exactly ``t_bound`` at the end). In absolute time a
pulse of 3e-7 yr at t = 1 yr is ~1e9 ulp of t long: the steps of an implicit or multistep
method inside it are rounded to ulp(t) (LSODA and VODE lose ~1e-10 rad/yr of the jump, and BDF
at rtol <= 1e-12 wants steps below scipy's minimum of 10 ulp(t)); in local time a step is
rounded to ulp(tau), relative to the pulse itself.

Implementing a new method
-------------------------
1. Subclass :class:`Stepper`, set the class attributes ``name`` (the registry key),
   ``adaptive`` (step size chosen from ``rtol``/``atol``) and, if relevant, the other
   capability flags: ``symplectic``, ``order``, ``attitudes`` (the attitude
   representations it can integrate; Scenario validation refuses the others and says why,
   from ``requirement``), ``needs_problem`` (it uses the segment's :class:`SegmentProblem`
   rather than only ``fun``, like the splitting methods) and ``kernel`` (the name of its
   compiled loop in ``core/kernels/``, if any).
2. Implement ``_step_impl() -> (ok, message)``: advance the local time ``self.tau`` and
   ``self.y`` by one step, keep the previous local time in ``self.tau_old``, and land exactly
   on ``self.tau_bound`` at the end; evaluate the right-hand side through
   :meth:`local_fun`. Return ``(False, reason)`` on numerical failure.
3. Implement ``_state_at_impl(tau)`` for any local time tau in [tau_old, tau] (dense output).
4. Add the class to ``METHODS`` (general-purpose methods: any y' = f(t, y)) or
   ``SPLITTING_METHODS`` (structure-exploiting methods) in ``integrators/__init__.py``.
The base class counts steps, records status and message, maps local to absolute time and
turns a non-finite state into a failure.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
import math
from typing import Callable, ClassVar, Protocol, TYPE_CHECKING

import numpy as np

from tumble_ros.core.kernels.checks import collapsed, finite_norm

if TYPE_CHECKING:
    from tumble_ros.core.torques import TorqueComponent

__all__ = ['Stepper', 'SegmentProblem', 'RUNNING', 'FINISHED', 'FAILED', 'budget_message']

RUNNING, FINISHED, FAILED = 'running', 'finished', 'failed'


def budget_message(steps: float, span: float, t: float) -> str:
    """
    Why a run stopped at its work budget: ``steps`` within ``span`` [yr] before ``t`` [yr].

    The budget is the scenario's (``model.limits.step_budget``); the message is the stepper's.
    """
    return (f'work budget exceeded at t = {t:.10g} yr: {steps:.0f} steps within {span:.3g} yr, '
            "less than one output_interval: the motion has become far faster than the scenario's "
            'own rates (a runaway spin-up, e.g. a pericentre very close to a point-mass '
            'perturber, or a diverging solution); if it is real, a shorter output_interval '
            'resolves it (docs/physics.md, "Work budget")')


def step_nan_message(method_name: str, t: float) -> str:
    """Why an adaptive step whose size is not a number failed (the same on both paths)."""
    return (f'{method_name} failed at t = {t:.10g} yr: the step size is not a number '
            '(the right-hand side is not finite there)')


@dataclass(frozen=True)
class SegmentProblem:
    """
    The structure of the equations on one integration segment (built by the Propagator).

    ``fun`` is this problem's right-hand side; methods that exploit the structure (the
    splitting methods, the compiled kernels) use these fields instead.

    Attributes
    ----------
    inertia : (Ix, Iy, Iz) principal moments.
    orbit_rate : ws [rad/yr].
    torque_body, torque_orbital : constant pulse torques on this segment, body-fixed and
        orbital-frame-fixed (zero outside pulses).
    extra_torques : the scenario's extra torques (``torques.TorqueComponent``), on every segment.
    attitude : the attitude representation of the state vector ("quaternion" or "euler").
    step_budget : (window [yr], most steps within it): the work budget of adaptive methods
        (``limits.step_budget``, :attr:`Scenario.step_budget`); (inf, inf): none.

    """

    inertia: tuple[float, float, float]
    orbit_rate: float
    torque_body: tuple[float, float, float] = (0.0, 0.0, 0.0)
    torque_orbital: tuple[float, float, float] = (0.0, 0.0, 0.0)
    attitude: str = 'quaternion'
    extra_torques: tuple[TorqueComponent, ...] = ()
    step_budget: tuple[float, float] = (math.inf, math.inf)


class StepSettings(Protocol):
    """What a stepper reads of its settings (:class:`~..scenario.IntegratorSettings`)."""

    @property
    def rtol(self) -> float:
        """Relative tolerance (adaptive methods)."""

    @property
    def atol(self) -> float:
        """Absolute tolerance [rad/yr] (adaptive methods)."""

    @property
    def step(self) -> float:
        """Step [yr] (fixed-step and splitting methods)."""

    @property
    def max_step(self) -> float:
        """Largest step [yr] of the adaptive methods; 0: none."""


class Stepper(ABC):
    """
    Base class of the step-by-step integrators.

    Parameters
    ----------
    fun : callable ``fun(t, y) -> ndarray``
        Right-hand side; t in years.
    t0, y0 : initial time [yr] and state.
    t_bound : float
        End of the segment [yr]; the stepper lands on it exactly and stops.
    settings : IntegratorSettings
        ``rtol``, ``atol``, ``max_step`` (adaptive methods), ``step`` (fixed-step methods).
    problem : SegmentProblem, optional
        The segment's structure; required by methods with ``needs_problem``, ignored by the
        others.

    Attributes
    ----------
    t, y : current time and state (y is owned by the stepper: copy before keeping).
    t_old : time at the start of the last step (None before the first step).
    t0 : start of the segment [yr], the origin of the local time.
    tau, tau_old, tau_bound : local times (t - t0) of the current state, of the start of the
        last step (None before the first step) and of the segment's end.
    status : ``"running"``, ``"finished"`` (reached t_bound) or ``"failed"``.
    message : why it failed, empty otherwise.
    n_steps : number of accepted steps.

    """

    name: ClassVar[str]
    adaptive: ClassVar[bool]
    symplectic: ClassVar[bool] = False
    #: Order of convergence (informative).
    order: ClassVar[int | None] = None
    #: Attitude representations this method can integrate (``dynamics.ATTITUDE_MODELS`` keys).
    attitudes: ClassVar[frozenset[str]] = frozenset({'quaternion', 'euler'})
    #: Why other attitudes are refused (used in Scenario validation messages).
    requirement: ClassVar[str] = ''
    #: Uses the SegmentProblem instead of only ``fun``.
    needs_problem: ClassVar[bool] = False
    #: Name of the compiled loop in ``core/kernels/`` (quaternion attitude), or None.
    kernel: ClassVar[str | None] = None

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float, y0: np.ndarray,
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        self.fun = fun
        self.problem = problem
        self.t = float(t0)
        self.y = np.array(y0, dtype=float)
        self.t_old: float | None = None
        self.t_bound = float(t_bound)
        self.t0 = self.t
        self.tau = 0.0
        self.tau_old: float | None = None
        self.tau_bound = self.t_bound - self.t0
        self.settings = settings
        self.status = FINISHED if self.t >= self.t_bound else RUNNING
        self.message = ''
        self.n_steps = 0
        # the work budget (adaptive methods; the compiled loop's ST.WIN_T, ST.WIN_STEPS)
        self._budget = (problem.step_budget if problem is not None and self.adaptive
                        else (math.inf, math.inf))
        self._window_t, self._window_steps = self.t, 0

    @property
    def nfev(self) -> int:
        """Return the number of right-hand-side evaluations so far."""
        return 0

    def local_fun(self, tau: float, y: np.ndarray) -> np.ndarray:
        """Return the right-hand side at local time ``tau`` (absolute time t0 + tau)."""
        derivative = self.fun(self.t0 + tau, y)
        return derivative

    def absolute(self, tau: float) -> float:
        """Return the absolute time of local time ``tau``: t0 + tau, exactly t_bound at the end."""
        return self.t_bound if tau >= self.tau_bound else self.t0 + tau

    def step(self) -> str:
        """Take one step; returns the new status."""
        if self.status != RUNNING:
            raise RuntimeError(f'step() on a stepper whose status is {self.status!r}')
        if self._window_steps >= self._budget[1]:
            self.status = FAILED
            self.message = budget_message(self._window_steps, self.t - self._window_t, self.t)
            return self.status
        t_good, tau_good, tau_old_good, y_good = self.t, self.tau, self.tau_old, self.y
        ok, message = self._step_impl()
        # the compiled loop's checks (kernels.checks), the same functions
        if ok and not finite_norm(self.y):
            ok, message = False, f'non-finite state after t = {t_good:.10g} yr'
        elif ok and collapsed(tau_good, self.tau, self.tau_bound):
            # (in local time: a step of a pulse segment may be far below ulp(t))
            ok, message = False, (f'step size collapsed to {self.tau - tau_good:.3g} yr at '
                                  f't = {t_good:.10g} yr: '
                                  'the solution is singular or diverging there')
        if not ok:
            # Keep the last good state: a failed step never hands out NaN or inf.
            self.t, self.tau, self.tau_old, self.y = t_good, tau_good, tau_old_good, y_good
            self.status, self.message = FAILED, message
            return self.status
        self.n_steps += 1
        self.t_old, self.t = t_good, self.absolute(self.tau)
        self._window_steps += 1
        if self.t - self._window_t >= self._budget[0]:
            self._window_t, self._window_steps = self.t, 0
        if self.tau >= self.tau_bound:
            self.status = FINISHED
        return self.status

    def state_at(self, t: float) -> np.ndarray:
        """State at ``t`` within the last step [t_old, t] (dense output); a new array."""
        if t == self.t:
            return self.y.copy()
        if self.t_old is None or self.tau_old is None or not (self.t_old <= t <= self.t):
            raise ValueError(f't = {t!r} is outside the last step [{self.t_old!r}, {self.t!r}]')
        # t - t0 rounds: keep it inside the step's local times
        return self._state_at_impl(min(max(t - self.t0, self.tau_old), self.tau))

    @abstractmethod
    def _step_impl(self) -> tuple[bool, str]:
        """Advance one step in local time; return (ok, message)."""

    @abstractmethod
    def _state_at_impl(self, tau: float) -> np.ndarray:
        """Dense output at local time ``tau`` inside the last step."""

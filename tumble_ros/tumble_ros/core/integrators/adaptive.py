"""
Adaptive methods: scipy's step-by-step solvers and VODE's Adams method.

* ``rk45``, ``dop853``: explicit Runge-Kutta pairs (Dormand-Prince 5(4) and 8(5,3));
* ``radau``, ``bdf``: implicit methods for stiff problems (Jacobian by finite differences);
* ``lsoda``: ODEPACK's automatic Adams/BDF switching, the "ode" default of
  Scilab/Matlab-like platforms the paper used;
* ``adams``: variable-order, variable-step Adams-Moulton (VODE), the paper's "Adams".

Each solver integrates its segment in local time tau = t - t0 (``base``: "Local time"). The
multistep solvers of ODEPACK and VODE (lsoda, adams) keep their own clock as the rounded sum
t = fl(t + h) while their state moves by exactly h; holding one step size for millions of
steps, that rounding adds up (:class:`Adams`), so their time is taken as the compensated sum
of the steps they report instead (:class:`_StepClock`).

``scipy.integrate`` is imported when a stepper of this module is first built, not with the
module: it costs ~0.2-0.5 s (it pulls in scipy.optimize, linalg, sparse), which every process
importing ``tumble_ros.core`` paid, the nodes included, though the compiled path never uses it
(benchmarks/HISTORY.md, "Node start-up").
"""
from __future__ import annotations

import functools
from typing import Any, Callable

import numpy as np

from tumble_ros.core.integrators.base import (SegmentProblem, step_nan_message, Stepper,
                                              StepSettings)


__all__ = ['RK45', 'DOP853', 'Radau', 'BDF', 'LSODA', 'Adams']


def _max_step(settings: StepSettings) -> float:
    return settings.max_step if settings.max_step > 0 else float(np.inf)


class _StepClock:
    """
    The exact time of an ODEPACK/VODE solver's state: the compensated sum of its steps.

    ``add(h)`` after every step (h = the solver's RWORK(11), HU, the step just taken; scipy
    keeps the work array); ``time`` is then the state's time, ``shift`` that time minus the
    solver's own clock t (which gives the right-hand side its time, and converts a time to the
    solver's for interpolation).
    """

    def __init__(self) -> None:
        self.hi = self.lo = 0.0  # hi + lo: Knuth's TwoSum keeps the rounding of every addition
        self.shift = 0.0

    def add(self, h: float, solver_t: float) -> None:
        hi = self.hi + h
        b = hi - self.hi
        self.lo += (self.hi - (hi - b)) + (h - b)
        self.hi = hi
        self.shift = (hi - solver_t) + self.lo

    @property
    def time(self) -> float:
        return self.hi + self.lo

    def solver_time(self, tau: float, solver_t: float) -> float:
        """Return the solver's time of the state at time ``tau`` (near the last step)."""
        return solver_t + ((tau - self.hi) - self.lo)


def _integrate() -> Any:
    """Return ``scipy.integrate`` (imported on the first stepper built, see the docstring)."""
    from scipy import integrate
    return integrate


@functools.lru_cache(maxsize=None)
def _solver_class(name: str) -> type:
    """Return the scipy ``OdeSolver`` class ``name`` (``_CompensatedLSODA``: ours, built once)."""
    integrate = _integrate()
    if name != '_CompensatedLSODA':
        solver: type = getattr(integrate, name)
        return solver

    class _CompensatedLSODA(integrate.LSODA):  # type: ignore[misc,name-defined]  # (scipy)
        """
        scipy's LSODA whose time is the exact sum of its steps (:class:`_StepClock`).

        LSODA's own clock stays the one it steps and stops by (tcrit, the segment's end, is
        converted to it before every step); ``t``, ``t_old`` and the dense output (centred on
        ``t``) are in exact time, and the right-hand side gets the exact time.
        """

        def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float,
                     y0: np.ndarray, t_bound: float, **options: Any) -> None:
            if t0 != 0.0:
                raise ValueError('_CompensatedLSODA starts at t0 = 0 (local time)')
            self.clock = _StepClock()
            super().__init__(lambda t, y: fun(t + self.clock.shift, y), t0, y0, t_bound,
                             **options)

        def _step_impl(self) -> tuple[bool, str | None]:
            # scipy's LSODA._step_impl (one step, itask 5: never past tcrit) on LSODA's clock
            solver = self._lsoda_solver
            integrator = solver._integrator
            rwork = integrator.rwork
            rwork[0] = tcrit = self.t_bound - self.clock.shift  # the end, on LSODA's clock
            itask = integrator.call_args[2]
            integrator.call_args[2] = 5
            solver._y, solver.t = integrator.run(
                solver.f, solver.jac or (lambda: None), solver._y, solver.t, tcrit,
                solver.f_params, solver.jac_params)
            integrator.call_args[2] = itask
            if not solver.successful():
                return False, 'Unexpected istate in LSODA.'
            self.clock.add(float(rwork[10]), solver.t)
            # landed on tcrit: exactly the segment's end (scipy's step() then finishes)
            self.t = self.t_bound if solver.t >= tcrit else min(self.clock.time, self.t_bound)
            self.y = solver._y.copy()
            self.njev = self.nlu = integrator.iwork[12]
            return True, None

    return _CompensatedLSODA


class _ScipyStepper(Stepper):
    """Adapter from a ``scipy.integrate.OdeSolver`` class to :class:`Stepper`."""

    adaptive = True
    #: The name of its ``scipy.integrate`` solver class (resolved by :func:`_solver_class`).
    solver_name: str

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float, y0: np.ndarray,
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        self._solver: Any = None  # a scipy OdeSolver (untyped)
        if self.status == 'running':
            self._solver = _solver_class(self.solver_name)(
                self.local_fun, 0.0, self.y, self.tau_bound,
                rtol=settings.rtol, atol=settings.atol, max_step=_max_step(settings),
            )
        self._dense: Any = None

    @property
    def nfev(self) -> int:
        return int(self._solver.nfev) if self._solver is not None else 0

    def _step_impl(self) -> tuple[bool, str]:
        solver = self._solver
        h_abs = getattr(solver, 'h_abs', None)
        if h_abs is not None and h_abs != h_abs:
            # NaN step size (a non-finite right-hand side where the initial step was chosen):
            # scipy's step loop would neither accept nor fail, for ever (kernels.dop853.step)
            return False, step_nan_message(self.name, self.t0 + solver.t)
        message = solver.step()
        if solver.status == 'failed':
            return False, f'{self.name} failed at t = {self.t0 + solver.t:.10g} yr: {message}'
        self.tau_old, self.tau, self.y = solver.t_old, solver.t, solver.y
        self._dense = None
        return True, ''

    def _state_at_impl(self, tau: float) -> np.ndarray:
        if self._dense is None:
            self._dense = self._solver.dense_output()
        state: np.ndarray = self._dense(tau)
        return state


class RK45(_ScipyStepper):
    name, solver_name = 'rk45', 'RK45'
    order = 5


class DOP853(_ScipyStepper):
    name, solver_name = 'dop853', 'DOP853'
    order = 8
    kernel = 'dop853'  # core/kernels/dop853.py transcribes scipy's DOP853 step by step


class Radau(_ScipyStepper):
    name, solver_name = 'radau', 'Radau'


class BDF(_ScipyStepper):
    name, solver_name = 'bdf', 'BDF'


class LSODA(_ScipyStepper):
    name, solver_name = 'lsoda', '_CompensatedLSODA'


class Adams(Stepper):
    """
    VODE's variable-order (1-12) Adams-Moulton method in one-step mode.

    VODE may step beyond ``t_bound`` (it has no stop time in scipy's wrapper); the
    right-hand side is smooth past the segment end (it is the same closed-form function
    continued), and the state at ``t_bound`` is VODE's own interpolant, so the stepper
    still ends exactly on ``t_bound``.

    Time: VODE integrates in local time, and its own clock is *not* the time of its state.
    VODE advances its time as tn = fl(tn + h) while its Nordsieck history moves by exactly h;
    at tight tolerances it holds one step size (and order 7) for millions of steps, so the
    rounding of tn + h is the same at every step of a binade and adds up: over Fig 9's
    2000 yr (3.6e6 steps of 5.5e-4 yr) tn fell 1.8e-7 yr behind the sum of the steps, a
    2.3e-6 rad/yr error of the 90 rad/yr nutation whatever rtol (docs/physics.md). The stepper
    therefore keeps the exact sum of VODE's steps (compensated summation of h), hands out
    that as the state's time, converts its times to VODE's for dense output and gives the
    right-hand side the corrected time.
    """

    name = 'adams'
    adaptive = True

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float, y0: np.ndarray,
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        self._nfev = 0
        # the exact local time of VODE's state: hi + lo, the compensated sum of its steps
        self._hi = self._lo = 0.0
        self._shift = 0.0  # that time minus VODE's own (tn), after its last step
        t0 = self.t0

        def counted(tau: float, y: np.ndarray) -> np.ndarray:
            self._nfev += 1
            return fun(t0 + (tau + self._shift), y)

        self._ode = _integrate().ode(counted).set_integrator(
            'vode', method='adams', rtol=settings.rtol, atol=settings.atol,
            max_step=settings.max_step, nsteps=100_000,
        )
        self._ode.set_initial_value(self.y, 0.0)

    @property
    def nfev(self) -> int:
        return self._nfev

    def _step_impl(self) -> tuple[bool, str]:
        ode = self._ode
        tau_prev = self.tau
        if self._hi + self._lo < self.tau_bound:
            y = ode.integrate(self.tau_bound, step=True)
            if not ode.successful():
                return False, (f'adams (VODE) failed near t = {self.t0 + self._hi:.10g} yr '
                               f'(istate {ode.get_return_code()})')
            # the step VODE took: RWORK(11) = HU (scipy keeps VODE's work array)
            h = float(ode._integrator.rwork[10])
            hi = self._hi + h  # Knuth's TwoSum: hi + lo stays the exact sum of the steps
            b = hi - self._hi
            self._lo += (self._hi - (hi - b)) + (h - b)
            self._hi = hi
            self._shift = (hi - ode.t) + self._lo
        tau = self._hi + self._lo
        if tau >= self.tau_bound:
            y = self._interpolate(self.tau_bound)
            tau = self.tau_bound
        self.tau_old, self.tau, self.y = tau_prev, tau, np.array(y, dtype=float)
        return True, ''

    def _interpolate(self, tau: float) -> np.ndarray:
        # With itask=1 and tau behind VODE's current time, VODE interpolates within its last
        # step (its Nordsieck history) without stepping. Keep the ode object's own
        # notion of "current" (t, y) unchanged so the next one-step call continues there.
        ode = self._ode
        t_cur, y_cur = ode.t, ode._y
        # VODE's time of the state at local time tau
        y = np.array(ode.integrate(t_cur + ((tau - self._hi) - self._lo)), dtype=float)
        ok = ode.successful()
        ode.t, ode._y = t_cur, y_cur
        if not ok:
            raise RuntimeError(
                f'adams (VODE) could not interpolate at t = {self.t0 + tau!r} yr')
        return y

    def _state_at_impl(self, tau: float) -> np.ndarray:
        return self._interpolate(tau)

"""
Adaptive methods: scipy's step-by-step solvers and VODE's Adams method.

* ``rk45``, ``dop853``: explicit Runge-Kutta pairs (Dormand-Prince 5(4) and 8(5,3));
* ``radau``, ``bdf``: implicit methods for stiff problems (Jacobian by finite differences);
* ``lsoda``: ODEPACK's automatic Adams/BDF switching, the "ode" default of
  Scilab/Matlab-like platforms the paper used;
* ``adams``: variable-order, variable-step Adams-Moulton (VODE), the paper's "Adams".

Each solver integrates its segment in local time tau = t - t0 (``base``: "Local time").
"""
from __future__ import annotations

import numpy as np
from scipy import integrate

from .base import step_nan_message, Stepper

__all__ = ['RK45', 'DOP853', 'Radau', 'BDF', 'LSODA', 'Adams']


def _max_step(settings) -> float:
    return settings.max_step if settings.max_step > 0 else np.inf


class _ScipyStepper(Stepper):
    """Adapter from a ``scipy.integrate.OdeSolver`` class to :class:`Stepper`."""

    adaptive = True
    solver_class: type

    def __init__(self, fun, t0, y0, t_bound, settings, problem=None):
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        self._solver = None
        if self.status == 'running':
            self._solver = self.solver_class(
                self.local_fun, 0.0, self.y, self.tau_bound,
                rtol=settings.rtol, atol=settings.atol, max_step=_max_step(settings),
            )
        self._dense = None

    @property
    def nfev(self) -> int:
        return self._solver.nfev if self._solver is not None else 0

    def _step_impl(self):
        solver = self._solver
        h_abs = getattr(solver, 'h_abs', None)
        if h_abs is not None and h_abs != h_abs:
            # NaN step size (a non-finite right-hand side where the initial step was chosen):
            # scipy's step loop would neither accept nor fail, for ever (kernels._dop853_step)
            return False, step_nan_message(self.name, self.t0 + solver.t)
        message = solver.step()
        if solver.status == 'failed':
            return False, f'{self.name} failed at t = {self.t0 + solver.t:.10g} yr: {message}'
        self.tau_old, self.tau, self.y = solver.t_old, solver.t, solver.y
        self._dense = None
        return True, ''

    def _state_at_impl(self, tau):
        if self._dense is None:
            self._dense = self._solver.dense_output()
        return self._dense(tau)


class RK45(_ScipyStepper):
    name, solver_class = 'rk45', integrate.RK45
    order = 5


class DOP853(_ScipyStepper):
    name, solver_class = 'dop853', integrate.DOP853
    order = 8
    kernel = 'dop853'  # core/kernels.py transcribes scipy's DOP853 step by step


class Radau(_ScipyStepper):
    name, solver_class = 'radau', integrate.Radau


class BDF(_ScipyStepper):
    name, solver_class = 'bdf', integrate.BDF


class LSODA(_ScipyStepper):
    name, solver_class = 'lsoda', integrate.LSODA


class Adams(Stepper):
    """
    VODE's variable-order (1-12) Adams-Moulton method in one-step mode.

    VODE may step beyond ``t_bound`` (it has no stop time in scipy's wrapper); the
    right-hand side is smooth past the segment end (it is the same closed-form function
    continued), and the state at ``t_bound`` is VODE's own interpolant, so the stepper
    still ends exactly on ``t_bound``. VODE's time is the local time tau = t - t0.
    """

    name = 'adams'
    adaptive = True

    def __init__(self, fun, t0, y0, t_bound, settings, problem=None):
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        self._nfev = 0
        t0 = self.t0

        def counted(tau, y):
            self._nfev += 1
            return fun(t0 + tau, y)

        self._ode = integrate.ode(counted).set_integrator(
            'vode', method='adams', rtol=settings.rtol, atol=settings.atol,
            max_step=settings.max_step, nsteps=100_000,
        )
        self._ode.set_initial_value(self.y, 0.0)
        self._tau_internal = 0.0

    @property
    def nfev(self) -> int:
        return self._nfev

    def _step_impl(self):
        ode = self._ode
        tau_prev = self.tau
        if self._tau_internal < self.tau_bound:
            y = ode.integrate(self.tau_bound, step=True)
            if not ode.successful():
                return False, (f'adams (VODE) failed near t = {self.t0 + ode.t:.10g} yr '
                               f'(istate {ode.get_return_code()})')
            self._tau_internal = ode.t
        if self._tau_internal >= self.tau_bound:
            y = self._interpolate(self.tau_bound)
            tau_new = self.tau_bound
        else:
            tau_new = self._tau_internal
        self.tau_old, self.tau, self.y = tau_prev, tau_new, np.array(y, dtype=float)
        return True, ''

    def _interpolate(self, tau):
        # With itask=1 and tau behind VODE's current time, VODE interpolates within its last
        # step (its Nordsieck history) without stepping. Keep the ode object's own
        # notion of "current" (t, y) unchanged so the next one-step call continues there.
        ode = self._ode
        t_cur, y_cur = ode.t, ode._y
        y = np.array(ode.integrate(tau), dtype=float)
        ok = ode.successful()
        ode.t, ode._y = t_cur, y_cur
        if not ok:
            raise RuntimeError(
                f'adams (VODE) could not interpolate at t = {self.t0 + tau!r} yr')
        return y

    def _state_at_impl(self, tau):
        return self._interpolate(tau)

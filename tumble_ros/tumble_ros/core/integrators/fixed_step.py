"""
Fixed-step explicit methods: the classical Runge-Kutta method of order 4 ('rk4').

This is the paper's "R-K" procedure. On a segment [t0, t_bound] it takes
n = ceil((t_bound - t0) / step) equal steps, so it lands exactly on every segment edge
(impact starts and ends) while never exceeding the requested step. Like every stepper it
works in the segment's local time tau = t - t0 (``base``: "Local time").

The method's arithmetic is written once, in ``core/kernels/rk4.py`` (step count, stages,
combination, local times, Hermite weights); this stepper applies it to whole state vectors
(numpy, any attitude, any right-hand side), the compiled loop to each component.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.integrators.base import SegmentProblem, Stepper, StepSettings
from tumble_ros.core.kernels import rk4 as _rk4

# the kernel's functions run on numpy arrays (their Python source: the compiled ones take floats)
_step_count = python_source(_rk4.step_count)
_stage = python_source(_rk4.stage)
_combine = python_source(_rk4.combine)
_next_tau = python_source(_rk4.next_tau)
_hermite = python_source(_rk4.hermite)

__all__ = ['RK4']


class RK4(Stepper):
    """
    Classical 4th-order Runge-Kutta with a fixed step ``settings.step`` [yr].

    Dense output is the cubic Hermite interpolant on the step, whose O(h^4) error
    matches the method's global order. The end-of-step derivative it needs is reused as
    the first stage of the next step, so dense output costs no extra evaluation.
    """

    name = 'rk4'
    adaptive = False
    order = 4
    kernel = 'rk4'

    def __init__(self, fun: Callable[..., Any], t0: float, y0: npt.NDArray[np.float64],
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        span = self.tau_bound
        n = int(_step_count(span, settings.step))
        self._h = span / n
        self._n_total = n
        self._f: npt.NDArray[np.float64] | None = None  # derivative at (t, y), computed lazily
        self._y_old = self.y
        self._f_old = self.y
        self._nfev = 0

    @property
    def nfev(self) -> int:
        return self._nfev

    def _deriv(self) -> npt.NDArray[np.float64]:
        if self._f is None:
            f: npt.NDArray[np.float64] = self.local_fun(self.tau, self.y)
            self._f = f
            self._nfev += 1
            return f
        return self._f

    def _step_impl(self) -> tuple[bool, str]:
        h, tau, y = self._h, self.tau, self.y
        fun = self.local_fun
        k1 = self._deriv()
        k2 = fun(tau + 0.5 * h, _stage(y, k1, 0.5 * h))
        k3 = fun(tau + 0.5 * h, _stage(y, k2, 0.5 * h))
        k4 = fun(tau + h, _stage(y, k3, h))
        self._nfev += 3
        self._y_old, self._f_old = y, k1
        self.y = _combine(y, k1, k2, k3, k4, h)
        self.tau_old = tau
        # tau_k = k h, and exactly tau_bound at the last step (kernels.rk4.next_tau)
        self.tau = float(_next_tau(float(self.n_steps), float(self._n_total), h,
                                   self.tau_bound))
        self._f = None
        return True, ''

    def _state_at_impl(self, tau: float) -> npt.NDArray[np.float64]:
        tau_old = self.tau if self.tau_old is None else self.tau_old  # (after a step: set)
        h = self.tau - tau_old
        s = (tau - tau_old) / h
        f1 = self._deriv()
        h00, h10, h01, h11 = _hermite(s)
        y: npt.NDArray[np.float64] = (h00 * self._y_old + (h10 * h) * self._f_old + h01 * self.y
                                      + (h11 * h) * f1)
        return y

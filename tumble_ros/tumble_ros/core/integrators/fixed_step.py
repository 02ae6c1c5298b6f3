"""
Fixed-step explicit methods: the classical Runge-Kutta method of order 4 ('rk4').

This is the paper's "R-K" procedure. On a segment [t0, t_bound] it takes
n = ceil((t_bound - t0) / step) equal steps, so it lands exactly on every segment edge
(impact starts and ends) while never exceeding the requested step. Like every stepper it
works in the segment's local time tau = t - t0 (``base``: "Local time").
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .base import SegmentProblem, Stepper, StepSettings


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

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float, y0: np.ndarray,
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        span = self.tau_bound
        n = max(1, math.ceil(span / settings.step * (1.0 - 1e-12))) if span > 0 else 1
        self._h = span / n
        self._n_total = n
        self._f: np.ndarray | None = None  # derivative at (t, y), computed lazily
        self._y_old: np.ndarray | None = None
        self._f_old: np.ndarray | None = None
        self._nfev = 0

    @property
    def nfev(self) -> int:
        return self._nfev

    def _deriv(self) -> np.ndarray:
        if self._f is None:
            self._f = self.local_fun(self.tau, self.y)
            self._nfev += 1
        return self._f

    def _step_impl(self) -> tuple[bool, str]:
        h, tau, y = self._h, self.tau, self.y
        fun = self.local_fun
        k1 = self._deriv()
        k2 = fun(tau + 0.5 * h, y + (0.5 * h) * k1)
        k3 = fun(tau + 0.5 * h, y + (0.5 * h) * k2)
        k4 = fun(tau + h, y + h * k3)
        self._nfev += 3
        self._y_old, self._f_old = y, k1
        self.y = y + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
        self.tau_old = tau
        # tau_k = k h, and exactly tau_bound at the last step: no rounding accumulates in t
        # (over 10^6 steps, t + h + h + ... drifts by ~1e-10 yr, enough to show in the Jacobi
        # integral at the 1e-13 level).
        self.tau = (self.tau_bound if self.n_steps + 1 >= self._n_total
                    else (self.n_steps + 1) * h)
        self._f = None
        return True, ''

    def _state_at_impl(self, tau: float) -> np.ndarray:
        # state_at() hands out states within a step taken
        assert self.tau_old is not None and self._y_old is not None and self._f_old is not None
        h = self.tau - self.tau_old
        s = (tau - self.tau_old) / h
        f1 = self._deriv()
        h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
        h10 = s * (1.0 - s) ** 2
        h01 = s * s * (3.0 - 2.0 * s)
        h11 = s * s * (s - 1.0)
        return h00 * self._y_old + (h10 * h) * self._f_old + h01 * self.y + (h11 * h) * f1

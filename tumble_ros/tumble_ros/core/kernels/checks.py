"""
The failure checks after every step: a state no longer finite, a step size that collapsed.

Both paths run them: ``integrators.base.Stepper.step`` (reference) and ``stepping.step``
(compiled).
"""
from __future__ import annotations

import math

import numpy as np

from tumble_ros.core.compiling.jit import jit
from tumble_ros.core.kernels.layout import Array

__all__ = ['finite_norm', 'collapsed', 'MIN_STEP_ULPS']

#: A step shorter than this many units in the last place of the local time is a collapse.
MIN_STEP_ULPS = 16.0


@jit
def finite_norm(y: Array) -> bool:
    """
    Return whether |y|^2 is finite.

    No component is NaN or infinite, nor so large that its square overflows: such a state has
    no usable rotation matrix, energy or attitude.
    """
    acc = 0.0
    for i in range(y.shape[0]):
        acc += y[i] * y[i]
    return math.isfinite(acc)


@jit
def collapsed(tau_good: float, tau: float, tau_bound: float) -> bool:
    """
    Return whether a step from local time tau_good to tau (before tau_bound) collapsed.

    Shorter than :data:`MIN_STEP_ULPS` ulp of tau_good: the solution is singular or diverging.
    In local time, so a step inside a short pulse is judged against the pulse, not against t.
    """
    if not tau < tau_bound:
        return False
    ulp: float = np.nextafter(abs(tau_good), np.inf) - abs(tau_good)
    return tau - tau_good <= MIN_STEP_ULPS * ulp

"""
Integrators behind one interface (:class:`~.base.Stepper`) and a name registry.

Two registries, one namespace of names (``integrator.method`` of a scenario):

* ``METHODS``: general-purpose methods, any y' = f(t, y): rk4, rk45, dop853, radau, bdf,
  lsoda, adams;
* ``SPLITTING_METHODS``: structure-preserving Lie-Poisson splitting methods, which need the
  rigid-body structure of the segment (:class:`~.base.SegmentProblem`) and the quaternion
  attitude: splitting (order 2), splitting4, splitting6;
* ``INTEGRATORS`` = both: every name a scenario accepts.

Capability flags on each class: ``adaptive``, ``symplectic``, ``order``, ``attitudes``
(+ ``requirement``, the reason others are refused), ``needs_problem`` and ``kernel`` (a
compiled loop in ``core/kernels/``; :mod:`.compiled`).
"""
from __future__ import annotations

from tumble_ros.core.integrators.adaptive import Adams, BDF, DOP853, LSODA, Radau, RK45
from tumble_ros.core.integrators.base import FAILED, FINISHED, RUNNING, SegmentProblem, Stepper
from tumble_ros.core.integrators.fixed_step import RK4
from tumble_ros.core.integrators.splitting import Splitting, Splitting4, Splitting6

METHODS: dict[str, type[Stepper]] = {
    cls.name: cls for cls in (RK4, RK45, DOP853, Radau, BDF, LSODA, Adams)
}
SPLITTING_METHODS: dict[str, type[Stepper]] = {
    cls.name: cls for cls in (Splitting, Splitting4, Splitting6)
}
INTEGRATORS: dict[str, type[Stepper]] = {**METHODS, **SPLITTING_METHODS}

__all__ = ['METHODS', 'SPLITTING_METHODS', 'INTEGRATORS', 'Stepper', 'SegmentProblem',
           'RUNNING', 'FINISHED', 'FAILED']

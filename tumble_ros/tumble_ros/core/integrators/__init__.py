"""Integrators behind one interface (:class:`~.base.Stepper`) and a name registry.

``METHODS`` maps the names accepted in a scenario (``integrator.method``) to classes.
Capability flags on each class: ``adaptive`` (step size from rtol/atol) and
``symplectic``.
"""
from __future__ import annotations

from .adaptive import BDF, DOP853, LSODA, RK45, Adams, Radau
from .base import FAILED, FINISHED, RUNNING, Stepper
from .fixed_step import RK4

METHODS: dict[str, type[Stepper]] = {
    cls.name: cls for cls in (RK4, RK45, DOP853, Radau, BDF, LSODA, Adams)
}

__all__ = ["METHODS", "Stepper", "RUNNING", "FINISHED", "FAILED"]

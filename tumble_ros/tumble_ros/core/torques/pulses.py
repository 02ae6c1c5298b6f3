"""
Impact pulses: a constant torque on one integration segment (paper Fig. 10).

A pulse's torque is fixed either in the body (``frame: body``) or in the orbital frame
(``frame: orbital``, turned into body axes with the current attitude). The Propagator cuts
the run at every pulse's start and end, so on a segment the pulse torque is a constant (no
integrator steps over an edge). Units: inertia-units * rad/yr^2; the result in body axes.
"""
from __future__ import annotations

from tumble_ros.core.compiling.jit import jit_inline
from tumble_ros.core.torques.frames import orbital_to_body

__all__ = ['pulse_torque']


@jit_inline
def pulse_torque(bx: float, by: float, bz: float, has_orbital: float, mx: float, my: float,
                 mz: float, q0: float, q1: float, q2: float,
                 q3: float) -> tuple[float, float, float]:
    """Return the body-axis torque of a body-fixed pulse b plus an orbital-frame pulse m."""
    if has_orbital != 0.0:
        ox, oy, oz = orbital_to_body(mx, my, mz, q0, q1, q2, q3)
        return bx + ox, by + oy, bz + oz
    return bx, by, bz

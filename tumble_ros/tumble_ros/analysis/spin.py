"""
The tumbling state at the start and at the end of a recording (``core.model.spinstate``).

The torque-free spin state through the first and the last sample that has both w and the
attitude: mode (SAM / LAM), rotation and precession periods, the pole (L's direction in the
orbital frame), and how far the pole moved between them: what an impact sequence or an
encounter did to the tumbler. Each state is also given as the literature gives it, the
scenario's ``spin.*`` block (``core.model.observables.observe``: the inertia ratios and the
phases besides), when it is a SAM or a LAM of a triaxial body. Computed in years, rad/yr and
radians; shown in the recording's display units (``display``).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.observables import observe, SpinObservables
from tumble_ros.core.model.spinstate import spin_state, SpinState

from .recording import Recording
from .timeaxis import same_stamps

__all__ = ['SpinChange', 'spin_change', 'closest_approach']


@dataclass(frozen=True)
class SpinChange:
    """The spin state at the first and the last sample with an attitude, and the pole's shift."""

    t_start: float
    start: SpinState
    t_end: float
    end: SpinState
    pole_shift: float | None      # [rad]
    rate_start: float = 0.0       # |w| at t_start [rad/yr]
    rate_end: float = 0.0         # |w| at t_end [rad/yr]
    #: The start's and the end's state as a ``spin.*`` block (None: not a SAM or LAM of a
    #: triaxial body).
    start_block: SpinObservables | None = None
    end_block: SpinObservables | None = None


def spin_change(rec: Recording) -> tuple[SpinChange | None, str | None]:
    """Return (the change, None), or (None, why it cannot be computed)."""
    if rec.scenario is None:
        return None, 'no scenario (the inertia is unknown)'
    if not len(rec.quaternion_t):
        return None, 'no attitude recorded'
    ia, ib = same_stamps(rec.t, rec.quaternion_t)
    if not len(ia):
        return None, 'no sample with both w and the attitude'
    try:
        first = spin_state(rec.omega[ia[0]], rec.scenario.inertia, rec.quaternion[ib[0]])
        last = spin_state(rec.omega[ia[-1]], rec.scenario.inertia, rec.quaternion[ib[-1]])
    except ValueError as err:
        return None, str(err)
    shift = None
    if first.pole is not None and last.pole is not None:
        shift = math.acos(max(-1.0, min(1.0, float(np.dot(first.pole, last.pole)))))
    return SpinChange(float(rec.t[ia[0]]), first, float(rec.t[ia[-1]]), last, shift,
                      float(np.linalg.norm(rec.omega[ia[0]])),
                      float(np.linalg.norm(rec.omega[ia[-1]])),
                      _block(rec.omega[ia[0]], rec.scenario.inertia, rec.quaternion[ib[0]]),
                      _block(rec.omega[ia[-1]], rec.scenario.inertia, rec.quaternion[ib[-1]])
                      ), None


def _block(omega: np.ndarray, inertia: tuple[float, float, float],
           quaternion: np.ndarray) -> SpinObservables | None:
    """Return the ``spin.*`` block of one sample, None if it has none (``observe`` refuses)."""
    try:
        return observe(omega, inertia, quaternion)
    except ScenarioError:
        return None


def closest_approach(rec: Recording) -> tuple[float, float] | None:
    """Return (t [yr], distance [km]) of the torquing body's nearest recorded sample, or None."""
    if not len(rec.perturber_t):
        return None
    distance = np.linalg.norm(rec.perturber, axis=1)
    k = int(np.argmin(distance))
    return float(rec.perturber_t[k]), float(distance[k])

"""
Lie-Poisson splitting methods for the rigid body in the Sun's tidal field ('splitting*').

Structure-preserving integrators for long runs (Touma & Wisdom 1994; Dullweber, Leimkuhler &
McLachlan 1997; McLachlan 1993). The state is the body angular momentum pi = I w and the
attitude quaternion q (body -> orbital); the Hamiltonian of the problem is

    H = T(pi) + V(q, t),   T = sum_i pi_i^2 / (2 I_i),   V = 3/2 ws^2 u.I.u,  u = C(q)^T s(t)

(s(t) the Sun direction; pulses add a constant torque on their segment). It is split into
pieces whose flows are exact:

* **kick** V (attitude frozen): pi += a * tau(q, t), tau = 3 ws^2 u x Iu (+ the segment's pulse
  torque, body-fixed or orbital-fixed: both are constant while the attitude is frozen).
* **free flow** T, split per axis about a reference moment I_r (the middle one)::

      T = |pi|^2 / (2 I_r) + sum_{i != r} 1/2 (1/I_i - 1/I_r) pi_i^2

  The first piece turns the attitude about the body vector pi by |pi| a / I_r (pi fixed);
  each axis piece turns pi by -c_i pi_i a about body axis i and the attitude by +c_i pi_i a
  (Dullweber et al.'s rotations, with the |pi|^2 part taken out: it Poisson-commutes with
  every function of pi). With two non-zero axis pieces they are composed symmetrically
  (B_i(a/2) B_k(a) B_i(a/2)); for an axially symmetric body (the paper's Ix = Iy) only one
  remains and the free flow is exact.

Every piece is a rotation, so |pi| and the inertial angular momentum L = C(q) pi are kept by
the free flow to rounding, and so is |q|. Time enters only through V: it is advanced in the
free flow (extended phase space, H + p_t), which makes the method symplectic for the
time-dependent problem; since V depends on t only through the turning Sun line, each kick
changes p_t and Omega.L by opposite amounts, so the Jacobi integral J = H - Omega.L inherits
the bounded (non-secular) energy error of symplectic methods.

The base step is Strang's kick-drift-kick (order 2, symmetric). ``splitting4`` and
``splitting6`` are symmetric compositions of it (Yoshida 1990 triple jump, order 4; Kahan & Li
1997 nine-stage, order 6): each stage is a base step of gamma_j h. One torque evaluation per
stage (the closing kick's torque opens the next stage).

Fixed step: a segment is covered by n = ceil(span / step) equal steps, so pulses start and end on
step boundaries and are integrated with their own constant torque (exact splitting at impact edges,
as for every method). A pulse segment gets more steps when its torque calls for them
(``kernels.splitting.pulse_step_count``: the pulse's own error terms, made no larger per unit time
than those of a regular step, so the jump converges with the order of the method). The steps are
taken in the segment's local time t - t0 (``base``: "Local time"). Dense output: a step of the same
method from the start of the step to the requested time, so interpolated values carry the method's
own local error, O(h^{p+1}) (order p), and coincide with the step's end point at its end.

The physics of a step (the torque, the free flow) is written once, in ``core/kernels/physics.py``:
this stepper calls those functions (compiled, or plain Python without numba) one step at a time, as
the reference path; the compiled loop runs them many steps per call.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from tumble_ros.core.integrators.base import SegmentProblem, Stepper, StepSettings
from tumble_ros.core.kernels import (body_torque, config_array, flow_called, N, new_state,
                                     problem_array, pulse_step_count, ST)
from tumble_ros.core.torques import extra_torque_arrays


__all__ = ['Splitting', 'Splitting4', 'Splitting6', 'COMPOSITIONS']

_Y4 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
#: Symmetric composition coefficients gamma_j of the Strang step, by order.
COMPOSITIONS: dict[int, tuple[float, ...]] = {
    2: (1.0,),
    # Yoshida (1990), the "triple jump"
    4: (_Y4, 1.0 - 2.0 * _Y4, _Y4),
    # Kahan & Li (1997), 9 stages, order 6 (Hairer, Lubich & Wanner, GNI, V.3.2)
    6: (0.39216144400731413927925056, 0.33259913678935943859974864, -0.70624617255763935980996482,
        0.08221359629355080023149045, 0.79854399093482996339895035, 0.08221359629355080023149045,
        -0.70624617255763935980996482, 0.33259913678935943859974864, 0.39216144400731413927925056),
}


class Splitting(Stepper):
    """
    Strang (kick-drift-kick) Lie-Poisson splitting, order 2, fixed step ``settings.step``.

    Needs the segment's :class:`~.base.SegmentProblem` (``problem=``); quaternion attitude only.
    """

    name = 'splitting'
    adaptive = False
    symplectic = True
    order = 2
    needs_problem = True
    attitudes = frozenset({'quaternion'})
    requirement = ('it composes exact rotations of the attitude quaternion and needs the '
                   "rigid-body structure; use attitude 'quaternion'")
    kernel = 'splitting'

    @classmethod
    def composition(cls) -> tuple[float, ...]:
        return COMPOSITIONS[cls.order]

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], t0: float, y0: np.ndarray,
                 t_bound: float, settings: StepSettings,
                 problem: SegmentProblem | None = None) -> None:
        super().__init__(fun, t0, y0, t_bound, settings, problem=problem)
        if problem is None:
            raise ValueError(f'{self.name}: needs the rigid-body problem '
                             '(problem=SegmentProblem), it cannot integrate a bare right-hand '
                             'side')
        if problem.attitude not in self.attitudes:
            raise ValueError(
                f'{self.name}: attitude {problem.attitude!r} not supported: {self.requirement}')
        span = self.tau_bound
        wx, wy, wz = self.y[:3].tolist()
        # The segment's arrays, as the compiled loop has them: the step below is the kernels'
        # own (one implementation of the method and its physics), taken one at a time.
        self._p = problem_array(problem.inertia, problem.orbit_rate, problem.torque_body,
                                problem.torque_orbital)
        self._extra = extra_torque_arrays(problem.extra_torques)
        n = int(pulse_step_count(self._p, span, float(settings.step), float(self.order),
                                 wx, wy, wz))
        self._h = span / n
        self._n_total = n
        self._gammas = self.composition()
        self._cfg = config_array(self.kernel, settings, self._gammas, self.order)
        self._work = new_state()  # the kernels' state layout, for their flow
        self._torq: tuple[float, ...] = body_torque(self._p, self._extra, self.t0 + self.tau,
                                                    *self.y[3:].tolist())
        ix, iy, iz = problem.inertia
        # pi = I w is carried from step to step, not recomputed from w: the round trip
        # w -> I w -> w would bias |L| by ~1e-17 per step (1e-12 over 10^5 steps).
        self._pi: tuple[float, ...] = (ix * self.y[0], iy * self.y[1], iz * self.y[2])
        self._y_old: np.ndarray | None = None
        self._pi_old: tuple[float, ...] | None = None
        self._torq_old: tuple[float, ...] | None = None
        self._nfev = 0

    @property
    def nfev(self) -> int:
        """Torque evaluations (one per stage)."""
        return self._nfev

    def _flow(self, s0: float, y: np.ndarray, pi: Sequence[float], torq: Sequence[float],
              h: float) -> tuple[np.ndarray, tuple[float, ...], tuple[float, ...]]:
        """
        Take a composed step of length h: the kernels' own step (``kernels.splitting.flow``).

        From local time s0, attitude y[3:], momentum pi and torque torq; returns (state,
        momentum, torque at the end).
        """
        st = self._work
        st[ST.Y_OLD:ST.Y_OLD + N] = y
        st[ST.PI_OLD:ST.PI_OLD + 3] = pi
        st[ST.TORQUE_OLD:ST.TORQUE_OLD + 3] = torq
        flow_called(self._p, self._extra, self._cfg, st, ST.Y_OLD, ST.PI_OLD, ST.TORQUE_OLD,
                    self.t0, s0, h, ST.Y, ST.PI, ST.TORQUE)
        return (st[ST.Y:ST.Y + N].copy(), tuple(st[ST.PI:ST.PI + 3].tolist()),
                tuple(st[ST.TORQUE:ST.TORQUE + 3].tolist()))

    def _step_impl(self) -> tuple[bool, str]:
        s = self.tau
        self._y_old, self._pi_old, self._torq_old = self.y, self._pi, self._torq
        try:
            self.y, self._pi, self._torq = self._flow(s, self.y, self._pi, self._torq, self._h)
        except (ValueError, OverflowError):
            # math.cos/sin of an infinite angle (|pi| overflowed): the compiled loop gets NaN
            # there and reports the same
            self.y, self._pi, self._torq = self._y_old, self._pi_old, self._torq_old
            return False, f'non-finite state after t = {self.t:.10g} yr'
        self._nfev += len(self._gammas)
        self.tau_old = s
        # tau_k = k h: no rounding accumulated in t over millions of steps
        self.tau = (self.tau_bound if self.n_steps + 1 >= self._n_total
                    else (self.n_steps + 1) * self._h)
        return True, ''

    def _state_at_impl(self, tau: float) -> np.ndarray:
        # state_at() hands out states within a step taken
        assert self.tau_old is not None and self._y_old is not None
        assert self._pi_old is not None and self._torq_old is not None
        return self._flow(self.tau_old, self._y_old, self._pi_old, self._torq_old,
                          tau - self.tau_old)[0]


class Splitting4(Splitting):
    """Order 4: Yoshida's triple jump of the Strang step (3 stages)."""

    name = 'splitting4'
    order = 4


class Splitting6(Splitting):
    """Order 6: Kahan & Li's 9-stage symmetric composition of the Strang step."""

    name = 'splitting6'
    order = 6

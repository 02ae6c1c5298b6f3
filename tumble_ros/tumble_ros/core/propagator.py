"""Incremental integration of a scenario, split at impact edges (tstops).

:class:`Propagator` owns the state of one simulated asteroid and advances it to any
requested time, so a ROS node can publish as it goes, stop, or schedule a new impact at
any moment. The integration is cut into *segments* whose edges are the start and end of
every impact pulse: the right-hand side is smooth on each segment (the pulse torque is
constant on it), and every method lands exactly on the edges. This is what
DifferentialEquations.jl calls ``tstops``; without it an adaptive method can step over a
pulse of 3e-7 yr entirely (the paper's Fig. 10 "ode" failure).

A non-finite state, a collapsing step size or a singular attitude stop the propagation:
:class:`IntegrationError` is raised and ``status``/``message`` say why; no NaN is ever
returned.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from .dynamics import ATTITUDE_MODELS, jacobi_integral
from .integrators import FAILED, METHODS, RUNNING
from .rotation import matrix_to_quaternion, unwrap_towards
from .scenario import Impact, Scenario, ScenarioError

__all__ = ["Propagator", "IntegrationError", "Sample"]

#: Largest attitude change [rad] between two points used to unwrap Euler angles.
_UNWRAP_STEP = 1.0
_UNWRAP_MIN_SIN = 0.1


class IntegrationError(RuntimeError):
    """The integration diverged or failed; ``t`` is the last good time [yr]."""

    def __init__(self, message: str, t: float) -> None:
        super().__init__(message)
        self.t = t


@dataclass(frozen=True)
class Sample:
    """The state at one time.

    Attributes
    ----------
    t : float
        Simulated time [yr].
    omega : (3,) array
        Angular velocity [rad/yr], body axes.
    quaternion : (4,) array
        Unit attitude quaternion, scalar first, body -> orbital frame.
    euler : (3,) array
        The paper's (phi, psi, theta) [rad]; phi and psi continuous (not wrapped).
    matrix : (3, 3) array
        C = body -> orbital rotation matrix.
    inertia, orbit_rate : the scenario's, for :attr:`jacobi`.
    """

    t: float
    omega: np.ndarray
    quaternion: np.ndarray
    euler: np.ndarray
    matrix: np.ndarray
    inertia: tuple[float, float, float]
    orbit_rate: float

    @property
    def jacobi(self) -> float:
        """Jacobi integral (``dynamics.jacobi_integral``), computed on demand."""
        return float(jacobi_integral(self.t, self.omega, self.matrix, self.inertia, self.orbit_rate))


class Propagator:
    """Advance a scenario's state in time, impacts included.

    Parameters
    ----------
    scenario : Scenario
        Validated scenario (its impacts are scheduled from the start).
    split_impacts : bool
        Cut the integration at impact edges (default). ``False`` puts the pulse into the
        right-hand side as a time switch instead; it exists only to demonstrate the
        failure this design prevents (docs/physics.md).
    """

    def __init__(self, scenario: Scenario, *, split_impacts: bool = True) -> None:
        self.scenario = scenario
        self._model = ATTITUDE_MODELS[scenario.attitude]
        self._method = METHODS[scenario.integrator.method]
        self._split = split_impacts
        self._impacts: list[Impact] = []
        self._edges: list[float] = [scenario.duration]
        self.t = 0.0
        self.y = np.concatenate([scenario.omega0, self._model.from_euler(*scenario.euler0)])
        self.status = RUNNING
        self.message = ""
        self._nfev_done = 0
        self.n_steps = 0
        self._euler_track = np.array(scenario.euler0, dtype=float)
        self._quat_prev = None
        self._edge_state: dict[float, np.ndarray] = {}  # state at impact edges reached so far
        self._reported: set[int] = set()
        self._stepper = None
        for impact in scenario.impacts:
            self.schedule(impact)
        self._start_segment(self.t, self.y)

    # -- public API -----------------------------------------------------------------
    @property
    def t_end(self) -> float:
        """End of the scenario [yr]."""
        return self.scenario.duration

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""
        return self._nfev_done + self._stepper.nfev

    @property
    def impacts(self) -> tuple[Impact, ...]:
        """All impacts scheduled so far, in order of start time."""
        return tuple(self._impacts)

    def schedule(self, impact: Impact) -> None:
        """Add an impact; its start must not lie before the current time ``t``."""
        if impact.start < self.t:
            raise ScenarioError(f"impact.start: must be >= the current time {self.t!r} yr, got {impact.start!r}")
        if impact.end > self.t_end:
            raise ScenarioError(f"impact: must end by the end of the scenario ({self.t_end!r} yr), "
                                f"ends at {impact.end!r}")
        bisect.insort(self._impacts, impact, key=lambda i: i.start)
        affects_segment = self._stepper is not None and impact.start < self._stepper.t_bound
        if self._split:
            for edge in (impact.start, impact.end):
                k = bisect.bisect_left(self._edges, edge)
                if k == len(self._edges) or self._edges[k] != edge:
                    self._edges.insert(k, edge)
        if affects_segment or not self._split:
            # Restart from the last state handed out: the running segment's right-hand
            # side or end no longer holds.
            self._start_segment(self.t, self.y)

    def advance_to(self, t: float) -> np.ndarray:
        """Integrate to time ``t`` [yr] (not before the current time) and return the state.

        Raises IntegrationError when the integration fails; ``status`` is then
        ``"failed"`` and stays so.
        """
        if self.status == FAILED:
            raise IntegrationError(self.message, self.t)
        if not self.t <= t <= self.t_end:
            raise ValueError(f"t = {t!r} must lie in [{self.t!r}, {self.t_end!r}] yr")
        stepper = self._stepper
        while t > stepper.t:
            if stepper.status != RUNNING:
                self._start_segment(stepper.t, stepper.y.copy())
                stepper = self._stepper
                continue
            self._step(stepper)
        self.y = stepper.state_at(t)
        self.t = t
        return self.y

    def pop_completed_impacts(self) -> list[tuple[Impact, np.ndarray, np.ndarray]]:
        """Impacts that ended by the current time and were not returned before.

        Each entry is (impact, state at its start, state at its end); the measured change
        of w [rad/yr, body axes] is ``end[:3] - start[:3]``.
        """
        done = []
        for impact in self._impacts:
            key = id(impact)
            if key in self._reported or impact.end > self.t:
                continue
            y_end = self._edge_state.get(impact.end)
            if y_end is None and self.t == impact.end:
                y_end = self.y.copy()  # the segment after the pulse has not started yet
            if y_end is not None and impact.start in self._edge_state:
                self._reported.add(key)
                done.append((impact, self._edge_state[impact.start], y_end))
        return done

    def quaternion_of(self, y: np.ndarray) -> np.ndarray:
        """Unit quaternion (scalar first, body -> orbital) of a state vector."""
        if self._model.name == "quaternion":
            return y[3:] / np.linalg.norm(y[3:])
        return matrix_to_quaternion(self._model.to_matrix(y[3:]))

    def sample(self, t: float) -> Sample:
        """Advance to ``t`` and describe the state there."""
        y = self.advance_to(t)
        attitude = y[3:]
        c = self._model.to_matrix(attitude)
        q = self.quaternion_of(y)
        if self._quat_prev is not None and np.dot(q, self._quat_prev) < 0.0:
            q = -q  # keep the quaternion continuous in time (q and -q are the same attitude)
        self._quat_prev = q
        return Sample(
            t=t,
            omega=y[:3].copy(),
            quaternion=q,
            euler=self._continuous_euler(attitude),
            matrix=c,
            inertia=self.scenario.inertia,
            orbit_rate=self.scenario.orbit_rate,
        )

    # -- internals ------------------------------------------------------------------
    def _start_segment(self, t0: float, y0: np.ndarray) -> None:
        if any(t0 in (i.start, i.end) for i in self._impacts):
            self._edge_state[t0] = np.array(y0)
        k = bisect.bisect_right(self._edges, t0)
        t_bound = self._edges[k] if k < len(self._edges) else self.t_end
        rhs = self._rhs_for(t0, t_bound)
        if self._stepper is not None:
            self._nfev_done += self._stepper.nfev
        self._stepper = self._method(rhs, t0, y0, t_bound, self.scenario.integrator)

    def _rhs_for(self, t0: float, t1: float):
        sc, make = self.scenario, self._model.make_rhs
        if not self._split:
            return self._switching_rhs()
        mid = 0.5 * (t0 + t1)
        body, orbital = np.zeros(3), np.zeros(3)
        for impact in self._impacts:
            if impact.start <= mid < impact.end:
                (body if impact.frame == "body" else orbital)[:] += impact.torque
        return make(sc.inertia, sc.orbit_rate, tuple(body), tuple(orbital))

    def _switching_rhs(self):
        """Pulses as a time switch inside one smooth-looking RHS (demonstration only)."""
        sc, make = self.scenario, self._model.make_rhs
        free = make(sc.inertia, sc.orbit_rate)
        pulses = [(i, make(sc.inertia, sc.orbit_rate, *((i.torque, (0, 0, 0)) if i.frame == "body"
                                                          else ((0, 0, 0), i.torque))))
                  for i in self._impacts]

        def rhs(t, y):
            for impact, pulsed in pulses:
                if impact.start <= t < impact.end:
                    return pulsed(t, y)
            return free(t, y)

        return rhs

    def _step(self, stepper) -> None:
        t_before = stepper.t
        stepper.step()
        self.n_steps += 1
        message = stepper.message
        if stepper.status != FAILED and self._model.singular(stepper.y[3:]):
            message = (f"attitude singular at t = {stepper.t:.10g} yr (theta = {stepper.y[5]:.3g} rad): the "
                       "Euler-angle equations divide by sin(theta); use attitude 'quaternion'")
        if stepper.status == FAILED or message:
            self.status, self.message = FAILED, message
            raise IntegrationError(message, t_before)
        if self._model.name == "quaternion":
            self._track_euler(stepper)

    def _track_euler(self, stepper) -> None:
        """Follow phi, psi continuously through the step just taken (quaternion mode)."""
        y = stepper.y
        w = math.sqrt(y[0] ** 2 + y[1] ** 2 + y[2] ** 2)
        cos_theta = self._model.to_matrix(y[3:])[2, 2]
        # phi and psi turn at up to |w| / sin(theta): subdivide long steps accordingly.
        # Below theta ~ 0.1 only phi + psi is well defined, so the bound stops growing.
        rate = w / max(_UNWRAP_MIN_SIN, math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta)))
        h = stepper.t - stepper.t_old
        n = max(1, math.ceil(rate * h / _UNWRAP_STEP))
        for j in range(1, n + 1):
            tj = stepper.t if j == n else stepper.t_old + h * j / n
            att = y[3:] if j == n else stepper.state_at(tj)[3:]
            self._euler_track = self._unwrapped(att)

    def _unwrapped(self, attitude) -> np.ndarray:
        phi, psi, theta = self._model.to_euler(attitude)
        ref = self._euler_track
        return np.array([unwrap_towards(phi, ref[0]), unwrap_towards(psi, ref[1]), theta])

    def _continuous_euler(self, attitude) -> np.ndarray:
        if self._model.name != "quaternion":
            return np.array(attitude, dtype=float)
        return self._unwrapped(attitude)

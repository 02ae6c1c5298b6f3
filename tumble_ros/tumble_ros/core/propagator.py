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

Fast path: for methods with a compiled loop (rk4, dop853, splitting*; quaternion attitude)
and numba available, each segment is run by a
:class:`~.integrators.compiled.CompiledStepper`, which takes all the steps up to a requested
time (and samples a whole output grid, :meth:`Propagator.sample_many`) without returning to
Python per step. Same steps, same results as the reference path (``fast=False``) to
rounding (tests/test_core_fast.py).
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from .dynamics import ATTITUDE_MODELS, jacobi_integral
from .integrators import FAILED, INTEGRATORS, RUNNING, SegmentProblem
from .integrators.compiled import CompiledStepper, why_no_fast_path
from .rotation import matrix_to_quaternion, unwrap_towards
from .scenario import Impact, Scenario, ScenarioError

__all__ = ["Propagator", "IntegrationError", "Sample", "segment_torques", "quaternions_to_matrices"]

#: Largest attitude change [rad] between two points used to unwrap Euler angles.
_UNWRAP_STEP = 1.0
_UNWRAP_MIN_SIN = 0.1


class IntegrationError(RuntimeError):
    """The integration diverged or failed; ``t`` is the last good time [yr]."""

    def __init__(self, message: str, t: float) -> None:
        super().__init__(message)
        self.t = t


def segment_torques(impacts, t0: float, t1: float) -> tuple[tuple, tuple]:
    """(body, orbital) pulse torques active on the segment [t0, t1] (whose edges are pulse edges)."""
    mid = 0.5 * (t0 + t1)
    body, orbital = np.zeros(3), np.zeros(3)
    for impact in impacts:
        if impact.start <= mid < impact.end:
            (body if impact.frame == "body" else orbital)[:] += impact.torque
    return tuple(body), tuple(orbital)


def quaternions_to_matrices(q: np.ndarray) -> np.ndarray:
    """``rotation.quaternion_to_matrix`` for an (..., 4) array (same arithmetic): (..., 3, 3)."""
    q0, q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    s = 2.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    c = np.empty(q.shape[:-1] + (3, 3))
    c[..., 0, 0] = 1.0 - s * (q2 * q2 + q3 * q3)
    c[..., 0, 1] = s * (q1 * q2 - q0 * q3)
    c[..., 0, 2] = s * (q1 * q3 + q0 * q2)
    c[..., 1, 0] = s * (q1 * q2 + q0 * q3)
    c[..., 1, 1] = 1.0 - s * (q1 * q1 + q3 * q3)
    c[..., 1, 2] = s * (q2 * q3 - q0 * q1)
    c[..., 2, 0] = s * (q1 * q3 - q0 * q2)
    c[..., 2, 1] = s * (q2 * q3 + q0 * q1)
    c[..., 2, 2] = 1.0 - s * (q1 * q1 + q2 * q2)
    return c


def continuous_quaternions(q: np.ndarray, previous=None) -> np.ndarray:
    """Normalise (n, 4) quaternions and flip signs so that consecutive ones have q.q' >= 0
    (as :meth:`Propagator.sample` does one at a time; ``previous`` is the last one handed out)."""
    q = q / np.sqrt(np.sum(q * q, axis=-1, keepdims=True))
    if len(q) == 0:
        return q
    dots = np.einsum("ij,ij->i", q[1:], q[:-1])
    first = -1.0 if previous is not None and np.dot(q[0], previous) < 0.0 else 1.0
    signs = np.cumprod(np.concatenate([[first], np.where(dots < 0.0, -1.0, 1.0)]))
    return q * signs[:, None]


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
        failure this design prevents (docs/physics.md). Not available with the splitting
        methods (they need a constant torque per segment).
    fast : bool or None
        Use the method's compiled loop (:mod:`~.integrators.compiled`): ``None`` (default)
        when available, ``True`` to require it (ValueError saying why if it is not),
        ``False`` for the reference step-by-step path. Both give the same trajectory.
    """

    def __init__(self, scenario: Scenario, *, split_impacts: bool = True, fast: bool | None = None) -> None:
        self.scenario = scenario
        self._model = ATTITUDE_MODELS[scenario.attitude]
        self._method = INTEGRATORS[scenario.integrator.method]
        self._split = split_impacts
        if self._method.needs_problem and not split_impacts:
            raise ValueError(f"split_impacts=False is not available with method {self._method.name!r}: "
                             "it needs a constant torque on each segment")
        why = why_no_fast_path(self._method, scenario.attitude)
        if not split_impacts:
            why = "split_impacts=False (a time-switched right-hand side) runs on the reference path"
        if fast and why:
            raise ValueError(f"fast path not available: {why}")
        self.fast = not why if fast is None else bool(fast)
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
            if self.fast:
                self._advance_compiled(stepper, t)
            else:
                self._step(stepper)
        self.y = stepper.state_at(t)
        self.t = t
        return self.y

    def sample_many(self, times) -> tuple[int, dict[str, np.ndarray], str]:
        """:meth:`sample` at every time of the sorted sequence ``times``, as arrays.

        Returns ``(n_done, arrays, message)``: ``arrays`` has ``omega`` (n, 3), ``euler``
        (n, 3), ``quaternion`` (n, 4) and ``matrix`` (n, 3, 3), of which the first ``n_done``
        rows are valid; ``message`` says why the rest are missing (integration failure),
        empty when n_done == n. On the fast path the whole grid is sampled inside the
        compiled loop (one call per segment).
        """
        times = np.ascontiguousarray(times, dtype=float)
        n = times.size
        if n and self.status != FAILED and not self.t <= times[0]:
            raise ValueError(f"t = {times[0]!r} must lie in [{self.t!r}, {self.t_end!r}] yr")
        if n and times[-1] > self.t_end:
            raise ValueError(f"t = {times[-1]!r} must lie in [{self.t!r}, {self.t_end!r}] yr")
        omega, euler = np.empty((n, 3)), np.empty((n, 3))
        quat, matrices = np.empty((n, 4)), np.empty((n, 3, 3))
        arrays = {"omega": omega, "euler": euler, "quaternion": quat, "matrix": matrices}
        if not self.fast:
            for k, t in enumerate(times):
                try:
                    s = self.sample(float(t))
                except IntegrationError as err:
                    return k, arrays, str(err)
                omega[k], euler[k], quat[k], matrices[k] = s.omega, s.euler, s.quaternion, s.matrix
            return n, arrays, ""
        if self.status == FAILED:
            return 0, arrays, self.message
        y_out = np.empty((n, 7))
        k, message = 0, ""
        while k < n:
            stepper = self._stepper
            if stepper.status != RUNNING and times[k] > stepper.t:
                self._start_segment(stepper.t, stepper.y.copy())
                continue
            k, steps = stepper.advance(times[-1], self._euler_track, times, y_out, euler, k)
            self.n_steps += steps
            if stepper.status == FAILED:
                self.status, self.message = FAILED, stepper.message
                message = stepper.message
                break
        if k:
            y = y_out[:k]
            omega[:k] = y[:, :3]
            quat[:k] = continuous_quaternions(y[:, 3:], self._quat_prev)
            matrices[:k] = quaternions_to_matrices(y[:, 3:])
            self._quat_prev = quat[k - 1].copy()
            self.t, self.y = float(times[k - 1]), y_out[k - 1].copy()
        return k, arrays, message

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
        if self._stepper is not None:
            self._nfev_done += self._stepper.nfev
        problem = self._problem_for(t0, t_bound)
        settings = self.scenario.integrator
        if self.fast:
            self._stepper = CompiledStepper(self._method, None, t0, y0, t_bound, settings, problem=problem)
        else:
            rhs = self._rhs_for(t0, t_bound)
            self._stepper = self._method(rhs, t0, y0, t_bound, settings, problem=problem)

    def _problem_for(self, t0: float, t1: float) -> SegmentProblem:
        sc = self.scenario
        body, orbital = segment_torques(self._impacts, t0, t1) if self._split else ((0.0,) * 3, (0.0,) * 3)
        return SegmentProblem(sc.inertia, sc.orbit_rate, body, orbital, sc.attitude)

    def _rhs_for(self, t0: float, t1: float):
        sc, make = self.scenario, self._model.make_rhs
        if not self._split:
            return self._switching_rhs()
        body, orbital = segment_torques(self._impacts, t0, t1)
        return make(sc.inertia, sc.orbit_rate, body, orbital)

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

    def _advance_compiled(self, stepper, t: float) -> None:
        _, steps = stepper.advance(t, self._euler_track)
        self.n_steps += steps
        if stepper.status == FAILED:
            self.status, self.message = FAILED, stepper.message
            raise IntegrationError(stepper.message, stepper.t)

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

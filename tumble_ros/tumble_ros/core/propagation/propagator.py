"""
Incremental integration of a scenario, split at impact edges (tstops).

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
from dataclasses import dataclass
import functools
import heapq
import math
import operator
from typing import Callable, NamedTuple, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.integrators import FAILED, INTEGRATORS, RUNNING, SegmentProblem
from tumble_ros.core.integrators.base import Stepper
from tumble_ros.core.integrators.compiled import CompiledStepper, why_no_fast_path
from tumble_ros.core.kernels.checks import finite_norm
from tumble_ros.core.kernels.tracking import track_pieces, track_rate, unwrapped_euler
from tumble_ros.core.model.dynamics import ATTITUDE_MODELS, AttitudeModel, jacobi_integral
from tumble_ros.core.model.rotation import (continuous_quaternions, matrix_to_quaternion,
                                            quaternions_to_matrices)
from tumble_ros.core.model.scenario import Impact, Scenario, ScenarioError
from tumble_ros.core.propagation.segments import NO_PULSE, Segment, SegmentRow, split_rows
from tumble_ros.core.torques.component import TorqueComponent
from tumble_ros.errors import CoreError

__all__ = ['Propagator', 'IntegrationError', 'Sample',
           'quaternions_to_matrices', 'FAST_WORK_BUDGET', 'REFERENCE_WORK_BUDGET']

#: Work per call of :meth:`Propagator.sample_many` (and per compiled call of
#: :meth:`Propagator.advance_to`): steps plus the dense evaluations of the Euler-angle
#: tracking, and at most as many samples. Compiled steps take ~0.3-3 us: 50,000 units stay
#: below ~0.15 s, so a node calling in a timer serves its signals in time. Reference-path
#: steps take 20-200 us in Python (scipy's implicit methods more).
FAST_WORK_BUDGET = 50_000
REFERENCE_WORK_BUDGET = 1_000
_NO_OMEGA = np.zeros(3)
#: A segment's start t0 and end t1 (its first fields): the keys of the bisections over them.
_SEGMENT_T0 = operator.itemgetter(0)
_SEGMENT_T1 = operator.itemgetter(1)
#: An impact's start: the key its lists are sorted by.
_START = operator.attrgetter('start')

FloatArray = npt.NDArray[np.float64]
#: A right-hand side f(t, y) of the equations of motion.
Rhs = Callable[[float, FloatArray], FloatArray]


def _interpolated_nonfinite_message(t: float) -> str:
    return f'non-finite state at t = {t:.10g} yr (interpolated inside a step that ran away)'


class IntegrationError(CoreError, RuntimeError):
    """The integration diverged or failed; ``t`` is the last good time [yr]."""

    def __init__(self, message: str, t: float) -> None:
        super().__init__(message)
        self.t = t


@dataclass(frozen=True)
class Sample:
    """
    The state at one time.

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
    omega: FloatArray
    quaternion: FloatArray
    euler: FloatArray
    matrix: FloatArray
    inertia: tuple[float, float, float]
    orbit_rate: float

    @property
    def jacobi(self) -> float:
        """Jacobi integral (``dynamics.jacobi_integral``), computed on demand."""
        return float(jacobi_integral(self.t, self.omega, self.matrix, self.inertia,
                                     self.orbit_rate))


class Propagator:
    """
    Advance a scenario's state in time, impacts included.

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

    def __init__(self, scenario: Scenario, *, split_impacts: bool = True,
                 fast: bool | None = None) -> None:
        self.scenario = scenario
        self._model = ATTITUDE_MODELS[scenario.attitude]
        self._method = INTEGRATORS[scenario.integrator.method]
        self._split = split_impacts
        if self._method.needs_problem and not split_impacts:
            raise ValueError('split_impacts=False is not available with method '
                             f'{self._method.name!r}: it needs a constant torque on each segment')
        why = why_no_fast_path(self._method, scenario.attitude)
        if not split_impacts:
            why = ('split_impacts=False (a time-switched right-hand side) runs on the reference '
                   'path')
        if fast and why:
            raise ValueError(f'fast path not available: {why}')
        self.fast = not why if fast is None else bool(fast)
        self._runner: _ReferenceRunner | _CompiledRunner = (
            _CompiledRunner(self._method) if self.fast else _ReferenceRunner(self._method,
                                                                             self._model))
        self._impacts: list[Impact] = []
        self._cuts = scenario.segment_cuts    # the encounter window's edges (a flyby)
        # (t0, t1, torque_body, torque_orbital) each: Segment's fields (segments.split_rows)
        self._segments: list[SegmentRow] = split_rows(0.0, scenario.duration, (), self._cuts)
        self.t = 0.0
        self.y = np.concatenate([scenario.omega0, self._model.from_euler(*scenario.euler0)])
        self.status = RUNNING
        self.message = ''
        self._nfev_done = 0
        self.n_steps = 0
        self._euler_track = np.array(scenario.euler0, dtype=float)
        self._track_at_t = self._euler_track.copy()  # continuous Euler angles at self.t
        self._quat_prev: FloatArray | None = None
        self._edge_state: dict[float, FloatArray] = {}  # state at impact edges reached so far
        self._edges: set[float] = set()   # every scheduled impact's start and end [yr]
        self._longest = 0.0                # the longest scheduled pulse [yr]
        # the impacts not reported ended yet: (end, order of scheduling, impact), a heap
        # (numbers only: tuples the garbage collector stops tracking; the impacts by order)
        self._unreported: list[tuple[float, int]] = []
        self._unreported_impacts: dict[int, Impact] = {}
        self._scheduled = 0                # impacts scheduled so far
        self._reported_cuts: set[float] = set()
        self._stepper: Stepper | None = None
        self.schedule_many(scenario.impacts)
        self._start_segment(self.t, self.y)

    # -- public API -----------------------------------------------------------------
    @property
    def t_end(self) -> float:
        """End of the scenario [yr]."""
        return self.scenario.duration

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""
        return self._nfev_done + self._current().nfev

    @property
    def impacts(self) -> tuple[Impact, ...]:
        """All impacts scheduled so far, in order of start time."""
        return tuple(self._impacts)

    @property
    def segments(self) -> tuple[Segment, ...]:
        """Return the integration segments of the whole run (:mod:`~.segments`) so far."""
        return tuple(Segment(*row) for row in self._segments)

    def schedule(self, impact: Impact) -> None:
        """Add an impact; its start must not lie before the current time ``t``."""
        self.schedule_many((impact,))

    def schedule_many(self, impacts: Sequence[Impact]) -> None:
        """
        Add impacts, as :meth:`schedule` one after the other would, in one pass.

        Their starts must not lie before the current time ``t`` (ScenarioError otherwise,
        nothing scheduled). The segments are re-split where the new pulses fall and nowhere
        else (:func:`~.segments.split_span`): scheduling n impacts costs O(n log n) plus the
        segments they overlap, not a re-split of the whole run per impact.
        """
        starts = [impact.start for impact in impacts]
        ends = [impact.end for impact in impacts]
        now, t_end = self.t, self.t_end
        for impact, start, end in zip(impacts, starts, ends):
            if start < now:
                raise ScenarioError(f'impact.start: must be >= the current time {now!r} yr, '
                                    f'got {impact.start!r}')
            if end > t_end:
                raise ScenarioError(f'impact: must end by the end of the scenario '
                                    f'({t_end!r} yr), ends at {impact.end!r}')
        if not impacts:
            return
        new = sorted(impacts, key=_START)   # stable: ties in the order given
        affects_segment = (self._stepper is not None
                           and new[0].start < self._stepper.t_bound)
        # (end, order of scheduling): a heap pops them in that total order whether
        # pushed one by one or heapified at once
        entries = [(end, self._scheduled + j) for j, end in enumerate(ends)]
        self._unreported_impacts.update(zip(range(self._scheduled, self._scheduled + len(ends)),
                                            impacts))
        self._scheduled += len(entries)
        if self._unreported:
            for entry in entries:
                heapq.heappush(self._unreported, entry)
        else:
            heapq.heapify(entries)
            self._unreported = entries
        self._edges.update(starts)
        self._edges.update(ends)
        self._longest = max(self._longest, max(impact.duration for impact in impacts))
        if len(new) > 1 and len(self._impacts) < len(new):
            # (the earlier ones first among equal starts, as bisect.insort puts them)
            self._impacts = sorted(self._impacts + new, key=_START)
            if self._split:   # (split_at_impacts of impacts already in its order)
                self._segments = split_rows(0.0, self.t_end, self._impacts, self._cuts)
        else:
            for impact in new:
                bisect.insort(self._impacts, impact, key=_START)
                if self._split:
                    self._resplit(impact.start, impact.end)
        if affects_segment or not self._split:
            # Restart from the last state handed out: the running segment's right-hand
            # side or end no longer holds. The Euler-angle track goes back with it (the
            # stepper may have run many steps past self.t in a call cut by its work budget).
            self._euler_track = self._track_at_t.copy()
            self._start_segment(self.t, self.y)

    def _resplit(self, start: float, end: float) -> None:
        """Split again the segments [start, end] [yr] overlaps (a pulse just scheduled)."""
        segments = self._segments
        i0 = max(0, bisect.bisect_right(segments, start, key=_SEGMENT_T0) - 1)
        i1 = bisect.bisect_left(segments, end, key=_SEGMENT_T1)
        a, b = segments[i0][0], segments[min(i1, len(segments) - 1)][1]
        # the impacts that may overlap [a, b]: those starting in [a - 2 longest pulses, b)
        # (twice the longest: an end is start + duration rounded)
        lo = bisect.bisect_left(self._impacts, a - 2.0 * self._longest, key=_START)
        hi = bisect.bisect_left(self._impacts, b, key=_START)
        overlapping = [i for i in self._impacts[lo:hi] if i.end > a]
        segments[i0:i1 + 1] = split_rows(a, b, overlapping, self._cuts)

    def advance_to(self, t: float) -> FloatArray:
        """
        Integrate to time ``t`` [yr] (not before the current time) and return the state.

        Raises IntegrationError when the integration fails; ``status`` is then
        ``"failed"`` and stays so. The work is done in bounded compiled calls
        (:data:`FAST_WORK_BUDGET`), so a KeyboardInterrupt is served in between.
        """
        if self.status == FAILED:
            raise IntegrationError(self.message, self.t)
        if not self.t <= t <= self.t_end:
            raise ValueError(f't = {t!r} must lie in [{self.t!r}, {self.t_end!r}] yr')
        while not self._advance_until(t, self._default_budget())[1]:
            pass
        y = self._current().state_at(t)
        euler = self._continuous_euler(y[3:])
        if euler is None or not finite_norm(y):
            # dense output inside a step whose end points are finite but whose state ran away
            self.status, self.message = FAILED, _interpolated_nonfinite_message(t)
            raise IntegrationError(self.message, self.t)
        self.y, self.t, self._track_at_t = y, t, euler
        return self.y

    def sample_many(self, times: npt.ArrayLike, *,
                    budget: float | None = None) -> tuple[int, dict[str, FloatArray], str]:
        """
        Sample (as :meth:`sample`) every time of the sorted sequence ``times``, into arrays.

        The work per call is bounded.

        Returns ``(n_done, arrays, message)``: ``arrays`` has ``omega`` (n, 3), ``euler``
        (n, 3), ``quaternion`` (n, 4) and ``matrix`` (n, 3, 3), of which the first ``n_done``
        rows are valid. Three outcomes:

        * ``n_done == n``, ``message == ""``: done.
        * ``n_done < n``, ``message == ""``: *partial progress, not a failure*: the call spent
          its work budget. Call again with the times not yet sampled (``times[n_done:]``, or
          any sorted times from ``times[n_done]`` on); the results are the same as with one
          uninterrupted call, bit for bit.
        * ``n_done < n``, ``message != ""``: the integration failed; ``message`` says why,
          ``status`` is ``"failed"`` and every later call returns ``(0, arrays, message)``.

        ``budget``: the work of this call in units of one integration step or one dense
        evaluation of the Euler-angle tracking (and at most as many samples); ``None`` is
        :data:`FAST_WORK_BUDGET` on the fast path, :data:`REFERENCE_WORK_BUDGET` on the
        reference path; ``math.inf`` runs to the end (or the failure) in such bounded chunks,
        never partial (what :func:`~.simulate.simulate` does). On the fast path the grid is
        sampled inside the compiled loop.
        """
        times = np.ascontiguousarray(times, dtype=float)
        n = times.size
        if n and self.status != FAILED and not self.t <= times[0]:
            raise ValueError(f't = {times[0]!r} must lie in [{self.t!r}, {self.t_end!r}] yr')
        if n and times[-1] > self.t_end:
            raise ValueError(f't = {times[-1]!r} must lie in [{self.t!r}, {self.t_end!r}] yr')
        arrays = {'omega': np.empty((n, 3)), 'euler': np.empty((n, 3)),
                  'quaternion': np.empty((n, 4)), 'matrix': np.empty((n, 3, 3))}
        y_out = self._runner.output_buffer(n)
        chunk = self._default_budget() if budget is None or budget == math.inf else budget
        if not chunk >= 1:
            raise ValueError(f'budget: must be >= 1 (or None, or math.inf), got {budget!r}')
        k, message = 0, ''
        while True:
            k, message = self._sample_into(times, arrays, y_out, k, chunk)
            if message or k == n or budget != math.inf:
                return k, arrays, message

    def _default_budget(self) -> int:
        return self._runner.work_budget

    def _sample_into(self, times: FloatArray, arrays: dict[str, FloatArray],
                     y_out: FloatArray | None, k0: int, budget: float) -> tuple[int, str]:
        """
        Sample times[k0:] into rows k0... of ``arrays``.

        At most ~``budget`` units of work (and samples); returns (next row, failure message or
        "").
        """
        k_stop = min(times.size, k0 + int(min(budget, times.size)))
        if y_out is None:
            return self._sample_stepwise(times, arrays, k0, k_stop, budget)
        return self._sample_compiled(times, arrays, y_out, k0, k_stop, budget)

    def pop_completed_impacts(self) -> list[tuple[Impact, FloatArray, FloatArray]]:
        """
        Impacts that ended by the current time and were not returned before.

        Each entry is (impact, state at its start, state at its end); the measured change
        of w [rad/yr, body axes] is ``end[:3] - start[:3]``.
        """
        done, waiting = [], []
        while self._unreported and self._unreported[0][0] <= self.t:
            entry = heapq.heappop(self._unreported)
            impact = self._unreported_impacts.pop(entry[1])
            y_end = self._edge_state.get(impact.end)
            if y_end is None and self.t == impact.end:
                y_end = self.y.copy()  # the segment after the pulse has not started yet
            if y_end is not None and impact.start in self._edge_state:
                done.append((impact.start, entry[1], impact, self._edge_state[impact.start],
                             y_end))
            elif impact.end == self.t:
                waiting.append(entry)   # its edge states may still come (else: never will)
                self._unreported_impacts[entry[1]] = impact
        for entry in waiting:
            heapq.heappush(self._unreported, entry)
        # in the order of the impacts (by start, ties in their order of scheduling)
        return [(impact, y_start, y_end) for *_, impact, y_start, y_end in sorted(
            done, key=lambda d: (d[0], d[1]))]

    def pop_window_edges(self) -> list[tuple[float, FloatArray]]:
        """
        Return the encounter window's edges reached and not returned before: (t, state).

        The simulator describes the state there (a new ``scenario`` segment), where the
        comparator's torque-free model stops or anchors again (:attr:`Scenario.encounter_window`).
        """
        done = []
        for t in self._cuts:
            if t in self._reported_cuts or t > self.t:
                continue
            y = self._edge_state.get(t)
            if y is None and self.t == t:
                y = self.y.copy()
            if y is not None:
                self._reported_cuts.add(t)
                done.append((t, y))
        return done

    def quaternion_of(self, y: FloatArray) -> FloatArray:
        """Return the unit quaternion (scalar first, body -> orbital) of a state vector."""
        if self._model.name == 'quaternion':
            attitude = y[3:]
            # np.linalg.norm's arithmetic (the square root of the dot product), without its
            # checks (~2 us; a segment start per impact): the same bits
            q: FloatArray = attitude / math.sqrt(attitude.dot(attitude))
            return q
        return np.asarray(matrix_to_quaternion(self._model.to_matrix(y[3:])), dtype=float)

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
            euler=self._track_at_t.copy(),  # (advance_to: self._continuous_euler(attitude))
            matrix=c,
            inertia=self.scenario.inertia,
            orbit_rate=self.scenario.orbit_rate,
        )

    # -- internals ------------------------------------------------------------------
    def _current(self) -> Stepper:
        """Return the stepper of the running segment (there is one from __init__ on)."""
        if self._stepper is None:
            raise RuntimeError('Propagator: no segment started')
        return self._stepper

    def _start_segment(self, t0: float, y0: FloatArray) -> None:
        if t0 in self._cuts or t0 in self._edges:
            self._edge_state[t0] = np.array(y0)
        k = bisect.bisect_right(self._segments, t0, key=_SEGMENT_T0) - 1
        segment = Segment(*self._segments[max(0, k)])
        if self._stepper is not None:
            self._nfev_done += self._stepper.nfev
        problem = self._free_problem
        if segment.torque_body is not NO_PULSE[0] or segment.torque_orbital is not NO_PULSE[1]:
            sc = self.scenario
            problem = SegmentProblem(sc.inertia, sc.orbit_rate, segment.torque_body,
                                     segment.torque_orbital, sc.attitude,
                                     *self._segment_constants)
        self._stepper = self._runner.new_stepper(
            segment, t0, y0, problem, self.scenario, None if self._split else self._switching_rhs,
            self._stepper)

    @functools.cached_property
    def _free_problem(self) -> SegmentProblem:
        """Return the problem of the segments without a pulse (one object for all of them)."""
        sc = self.scenario
        return SegmentProblem(sc.inertia, sc.orbit_rate, *NO_PULSE, sc.attitude,
                              *self._segment_constants)

    @functools.cached_property
    def _segment_constants(self) -> tuple[tuple[TorqueComponent, ...], tuple[float, float]]:
        """Return the scenario's (extra_torques, step_budget): the same for every segment."""
        return self.scenario.extra_torques, self.scenario.step_budget

    def _switching_rhs(self) -> Rhs:
        """Pulses as a time switch inside one smooth-looking RHS (demonstration only)."""
        sc, make = self.scenario, self._model.make_rhs
        free = make(sc.inertia, sc.orbit_rate, extra_torques=sc.extra_torques)
        pulses = [(i, make(sc.inertia, sc.orbit_rate,
                           *((i.torque, (0, 0, 0)) if i.frame == 'body'
                             else ((0, 0, 0), i.torque)), extra_torques=sc.extra_torques))
                  for i in self._impacts]

        def rhs(t: float, y: FloatArray) -> FloatArray:
            for impact, pulsed in pulses:
                if impact.start <= t < impact.end:
                    return pulsed(t, y)
            return free(t, y)

        return rhs

    def _advance_until(self, t: float, budget: float) -> tuple[int, bool]:
        """
        Step towards ``t`` with at most ~``budget`` units of work.

        Work: steps and tracking evaluations. Returns (work done, whether the stepper reached
        t). Raises IntegrationError.
        """
        if self.status == FAILED:
            raise IntegrationError(self.message, self.t)
        stepper = self._current()
        work = 0
        while t > stepper.t:
            if stepper.status != RUNNING:
                self._start_segment(stepper.t, stepper.y)   # (kept as copies: edge, stepper)
                stepper = self._current()
                continue
            if work >= budget:
                return work, False
            done = self._runner.advance(stepper, t, budget - work, self._euler_track)
            self.n_steps += done.steps
            if done.failure:
                self.status, self.message = FAILED, done.failure
                raise IntegrationError(done.failure, done.t_good)
            work += done.work
        return work, True

    def _continuous_euler(self, attitude: FloatArray) -> FloatArray | None:
        if self._model.name != 'quaternion':
            euler = np.array(attitude, dtype=float)
            return euler if np.all(np.isfinite(euler)) else None
        return unwrapped_towards(attitude, self._euler_track)

    def _sample_stepwise(self, times: FloatArray, arrays: dict[str, FloatArray], k0: int,
                         k_stop: int, budget: float) -> tuple[int, str]:
        """Sample times[k0:k_stop] one by one (the reference path; see :meth:`_sample_into`)."""
        omega, euler, quat, matrices = (arrays['omega'], arrays['euler'], arrays['quaternion'],
                                        arrays['matrix'])
        work = 0
        for k in range(k0, k_stop):
            t = float(times[k])
            try:
                used, reached = self._advance_until(t, budget - work)
                work += used
                if not reached:
                    return k, ''
                s = self.sample(t)
            except IntegrationError as err:
                return k, str(err) or 'integration failed'
            omega[k], euler[k], quat[k], matrices[k] = s.omega, s.euler, s.quaternion, s.matrix
        return k_stop, ''

    def _sample_compiled(self, times: FloatArray, arrays: dict[str, FloatArray],
                         y_out: FloatArray, k0: int, k_stop: int,
                         budget: float) -> tuple[int, str]:
        """Sample times[k0:k_stop] inside the compiled loop (see :meth:`_sample_into`)."""
        omega, euler, quat, matrices = (arrays['omega'], arrays['euler'], arrays['quaternion'],
                                        arrays['matrix'])
        work = 0
        if self.status == FAILED:
            return k0, self.message
        t_view = times[:k_stop]
        k, message = k0, ''
        while k < k_stop:
            stepper = self._current()
            if stepper.status != RUNNING and t_view[k] > stepper.t:
                self._start_segment(stepper.t, stepper.y)   # (kept as copies: edge, stepper)
                work += 1
                continue
            if work >= budget:
                break
            if not isinstance(stepper, CompiledStepper):
                raise TypeError('Propagator: the compiled sampling needs a compiled stepper')
            k, steps = stepper.advance(t_view[-1], self._euler_track, t_view, y_out, euler, k,
                                       budget - work)
            work += stepper.work
            self.n_steps += steps
            if stepper.status == FAILED:
                self.status, self.message = FAILED, stepper.message or 'integration failed'
                message = self.message
                break
        if k > k0:
            # the rule of advance_to: no sample with a non-finite state or Euler angles
            y = y_out[k0:k]
            norm2 = y[:, 0] * y[:, 0]
            for i in range(1, y.shape[1]):
                norm2 += y[:, i] * y[:, i]  # (summed in the order of kernels.checks.finite_norm)
            bad = np.flatnonzero(~(np.isfinite(norm2) & np.isfinite(euler[k0:k]).all(axis=1)))
            if bad.size:
                k = k0 + int(bad[0])
                self.status = FAILED
                self.message = _interpolated_nonfinite_message(float(times[k]))
                message = self.message
        if k > k0:
            y = y_out[k0:k]
            omega[k0:k] = y[:, :3]
            quat[k0:k] = continuous_quaternions(y[:, 3:], self._quat_prev)
            matrices[k0:k] = quaternions_to_matrices(y[:, 3:])
            self._quat_prev = quat[k - 1].copy()
            self.t, self.y = float(times[k - 1]), y_out[k - 1].copy()
            self._track_at_t = euler[k - 1].copy()
        return k, message


def unwrapped_towards(attitude: FloatArray, track: FloatArray) -> FloatArray | None:
    """
    Return phi, psi of a quaternion ``attitude`` unwrapped towards ``track`` [rad], and theta.

    The compiled loop's conversion (``kernels.tracking``); None if they are not finite (a
    state that ran away: ``kernels.tracking.set_track`` skips it the same way).
    """
    y = np.concatenate((_NO_OMEGA, attitude))
    phi, psi, theta = unwrapped_euler(y, 0, track)
    if not (math.isfinite(phi) and math.isfinite(psi) and math.isfinite(theta)):
        return None
    return np.array([phi, psi, theta])


class Advance(NamedTuple):
    """
    What one call of a strategy's ``advance`` did.

    ``work``: units of work spent; ``steps``: integration steps taken (counted even when the
    last one failed); ``failure``: why the integration failed ('' if it did not), ``t_good``
    the last good time [yr] then.
    """

    work: int
    steps: int
    failure: str = ''
    t_good: float = math.nan


class _ReferenceRunner:
    """The reference path: the method's own stepper, one step at a time, phi/psi in Python."""

    work_budget = REFERENCE_WORK_BUDGET

    def __init__(self, method: type[Stepper], model: AttitudeModel) -> None:
        self._method, self._model = method, model

    def output_buffer(self, n: int) -> None:
        """Return no buffer: samples come one at a time from :meth:`Propagator.sample`."""
        return None

    def new_stepper(self, segment: Segment, t0: float, y0: FloatArray, problem: SegmentProblem,
                    scenario: Scenario, switching: Callable[[], Rhs] | None,
                    previous: Stepper | None = None) -> Stepper:
        """
        Return the method's stepper for ``segment``, from ``t0``, ``y0``.

        ``switching``: None (the segment's own smooth right-hand side), or what builds the
        time-switched one of ``split_impacts=False``. ``previous`` (the last segment's
        stepper) is not used: a new one is built.
        """
        rhs = (self._model.make_rhs(scenario.inertia, scenario.orbit_rate, segment.torque_body,
                                    segment.torque_orbital, problem.extra_torques)
               if switching is None else switching())
        return self._method(rhs, t0, y0, segment.t1, scenario.integrator, problem=problem)

    def advance(self, stepper: Stepper, t: float, budget: float, track: FloatArray) -> Advance:
        """Take one step, following the Euler angles in ``track`` (updated in place)."""
        t_before = stepper.t
        stepper.step()
        message = stepper.message
        if stepper.status != FAILED and self._model.singular(stepper.y[3:]):
            message = (f'attitude singular at t = {stepper.t:.10g} yr '
                       f'(theta = {stepper.y[5]:.3g} rad): the '
                       "Euler-angle equations divide by sin(theta); use attitude 'quaternion'")
        if stepper.status == FAILED or message:
            return Advance(0, 1, message, t_before)
        if self._model.name == 'quaternion':
            return Advance(1 + self._track_euler(stepper, track), 1)
        return Advance(1, 1)

    def _track_euler(self, stepper: Stepper, track: FloatArray) -> int:
        """
        Follow phi, psi continuously through the step just taken (quaternion mode).

        ``track`` is updated in place. Returns the dense evaluations it took.
        """
        y, t_old = stepper.y, stepper.t_old
        if t_old is None:
            return 0  # (no step taken yet: nothing to follow)
        # the compiled loop's bound and subdivision (kernels.tracking)
        h = stepper.t - t_old
        n = track_pieces(track_rate(*y.tolist()) * h)
        for j in range(1, n + 1):
            tj = stepper.t if j == n else t_old + h * j / n
            att = y[3:] if j == n else stepper.state_at(tj)[3:]
            euler = unwrapped_towards(att, track)
            if euler is not None:
                track[:] = euler
        return int(n) - 1


class _CompiledRunner:
    """The fast path: the method's compiled loop, many steps and samples per call."""

    work_budget = FAST_WORK_BUDGET

    def __init__(self, method: type[Stepper]) -> None:
        self._method = method

    def output_buffer(self, n: int) -> FloatArray:
        """Return the (n, 7) array the compiled loop writes the sampled states into."""
        return np.empty((n, 7))

    def new_stepper(self, segment: Segment, t0: float, y0: FloatArray, problem: SegmentProblem,
                    scenario: Scenario, switching: Callable[[], Rhs] | None,
                    previous: Stepper | None = None) -> Stepper:
        """
        Return a compiled stepper of the method for ``segment``, from ``t0``, ``y0``.

        ``previous``: the last segment's stepper, restarted on this segment when it is a
        compiled stepper of the same body (:meth:`CompiledStepper.restart`: the same stepper a
        new one would be, without building its arrays again); else a new one.
        """
        if (isinstance(previous, CompiledStepper) and previous.method is self._method
                and previous.settings is scenario.integrator and previous.is_same_body(problem)):
            previous.restart_same_body(t0, y0, segment.t1, problem)
            return previous
        # no right-hand side: the compiled loop evaluates its own (problem)
        return CompiledStepper(self._method, None,  # type: ignore[arg-type]
                               t0, y0, segment.t1, scenario.integrator, problem=problem)

    def advance(self, stepper: Stepper, t: float, budget: float, track: FloatArray) -> Advance:
        """Run the compiled loop towards ``t`` within ``budget``; ``track`` updated in place."""
        if not isinstance(stepper, CompiledStepper):
            raise TypeError('Propagator: the compiled path needs a compiled stepper')
        _, steps = stepper.advance(t, track, budget=budget)
        if stepper.status == FAILED:
            return Advance(stepper.work, steps, stepper.message or 'integration failed',
                           stepper.t)
        return Advance(stepper.work, steps)

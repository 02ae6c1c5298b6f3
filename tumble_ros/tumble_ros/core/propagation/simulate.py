"""The researcher's entry point: ``simulate(scenario, t_eval)`` without ROS."""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np
import numpy.typing as npt

from tumble_ros.core.model.dynamics import jacobi_integral
from tumble_ros.core.model.scenario import Scenario, ScenarioError
from tumble_ros.core.propagation.propagator import Propagator

__all__ = ['sample_times', 'simulate', 'SimulationResult']

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SimulationResult:
    """
    Samples of one run at the requested times (n of them).

    Attributes
    ----------
    t : (n,) times [yr].
    omega : (n, 3) angular velocity [rad/yr], body axes.
    euler : (n, 3) the paper's (phi, psi, theta) [rad]; phi, psi continuous (unwrapped).
    quaternion : (n, 4) unit quaternion, scalar first, body -> orbital frame.
    jacobi : (n,) Jacobi integral (constant between impacts).
    success : bool
        False if the integration failed; the arrays then stop at the last good sample
        before the failure (never NaN).
    message : str
        Why it failed, empty on success.
    nfev, n_steps : right-hand-side evaluations and integration steps.

    """

    t: np.ndarray
    omega: np.ndarray
    euler: np.ndarray
    quaternion: np.ndarray
    jacobi: np.ndarray
    success: bool
    message: str
    nfev: int
    n_steps: int


def sample_times(scenario: Scenario, t_eval: npt.ArrayLike | None = None) -> FloatArray:
    """
    Return the sample times [yr] of a run: ``t_eval`` checked, or the scenario's output grid.

    ``t_eval`` must be a non-empty, finite, sorted 1-D sequence inside [0, duration]
    (ScenarioError naming ``t_eval`` otherwise); None gives ``scenario.output_times``.
    """
    if t_eval is None:
        return np.asarray(scenario.output_times, dtype=float)
    duration = scenario.duration
    t = np.asarray(t_eval, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ScenarioError(
            f't_eval: must be a non-empty 1-D sequence of times, got shape {t.shape}')
    if not np.all(np.isfinite(t)):
        raise ScenarioError('t_eval: must be finite')
    if np.any(np.diff(t) < 0):
        raise ScenarioError('t_eval: must be sorted in increasing order')
    if t[0] < 0.0 or t[-1] > duration:
        raise ScenarioError(
            f't_eval: must lie in [0, duration = {duration!r}] yr, got [{t[0]!r}, {t[-1]!r}]')
    return t


def simulate(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
             split_impacts: bool = True,
             fast: bool | None = None) -> SimulationResult:
    """
    Integrate ``scenario`` and sample it at exactly the times ``t_eval`` [yr].

    ``t_eval`` defaults to ``scenario.output_times`` (every ``output_interval`` from 0 to
    ``duration``). ``split_impacts=False`` is a demonstration switch only (see
    :class:`~.propagator.Propagator`). ``fast`` chooses the compiled loop (default: when
    available; ``False``: the reference step-by-step path; same results).

    Raises ScenarioError for invalid ``t_eval``; a numerical failure is reported in the
    result (``success=False``, ``message``), not raised.
    """
    times = sample_times(scenario, t_eval)
    prop = Propagator(scenario, split_impacts=split_impacts, fast=fast)
    n = times.size
    # to the end, in bounded calls
    done, arrays, message = prop.sample_many(times, budget=math.inf)
    t_out = times[:done]
    omega, matrices = arrays['omega'][:done], arrays['matrix'][:done]
    jacobi = jacobi_integral(t_out, omega, matrices, scenario.inertia, scenario.orbit_rate)
    return SimulationResult(
        t=t_out,
        omega=omega,
        euler=arrays['euler'][:done],
        quaternion=arrays['quaternion'][:done],
        jacobi=np.asarray(jacobi).reshape(-1),
        success=done == n,
        message=message,
        nfev=prop.nfev,
        n_steps=prop.n_steps,
    )

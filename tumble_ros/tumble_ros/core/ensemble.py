r"""
Ensembles: one asteroid, N bodies integrated at once (the paper's conclusion).

Each body is the scenario with its own impact sequence and/or initial state, e.g. one
asteroid under N random impact sequences::

    from tumble_ros.core import load_scenario, random_impacts, simulate_ensemble
    from tumble_ros.cli.progress import ProgressBar
    sc = load_scenario("tumble_ros/config/fig9.yaml").replace(duration=20.0, output_interval=1.0)
    hits = random_impacts(1000, sc.duration, rate=0.5, torque=1e6, pulse=3e-7, seed=1)
    res = simulate_ensemble(sc, impacts=hits, progress=ProgressBar(sc.duration, 1000))
    res.omega.shape        # (1000, 21, 3)

Body k of the ensemble is exactly ``ensemble_scenarios(...)[k]``, and its samples are those
of ``simulate(that scenario, t_eval)`` (same method, same steps: tests/test_core_ensemble.py).

How: every body's segments (split at its own impact edges) and integration state are packed
into arrays, and compiled calls (``kernels.ensemble_advance``, a loop over a block of bodies
that releases the GIL, one block per thread, as many threads as cores) advance all of them
to the next progress checkpoint, sampling the output grid on the way.
Methods with a compiled loop (rk4, dop853, splitting*) and the quaternion attitude take this
path when numba is available; otherwise the bodies are run one after the other with
:func:`~.simulate.simulate` (same results, slower).

The command line (progress on stderr, a summary on stdout) is :mod:`tumble_ros.cli.ensemble`.
"""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
import math
import os
import time
from typing import Callable

import numpy as np

from . import kernels as K
from .dynamics import ATTITUDE_MODELS, jacobi_integral
from .integrators import INTEGRATORS
from .integrators.compiled import failure_message, why_no_fast_path
from .rotation import continuous_quaternions, quaternions_to_matrices
from .scenario import Impact, MAX_OMEGA, MAX_ROTATION, Scenario, ScenarioError
from .segments import split_at_impacts
from .simulate import _check_times, simulate
from .torques import extra_torque_arrays

__all__ = ['EnsembleResult', 'simulate_ensemble', 'ensemble_scenarios', 'random_impacts']


@dataclass(frozen=True)
class EnsembleResult:
    """
    Samples of N bodies at the same n times.

    Attributes
    ----------
    t : (n,) times [yr].
    omega : (N, n, 3) angular velocity [rad/yr], body axes.
    euler : (N, n, 3) the paper's (phi, psi, theta) [rad], phi and psi continuous.
    quaternion : (N, n, 4) unit quaternion, scalar first, body -> orbital.
    jacobi : (N, n) Jacobi integral (constant between impacts).
    success : (N,) bool; a failed body's rows after its last good sample are NaN.
    messages : N strings, why each failed body failed (empty on success).
    n_steps, nfev : (N,) integration steps and right-hand-side (torque) evaluations.
    wall_time : seconds spent integrating (set-up and post-processing excluded).
    compiled : whether the compiled ensemble loop ran (else one simulate() per body).

    """

    t: np.ndarray
    omega: np.ndarray
    euler: np.ndarray
    quaternion: np.ndarray
    jacobi: np.ndarray
    success: np.ndarray
    messages: tuple[str, ...]
    n_steps: np.ndarray
    nfev: np.ndarray
    wall_time: float
    compiled: bool

    @property
    def n_bodies(self) -> int:
        return int(self.success.size)

    @property
    def body_steps_per_second(self) -> float:
        """Integration steps of all bodies per wall-clock second."""
        return float(self.n_steps.sum()) / self.wall_time if self.wall_time > 0 else math.inf


# ---------------------------------------------------------------------------------------
# Inputs
# ---------------------------------------------------------------------------------------
def _bodies(scenario, impacts, omega0, euler0, n_bodies):
    sizes = {name: len(v) for name, v in (('impacts', impacts), ('omega0', omega0),
                                          ('euler0', euler0))
             if v is not None}
    if n_bodies is not None:
        sizes['n_bodies'] = int(n_bodies)
    if not sizes:
        raise ScenarioError(
            'ensemble: give impacts, omega0, euler0 (one entry per body) or n_bodies')
    if len(set(sizes.values())) != 1:
        raise ScenarioError(f'ensemble: inconsistent numbers of bodies {sizes}')
    n = next(iter(sizes.values()))
    if n < 1:
        raise ScenarioError('ensemble: needs at least one body')
    if omega0 is not None:
        omega0 = np.asarray(omega0, dtype=float)
        if omega0.shape != (n, 3) or not np.all(np.isfinite(omega0)):
            raise ScenarioError(f'omega0: must be a finite (N, 3) array, got shape {omega0.shape}')
        # the bounds of Scenario (every body of the reference path is one), checked here for the
        # compiled path too
        fastest = float(np.max(np.linalg.norm(omega0, axis=1)))
        if fastest > MAX_OMEGA:
            raise ScenarioError(
                f'omega0: |omega0| = {fastest:.3g} rad/yr exceeds {MAX_OMEGA:g} rad/yr')
        if fastest * scenario.duration > MAX_ROTATION:
            raise ScenarioError(f'duration: a body turns by |omega0| * duration = '
                                f'{fastest * scenario.duration:.3g} rad, above '
                                f'{MAX_ROTATION:.0e} rad')
    if euler0 is not None:
        euler0 = np.asarray(euler0, dtype=float)
        if euler0.shape != (n, 3) or not np.all(np.isfinite(euler0)):
            raise ScenarioError(f'euler0: must be a finite (N, 3) array, got shape {euler0.shape}')
    if impacts is not None:
        impacts = [tuple(body) for body in impacts]
        for b, body in enumerate(impacts):
            for k, impact in enumerate(body):
                if not isinstance(impact, Impact):
                    raise ScenarioError(f'impacts[{b}][{k}]: must be an Impact, got {impact!r}')
                if impact.end > scenario.duration:
                    raise ScenarioError(f'impacts[{b}][{k}].start: the pulse must end by the end '
                                        f'of the run ({scenario.duration:g} yr); it ends at '
                                        f'{impact.end!r}')
    return n, impacts, omega0, euler0


def ensemble_scenarios(scenario: Scenario, *, impacts=None, omega0=None, euler0=None,
                       n_bodies: int | None = None) -> list[Scenario]:
    """
    Return the N single-body scenarios an ensemble integrates (body k = element k).

    ``impacts[k]`` (a sequence of :class:`Impact`) replaces the scenario's impacts for body k;
    ``omega0[k]`` and ``euler0[k]`` replace its initial state. Fields not given are the
    scenario's. Every body is validated as a :class:`Scenario`.
    """
    n, impacts, omega0, euler0 = _bodies(scenario, impacts, omega0, euler0, n_bodies)
    out = []
    for b in range(n):
        changes = {}
        if impacts is not None:
            changes['impacts'] = impacts[b]
        if omega0 is not None:
            changes['omega0'] = tuple(omega0[b])
        if euler0 is not None:
            changes['euler0'] = tuple(euler0[b])
        out.append(scenario.replace(**changes) if changes else scenario)
    return out


def random_impacts(n_bodies: int, duration: float, *, rate: float, torque: float,
                   pulse: float = 3e-7, frame: str = 'body',
                   seed=None) -> list[tuple[Impact, ...]]:
    """
    Draw N independent random impact sequences.

    Poisson arrivals at ``rate`` per year on [0, duration - pulse], each a pulse of length
    ``pulse`` [yr] and magnitude ``torque`` [I rad/yr^2] in an isotropic random direction,
    fixed in ``frame``.
    """
    if rate < 0 or not math.isfinite(rate):
        raise ScenarioError(f'rate: must be a finite number >= 0, got {rate!r}')
    if not 0 < pulse < duration:
        raise ScenarioError(f'pulse: must lie in (0, duration = {duration!r}), got {pulse!r}')
    rng = np.random.default_rng(seed)
    span = duration - pulse
    counts = rng.poisson(rate * span, size=n_bodies)
    out = []
    for count in counts:
        starts = np.sort(rng.uniform(0.0, span, size=count))
        directions = rng.normal(size=(count, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        out.append(tuple(Impact(float(s), pulse, tuple(float(v) for v in torque * d), frame)
                         for s, d in zip(starts, directions)))
    return out


# ---------------------------------------------------------------------------------------
# The ensemble
# ---------------------------------------------------------------------------------------
def simulate_ensemble(scenario: Scenario, t_eval=None, *, impacts=None, omega0=None, euler0=None,
                      n_bodies: int | None = None, fast: bool | None = None,
                      progress: Callable[[float, float, int], None] | None = None,
                      checkpoints: int | None = None,
                      threads: int | None = None) -> EnsembleResult:
    """
    Integrate N bodies of one scenario at once and sample them at the times ``t_eval``.

    Parameters
    ----------
    scenario
        The common scenario (body, orbit, integrator, duration, output grid).
    t_eval
        Output times [yr] (default ``scenario.output_times``).
    impacts, omega0, euler0, n_bodies
        Per-body inputs (see :func:`ensemble_scenarios`); N is their common length
        (``n_bodies`` alone: N identical bodies).
    fast
        Compiled ensemble loop: None = when available, True = required (ValueError saying
        why not), False = one reference :func:`simulate` per body.
    progress
        A callable ``progress(fraction, t, body_steps)``, called after each of ``checkpoints``
        chunks (a display on stderr: :class:`tumble_ros.cli.progress.ProgressBar`).
    checkpoints
        Number of chunks of the time span, each one compiled call (default: 100 with
        progress, else 1; every chunk costs a little per body, and the steps taken do not
        depend on it).
    threads
        Threads running blocks of bodies at once (default: the number of cores; the results
        do not depend on it).

    """
    times = scenario.output_times if t_eval is None else _check_times(t_eval, scenario.duration)
    n, impacts, omega0, euler0 = _bodies(scenario, impacts, omega0, euler0, n_bodies)
    method = INTEGRATORS[scenario.integrator.method]
    why = why_no_fast_path(method, scenario.attitude)
    if fast and why:
        raise ValueError(f'compiled ensemble not available: {why}')
    use_fast = not why if fast is None else bool(fast)
    if use_fast:
        if checkpoints is None:
            checkpoints = 1 if progress is None else 100
        threads = (os.cpu_count() or 1) if threads is None else max(1, int(threads))
        return _ensemble_compiled(scenario, times, n, impacts, omega0, euler0, method, progress,
                                  max(1, int(checkpoints)), threads)
    return _ensemble_reference(scenario, times, n, impacts, omega0, euler0, progress)


def _ensemble_reference(scenario, times, n, impacts, omega0, euler0, progress) -> EnsembleResult:
    per_body = any(v is not None for v in (impacts, omega0, euler0))
    bodies = ensemble_scenarios(scenario, impacts=impacts, omega0=omega0, euler0=euler0,
                                n_bodies=None if per_body else n)
    m = times.size
    omega, euler = np.full((n, m, 3), np.nan), np.full((n, m, 3), np.nan)
    quat, jac = np.full((n, m, 4), np.nan), np.full((n, m), np.nan)
    success, n_steps, nfev, messages = (np.zeros(n, bool), np.zeros(n, np.int64),
                                        np.zeros(n, np.int64), [])
    start = time.perf_counter()
    for b, body in enumerate(bodies):
        r = simulate(body, times, fast=False)
        k = r.t.size
        omega[b, :k], euler[b, :k], quat[b, :k], jac[b, :k] = (r.omega, r.euler, r.quaternion,
                                                               r.jacobi)
        success[b], n_steps[b], nfev[b] = r.success, r.n_steps, r.nfev
        messages.append(r.message)
        if progress is not None:
            progress((b + 1) / n, float(times[-1]), int(n_steps.sum()))
    wall = time.perf_counter() - start
    return EnsembleResult(times, omega, euler, quat, jac, success, tuple(messages), n_steps, nfev,
                          wall, False)


def _ensemble_compiled(scenario, times, n, impacts, omega0, euler0, method, progress, checkpoints,
                       threads):
    settings = scenario.integrator
    gammas = method.composition() if hasattr(method, 'composition') else ()
    cfg = K.config_array(method.kernel, settings, gammas, method.order or 0)
    # segment tables
    if impacts is None:
        per_body = [split_at_impacts(scenario.duration, scenario.impacts,
                                     scenario.segment_cuts)] * n
    else:
        per_body = [split_at_impacts(scenario.duration, body, scenario.segment_cuts)
                    for body in impacts]
    seg_ptr = np.zeros(n + 1, dtype=np.int64)
    seg_ptr[1:] = np.cumsum([len(s) for s in per_body])
    total = int(seg_ptr[-1])
    seg_t = np.empty((total, 2))
    torques = np.zeros((total, 6))
    j = 0
    for segs in per_body:
        for t0, t1, body, orbital in segs:
            seg_t[j] = t0, t1
            torques[j, :3], torques[j, 3:] = body, orbital
            j += 1
    probs = K.problem_arrays(scenario.inertia, scenario.orbit_rate, torques)
    extra = extra_torque_arrays(scenario.extra_torques)
    # initial states
    model = ATTITUDE_MODELS[scenario.attitude]
    states = np.zeros((n, K.ST.SIZE))
    states[:, K.ST.Y:K.ST.Y + 3] = scenario.omega0 if omega0 is None else omega0
    if euler0 is None:
        states[:, K.ST.Y + 3:K.ST.Y + 7] = model.from_euler(*scenario.euler0)
        tracks = np.tile(np.array(scenario.euler0, dtype=float), (n, 1))
    else:
        states[:, K.ST.Y + 3:K.ST.Y + 7] = [model.from_euler(*e) for e in euler0]
        tracks = np.array(euler0, dtype=float)
    m = times.size
    times = np.ascontiguousarray(times, dtype=float)
    y_out = np.full((n, m, K.N), np.nan)
    e_out = np.full((n, m, 3), np.nan)
    k_out = np.zeros(n, dtype=np.int64)
    steps = np.zeros(n, dtype=np.int64)
    cur = seg_ptr[:-1].copy()

    # blocks of bodies: a few per thread, so that uneven bodies (impacts) balance out
    threads = min(threads, n)
    n_blocks = 1 if threads == 1 else min(n, 4 * threads)
    edges = np.linspace(0, n, n_blocks + 1).astype(np.int64)
    blocks = list(zip(edges[:-1].tolist(), edges[1:].tolist()))

    start = time.perf_counter()
    with ThreadPoolExecutor(threads) if threads > 1 else _NoPool() as pool:
        list(pool.map(lambda blk: K.ensemble_init(extra, cfg, probs, seg_t, seg_ptr, states, *blk),
                      blocks))
        t_end = float(times[-1])
        stops = [t_end * (c + 1) / checkpoints for c in range(checkpoints - 1)] + [t_end]
        for c, t_stop in enumerate(stops):
            list(pool.map(lambda blk: K.ensemble_advance(extra, cfg, probs, seg_t, seg_ptr, cur,
                                                         states, tracks, t_stop, times, y_out,
                                                         e_out, k_out, steps, *blk),
                          blocks))
            if progress is not None:
                progress((c + 1) / len(stops), t_stop, int(steps.sum()))
    wall = time.perf_counter() - start

    failed = states[:, K.ST.STATUS] == K.STATUS.FAILED
    success = (k_out == m) & ~failed
    messages = tuple(failure_message(states[b], method.name) if failed[b] else ''
                     for b in range(n))
    nfev = (states[:, K.ST.NFEV_DONE] + states[:, K.ST.NFEV]).astype(np.int64)
    omega = y_out[:, :, :3].copy()
    quat = np.full((n, m, 4), np.nan)
    jac = np.full((n, m), np.nan)
    for b0 in range(0, n, 1024):  # bounded memory for the (chunk, n, 3, 3) matrices
        b1 = min(n, b0 + 1024)
        for kk in np.unique(k_out[b0:b1]):
            rows = np.arange(b0, b1)[k_out[b0:b1] == kk]
            if kk == 0:
                continue
            q = y_out[rows, :kk, 3:]
            quat[rows, :kk] = continuous_quaternions(q)
            c = quaternions_to_matrices(q)
            jac[rows, :kk] = jacobi_integral(times[:kk], omega[rows, :kk], c, scenario.inertia,
                                             scenario.orbit_rate)
    return EnsembleResult(times, omega, e_out, quat, jac, success, messages, steps, nfev, wall,
                          True)


class _NoPool:
    """``ThreadPoolExecutor`` stand-in that runs in the calling thread."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    @staticmethod
    def map(fn, items):  # noqa: A003 (the name of the Executor method it stands in for)
        return map(fn, items)

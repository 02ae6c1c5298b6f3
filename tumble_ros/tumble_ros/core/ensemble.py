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
from dataclasses import dataclass, replace
import math
import os
import time
from typing import Callable, Iterator

import numpy as np

from . import kernels as K
from .dynamics import ATTITUDE_MODELS, jacobi_integral
from .integrators import INTEGRATORS
from .integrators.compiled import failure_message, why_no_fast_path
from .limits import step_budget
from .rotation import continuous_quaternions, quaternions_to_matrices
from .scenario import Impact, IMPACT_FRAMES, MAX_OMEGA, MAX_ROTATION, Scenario, ScenarioError
from .segments import split_at_impacts
from .simulate import _check_times, simulate
from .torques import extra_torque_arrays

__all__ = ['EnsembleResult', 'simulate_ensemble', 'ensemble_scenarios', 'random_impacts',
           'RandomImpacts', 'GaussianSpread', 'body_rng', 'concatenate_results', 'ChunkResult',
           'chunk_ranges', 'default_chunk_size', 'iter_chunks', 'prepare_inputs', 'run_chunk']


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
def _resolve(scenario, impacts, omega0, euler0, n_bodies, first_body):
    """Draw the per-body inputs given as samplers (bodies first_body ... of the ensemble)."""
    samplers = [v for v in (impacts, omega0, euler0) if _is_sampler(v)]
    if isinstance(first_body, bool) or not isinstance(first_body, (int, np.integer)) \
            or first_body < 0:
        raise ScenarioError(f'first_body: must be an integer >= 0, got {first_body!r}')
    if not samplers:
        return impacts, omega0, euler0
    if n_bodies is None:
        raise ScenarioError('n_bodies: needed with RandomImpacts or GaussianSpread inputs '
                            '(they draw one entry per body)')
    n = int(n_bodies)
    if isinstance(impacts, RandomImpacts):
        impacts = impacts.draw(first_body, n, scenario.duration)
    if isinstance(omega0, GaussianSpread):
        omega0 = omega0.draw(first_body, n, stream=OMEGA0_STREAM)
    if isinstance(euler0, GaussianSpread):
        euler0 = euler0.draw(first_body, n, stream=EULER0_STREAM)
    return impacts, omega0, euler0


def _bodies(scenario, impacts, omega0, euler0, n_bodies, first_body=0):
    impacts, omega0, euler0 = _resolve(scenario, impacts, omega0, euler0, n_bodies, first_body)
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
                       n_bodies: int | None = None, first_body: int = 0) -> list[Scenario]:
    """
    Return the N single-body scenarios an ensemble integrates (body k = element k).

    ``impacts[k]`` (a sequence of :class:`Impact`) replaces the scenario's impacts for body k;
    ``omega0[k]`` and ``euler0[k]`` replace its initial state. Fields not given are the
    scenario's. Every body is validated as a :class:`Scenario`. ``impacts`` may also be a
    :class:`RandomImpacts` and ``omega0``/``euler0`` a :class:`GaussianSpread` (then
    ``n_bodies`` is needed): element k is then body ``first_body + k`` of that draw.
    """
    n, impacts, omega0, euler0 = _bodies(scenario, impacts, omega0, euler0, n_bodies,
                                         first_body)
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
        out.append(_sequence(starts, directions, torque, pulse, frame))
    return out


def _sequence(starts, directions, torque, pulse, frame) -> tuple[Impact, ...]:
    """Return the impacts of one body: sorted ``starts`` [yr], unit ``directions`` (k, 3)."""
    return tuple(Impact(float(s), pulse, tuple(float(v) for v in torque * d), frame)
                 for s, d in zip(starts, directions))


#: The random streams of one body (see :func:`body_rng`): each per-body input draws from its own.
IMPACTS_STREAM, OMEGA0_STREAM, EULER0_STREAM = 0, 1, 2


def body_rng(seed: int, body: int, stream: int) -> np.random.Generator:
    """
    Return the random generator of body ``body`` for one input ``stream`` of a run's ``seed``.

    It depends on (seed, stream, body) only: not on the number of bodies, nor on how they are
    split into chunks, processes or machines. It is NumPy's
    ``SeedSequence(seed).spawn(...)[stream].spawn(...)[body]``, i.e.
    ``SeedSequence(seed, spawn_key=(stream, body))``: statistically independent streams.
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed),
                                                        spawn_key=(int(stream), int(body))))


def _check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ScenarioError(f'seed: must be an integer >= 0, got {seed!r}')
    return int(seed)


@dataclass(frozen=True)
class RandomImpacts:
    """
    Random impact sequences drawn body by body: body b's from (seed, b) alone.

    Poisson arrivals at ``rate`` per year on [0, duration - pulse], each a pulse of ``pulse``
    [yr] and magnitude ``torque`` [I rad/yr^2] in an isotropic random direction fixed in
    ``frame`` (the law of :func:`random_impacts`, whose one stream depends on N). Being a
    small description, it travels to the workers of a distributed run, which draw their own
    bodies: the ensemble gives the same impacts whatever its chunking.
    """

    rate: float
    torque: float
    pulse: float = 3e-7
    frame: str = 'body'
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ('rate', 'torque', 'pulse'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
                    or not math.isfinite(value) or value < 0:
                raise ScenarioError(f'{name}: must be a finite number >= 0, got {value!r}')
            object.__setattr__(self, name, float(value))
        if self.pulse <= 0:
            raise ScenarioError(f'pulse: must be > 0, got {self.pulse!r}')
        if self.frame not in IMPACT_FRAMES:
            raise ScenarioError(f'frame: must be one of {IMPACT_FRAMES}, got {self.frame!r}')
        object.__setattr__(self, 'seed', _check_seed(self.seed))

    def body(self, b: int, duration: float) -> tuple[Impact, ...]:
        """Return the impacts of body ``b`` in a run of ``duration`` [yr]."""
        if not 0 < self.pulse < duration:
            raise ScenarioError(f'pulse: must lie in (0, duration = {duration!r}), '
                                f'got {self.pulse!r}')
        rng = body_rng(self.seed, b, IMPACTS_STREAM)
        span = duration - self.pulse
        count = rng.poisson(self.rate * span)
        starts = np.sort(rng.uniform(0.0, span, size=count))
        directions = rng.normal(size=(count, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        return _sequence(starts, directions, self.torque, self.pulse, self.frame)

    def draw(self, first: int, count: int, duration: float) -> list[tuple[Impact, ...]]:
        """Return the impacts of bodies ``first`` ... ``first + count - 1``."""
        return [self.body(b, duration) for b in range(first, first + count)]


@dataclass(frozen=True)
class GaussianSpread:
    """
    Per-body vectors ``center + sigma * N(0, 1)`` (omega0 [rad/yr] or euler0 [rad]).

    Body b's vector is drawn from (seed, stream, b) alone (:func:`body_rng`; the stream is the
    input's: omega0 and euler0 given the same seed are still independent). ``sigma`` is one
    standard deviation or one per component.
    """

    center: tuple[float, float, float]
    sigma: float | tuple[float, float, float]
    seed: int = 0

    def __post_init__(self) -> None:
        center = np.asarray(self.center, dtype=float)
        sigma = np.broadcast_to(np.asarray(self.sigma, dtype=float), (3,)) \
            if np.ndim(self.sigma) in (0, 1) and np.size(self.sigma) in (1, 3) else None
        if center.shape != (3,) or not np.all(np.isfinite(center)):
            raise ScenarioError(f'center: must be 3 finite numbers, got {self.center!r}')
        if sigma is None or not np.all(np.isfinite(sigma)) or np.any(sigma < 0):
            raise ScenarioError(f'sigma: must be one or 3 finite numbers >= 0, '
                                f'got {self.sigma!r}')
        object.__setattr__(self, 'center', tuple(float(v) for v in center))
        object.__setattr__(self, 'sigma', tuple(float(v) for v in sigma))
        object.__setattr__(self, 'seed', _check_seed(self.seed))

    def draw(self, first: int, count: int, stream: int) -> np.ndarray:
        """Return the (count, 3) vectors of bodies ``first`` ... ``first + count - 1``."""
        out = np.empty((count, 3))
        center, sigma = np.array(self.center), np.array(self.sigma)
        for k in range(count):
            out[k] = center + sigma * body_rng(self.seed, first + k, stream).normal(size=3)
        return out


# ---------------------------------------------------------------------------------------
# The ensemble
# ---------------------------------------------------------------------------------------
def simulate_ensemble(scenario: Scenario, t_eval=None, *, impacts=None, omega0=None, euler0=None,
                      n_bodies: int | None = None, fast: bool | None = None,
                      progress: Callable[[float, float, int], None] | None = None,
                      checkpoints: int | None = None,
                      threads: int | None = None, first_body: int = 0,
                      client=None, chunk_size: int | None = None) -> EnsembleResult:
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
        (``n_bodies`` alone: N identical bodies). ``impacts`` may be a :class:`RandomImpacts`
        and ``omega0`` [rad/yr, body axes] / ``euler0`` [rad] a :class:`GaussianSpread`, drawn
        body by body (then ``n_bodies`` is needed).
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
    first_body
        Index in the whole ensemble of this call's first body: the samplers draw bodies
        ``first_body``, ``first_body + 1``, ... (how a chunk of a bigger run draws its own).
    client
        A Dask ``distributed.Client``: the bodies are split into chunks of ``chunk_size``,
        each integrated by this function in a task on the cluster's workers (one thread per
        task), and gathered here; ``wall_time`` is then the wall-clock time of the whole
        distributed run. The same results, bit for bit, as without it (:func:`iter_chunks`,
        :mod:`tumble_ros.core.ensemble_dask`; results bigger than memory go to a store
        instead: ``tumble_ros.ensembles.run_ensemble_to_store``).
    chunk_size
        Bodies per task with a ``client`` (default: :func:`default_chunk_size`).

    """
    if client is not None:
        return _simulate_on_client(client, scenario, t_eval, impacts=impacts, omega0=omega0,
                                   euler0=euler0, n_bodies=n_bodies, fast=fast,
                                   chunk_size=chunk_size, progress=progress)
    times = scenario.output_times if t_eval is None else _check_times(t_eval, scenario.duration)
    n, impacts, omega0, euler0 = _bodies(scenario, impacts, omega0, euler0, n_bodies, first_body)
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
    # the work budget at the fastest body's rate (limits.step_budget; adaptive methods only)
    spin = 0.0 if omega0 is None else float(
        np.max(np.linalg.norm(np.atleast_2d(omega0), axis=-1)))
    budget = (step_budget(scenario.output_interval, max(scenario.own_rate, spin),
                          settings.max_step) if method.adaptive else (math.inf, math.inf))
    cfg = K.config_array(method.kernel, settings, gammas, method.order or 0, budget)
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


# ---------------------------------------------------------------------------------------
# Chunks: the unit of work of big and distributed runs
# ---------------------------------------------------------------------------------------
#: Largest default chunk [bodies]; and the output a default chunk holds at most [bytes].
MAX_CHUNK_BODIES = 10_000
CHUNK_BYTES = 64 * 2**20
#: Bytes of output per body and sample in a task (omega, euler, quaternion, jacobi and the
#: loop's own (n, K.N) state samples), for the default chunk size.
_BYTES_PER_SAMPLE = (3 + 3 + 4 + 1 + 7) * 8


@dataclass(frozen=True)
class ChunkResult:
    """
    Bodies ``start`` ... ``stop - 1`` of an ensemble, integrated in one task.

    Attributes
    ----------
    index : the chunk's number (chunk i holds bodies [i * chunk_size, ...)).
    start, stop : its bodies, half-open.
    result : their :class:`EnsembleResult` (row k = body start + k).
    omega0 : (n, 3) their initial angular velocity [rad/yr], body axes (as drawn).
    euler0 : (n, 3) their initial Euler angles (phi, psi, theta) [rad] (as drawn).
    n_impacts : (n,) number of impacts of each.

    """

    index: int
    start: int
    stop: int
    result: EnsembleResult
    omega0: np.ndarray
    euler0: np.ndarray
    n_impacts: np.ndarray


def _is_sampler(value) -> bool:
    return isinstance(value, (RandomImpacts, GaussianSpread))


def chunk_ranges(n_bodies: int, chunk_size: int) -> list[tuple[int, int]]:
    """Return the (start, stop) bodies of each chunk: chunk i is [i * size, (i + 1) * size)."""
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or chunk_size < 1:
        raise ScenarioError(f'chunk_size: must be an integer >= 1, got {chunk_size!r}')
    return [(a, min(n_bodies, a + int(chunk_size))) for a in range(0, n_bodies, int(chunk_size))]


def default_chunk_size(n_bodies: int, n_samples: int, workers: int = 1) -> int:
    """
    Return the bodies per task used when none is given.

    At most :data:`MAX_CHUNK_BODIES`, at most :data:`CHUNK_BYTES` of output per task (so a
    task's memory does not depend on N), and small enough for 4 chunks per worker when N allows
    it (so that uneven chunks balance out).
    """
    by_memory = max(1, CHUNK_BYTES // (max(1, n_samples) * _BYTES_PER_SAMPLE))
    by_balance = max(1, math.ceil(n_bodies / (4 * max(1, workers))))
    return int(min(MAX_CHUNK_BODIES, by_memory, by_balance))


def prepare_inputs(scenario: Scenario, impacts, omega0, euler0,
                   n_bodies: int | None) -> tuple[int, dict]:
    """
    Validate an ensemble's inputs once (the driver of a chunked run); return N and the inputs.

    The inputs come back as a dict (``impacts``, ``omega0``, ``euler0``): explicit ones
    validated and converted (arrays, tuples of :class:`Impact`), samplers as given.
    """
    if n_bodies is None and any(_is_sampler(v) for v in (impacts, omega0, euler0)):
        raise ScenarioError('n_bodies: needed with RandomImpacts or GaussianSpread inputs '
                            '(they draw one entry per body)')
    explicit = [None if _is_sampler(v) else v for v in (impacts, omega0, euler0)]
    n, e_impacts, e_omega0, e_euler0 = _bodies(scenario, *explicit, n_bodies)
    inputs = {'impacts': impacts if _is_sampler(impacts) else e_impacts,
              'omega0': omega0 if _is_sampler(omega0) else e_omega0,
              'euler0': euler0 if _is_sampler(euler0) else e_euler0}
    return n, inputs


def _chunk_inputs(inputs: dict, start: int, stop: int) -> dict:
    """Samplers travel whole (the task draws its own bodies); explicit inputs are sliced."""
    return {k: v if v is None or _is_sampler(v) else v[start:stop] for k, v in inputs.items()}


def run_chunk(scenario: Scenario, t_eval, inputs: dict, index: int, start: int, stop: int,
              fast: bool | None = None, threads: int | None = 1) -> ChunkResult:
    """
    Integrate bodies ``start`` ... ``stop - 1`` of an ensemble: the task of a chunk.

    ``inputs`` holds ``impacts``, ``omega0`` and ``euler0``, each None, the chunk's slice of
    an explicit per-body input, or a sampler (drawn here for bodies start ... stop - 1).
    """
    n = stop - start
    impacts, omega0, euler0 = _resolve(scenario, inputs.get('impacts'), inputs.get('omega0'),
                                       inputs.get('euler0'), n, start)
    result = simulate_ensemble(scenario, t_eval, impacts=impacts, omega0=omega0,
                               euler0=euler0, n_bodies=n, fast=fast, threads=threads)
    omega0 = np.tile(scenario.omega0, (n, 1)) if omega0 is None else np.asarray(omega0, float)
    euler0 = np.tile(scenario.euler0, (n, 1)) if euler0 is None else np.asarray(euler0, float)
    n_impacts = (np.full(n, len(scenario.impacts), dtype=np.int32) if impacts is None
                 else np.array([len(b) for b in impacts], dtype=np.int32))
    return ChunkResult(index, start, stop, result, omega0, euler0, n_impacts)


def iter_chunks(scenario: Scenario, t_eval=None, *, impacts=None, omega0=None, euler0=None,
                n_bodies: int | None = None, chunk_size: int | None = None, client=None,
                fast: bool | None = None, skip=frozenset(), threads: int | None = None,
                max_in_flight: int | None = None) -> Iterator[ChunkResult]:
    """
    Yield the results of the ensemble's chunks as they finish (in any order).

    Inputs as :func:`~.ensemble.simulate_ensemble`. ``client``: a Dask ``distributed.Client``
    (None: the chunks run here one after the other, each on ``threads`` threads, default all
    cores). Chunks whose index is in ``skip`` are not run. With a client at most
    ``max_in_flight`` tasks (default: twice the cluster's threads, plus 2) are submitted at
    once, so neither the workers nor this process hold more than that many chunks' results.
    Closing the iterator early (an exception, Ctrl-C) cancels the tasks not finished.
    With a client, a task that raises anything but a ScenarioError raises
    :class:`~.ensemble_dask.EnsembleRunError` here.
    """
    times = scenario.output_times if t_eval is None else _check_times(t_eval, scenario.duration)
    n, inputs = prepare_inputs(scenario, impacts, omega0, euler0, n_bodies)
    workers = 1 if client is None else max(1, len(client.nthreads()))
    size = default_chunk_size(n, times.size, workers) if chunk_size is None else chunk_size
    todo = [(i, a, b) for i, (a, b) in enumerate(chunk_ranges(n, size)) if i not in skip]
    if client is None:
        for i, a, b in todo:
            yield run_chunk(scenario, times, _chunk_inputs(inputs, a, b), i, a, b, fast,
                            threads)
        return
    from .ensemble_dask import map_as_completed

    yield from map_as_completed(client, run_chunk,
                                [(scenario, times, _chunk_inputs(inputs, a, b), i, a, b, fast, 1)
                                 for i, a, b in todo],
                                names=[f'chunk-{i}' for i, _, _ in todo],
                                max_in_flight=max_in_flight)


def _simulate_on_client(client, scenario: Scenario, t_eval=None, *, impacts=None,
                        omega0=None, euler0=None, n_bodies: int | None = None,
                        fast: bool | None = None, chunk_size: int | None = None,
                        progress: Callable[[float, float, int], None] | None = None
                        ) -> EnsembleResult:
    """
    Return :func:`~.ensemble.simulate_ensemble` (same arguments) run as chunks on ``client``.

    ``progress(fraction of bodies done, t_end [yr], body-steps so far)`` is called as each
    chunk finishes; ``wall_time`` is the wall-clock time of the whole run.
    """
    start = time.perf_counter()
    explicit = [v for v in (impacts, omega0, euler0) if v is not None and not _is_sampler(v)]
    total = n_bodies if n_bodies is not None else len(explicit[0]) if explicit else 1
    parts, done, steps = {}, 0, 0
    for chunk in iter_chunks(scenario, t_eval, impacts=impacts, omega0=omega0, euler0=euler0,
                             n_bodies=n_bodies, chunk_size=chunk_size, client=client,
                             fast=fast):
        parts[chunk.index] = chunk.result
        done += chunk.stop - chunk.start
        steps += int(chunk.result.n_steps.sum())
        if progress is not None:
            progress(done / total, float(chunk.result.t[-1]), steps)
    result = concatenate_results(parts[i] for i in sorted(parts))
    return replace(result, wall_time=time.perf_counter() - start)


def concatenate_results(parts) -> EnsembleResult:
    """
    Join the results of consecutive groups of bodies (same times) into one, in the given order.

    ``wall_time`` is the sum of the parts' (the caller may replace it with
    ``dataclasses.replace``); ``compiled`` holds if it holds for every part.
    """
    parts = list(parts)
    if not parts:
        raise ValueError('concatenate_results: no parts')
    t = parts[0].t
    if any(p.t.shape != t.shape or np.any(p.t != t) for p in parts):
        raise ValueError('concatenate_results: the parts have different sample times')

    def cat(name):
        return np.concatenate([getattr(p, name) for p in parts])

    return EnsembleResult(t, cat('omega'), cat('euler'), cat('quaternion'), cat('jacobi'),
                          cat('success'), tuple(m for p in parts for m in p.messages),
                          cat('n_steps'), cat('nfev'), float(sum(p.wall_time for p in parts)),
                          all(p.compiled for p in parts))


class _NoPool:
    """``ThreadPoolExecutor`` stand-in that runs in the calling thread."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    @staticmethod
    def map(fn, items):  # noqa: A003 (the name of the Executor method it stands in for)
        return map(fn, items)

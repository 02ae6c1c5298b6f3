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

Bigger runs are cut into chunks of bodies (:func:`plan_chunks`, :func:`run_chunk`: the unit of
work, the same numbers whatever the chunking); where the chunks run (this process, a Dask
cluster) and where their results go (memory, a store) is the run layer's,
:mod:`tumble_ros.runs.ensembles`. The command line (progress on stderr, a summary on stdout) is
:mod:`tumble_ros.cli.ensemble`.
"""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
import contextlib
import dataclasses
from dataclasses import dataclass, replace
import math
import os
import threading
import time
from typing import (Any, Callable, Collection, Iterable, Iterator, Literal, Sequence,
                    TypeAlias)

import numpy as np
import numpy.typing as npt

from tumble_ros.core import kernels as K
from tumble_ros.core.compiling.jit import first_use, load_for
from tumble_ros.core.integrators import INTEGRATORS
from tumble_ros.core.integrators.base import Stepper
from tumble_ros.core.integrators.compiled import failure_message, why_no_fast_path
from tumble_ros.core.kernels import samples
from tumble_ros.core.model.dynamics import ATTITUDE_MODELS
from tumble_ros.core.model.limits import MAX_OMEGA, MAX_ROTATION, step_budget
from tumble_ros.core.model.scenario import Impact, IMPACT_FRAMES, Scenario, ScenarioError
from tumble_ros.core.propagation.segments import split_at_impacts
from tumble_ros.core.propagation.simulate import sample_times, simulate
from tumble_ros.core.torques import extra_torque_arrays, tidal_potential_coefficient

__all__ = ['EnsembleResult', 'simulate_ensemble', 'ensemble_scenarios', 'random_impacts',
           'RandomImpacts', 'GaussianSpread', 'body_rng', 'concatenate_results', 'ChunkResult',
           'chunk_ranges', 'default_chunk_size', 'iter_chunks', 'prepare_inputs', 'run_chunk',
           'ChunkTask', 'ChunkPlan', 'plan_chunks', 'Progress']

FloatArray: TypeAlias = npt.NDArray[np.float64]
#: Per-body impacts: a sampler, or one sequence of :class:`Impact` per body.
ImpactsInput: TypeAlias = 'RandomImpacts | Sequence[Sequence[Impact]] | None'
#: Per-body vectors (omega0 [rad/yr], euler0 [rad]): a sampler, or an (N, 3) array.
VectorsInput: TypeAlias = 'GaussianSpread | npt.ArrayLike | None'
#: ``progress(fraction done, t [yr], body-steps so far)``.
Progress: TypeAlias = Callable[[float, float, int], None]
#: An ensemble's inputs (``impacts``, ``omega0``, ``euler0``) once checked: None, a sampler, or
#: the explicit per-body values (tuples of Impact, (N, 3) arrays).
Inputs: TypeAlias = dict[str, Any]


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
    wall_time : seconds spent integrating (set-up, numba's first load or compilation of the
        loops and post-processing excluded).
    compiled : whether the compiled ensemble loop ran (else one simulate() per body).
    euler_angles : whether the run followed the Euler angles (``simulate_ensemble``'s
        ``euler_angles``); False: ``euler`` is a read-only view of one NaN, left out when the
        result is pickled (a Dask task's result) and joined without memory.

    """

    t: FloatArray
    omega: FloatArray
    euler: FloatArray
    quaternion: FloatArray
    jacobi: FloatArray
    success: npt.NDArray[np.bool_]
    messages: tuple[str, ...]
    n_steps: npt.NDArray[np.int64]
    nfev: npt.NDArray[np.int64]
    wall_time: float
    compiled: bool
    euler_angles: bool = True

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle the result; without Euler angles, without its (N, n, 3) NaN ``euler``."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if not self.euler_angles:
            fields['euler'] = None
        return (_unpickled_result, (fields,))

    @property
    def n_bodies(self) -> int:
        """Return the number of bodies N."""
        return int(self.success.size)

    @property
    def body_steps_per_second(self) -> float:
        """Integration steps of all bodies per wall-clock second."""
        return float(self.n_steps.sum()) / self.wall_time if self.wall_time > 0 else math.inf


def _unpickled_result(fields: dict[str, Any]) -> EnsembleResult:
    """Return the :class:`EnsembleResult` of pickled ``fields`` (``euler`` None: NaN view)."""
    if fields['euler'] is None:
        fields['euler'] = _no_euler(fields['success'].size, fields['t'].size)
    return EnsembleResult(**fields)


# ---------------------------------------------------------------------------------------
# Inputs
# ---------------------------------------------------------------------------------------
def _resolve(scenario: Scenario, impacts: ImpactsInput, omega0: VectorsInput,
             euler0: VectorsInput, n_bodies: int | None, first_body: int
             ) -> tuple[Any, Any, Any]:
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
    n, first = int(n_bodies), int(first_body)
    if isinstance(impacts, RandomImpacts):
        impacts = impacts.draw(first, n, scenario.duration)
    if isinstance(omega0, GaussianSpread):
        omega0 = omega0.draw(first, n, stream=OMEGA0_STREAM)
    if isinstance(euler0, GaussianSpread):
        euler0 = euler0.draw(first, n, stream=EULER0_STREAM)
    return impacts, omega0, euler0


def _fastest_spin(omega: FloatArray) -> float:
    """
    Return max |omega| [rad/yr] over the rows of ``omega`` (N, 3): the bodies' fastest spin.

    By columns, x^2 + y^2 + z^2 in numpy's order (the bits of ``np.linalg.norm(omega,
    axis=1)``): numpy's reduction along a row of three took ~0.1 s at N = 10^6.
    """
    x, y, z = omega[:, 0], omega[:, 1], omega[:, 2]
    return float(np.sqrt(np.max(x * x + y * y + z * z)))


def _bodies(scenario: Scenario, impacts: ImpactsInput, omega0: VectorsInput,
            euler0: VectorsInput, n_bodies: int | None, first_body: int = 0
            ) -> tuple[int, list[tuple[Impact, ...]] | None, FloatArray | None,
                       FloatArray | None]:
    """Draw the samplers, check every per-body input; return N and the explicit inputs."""
    drawn_impacts, drawn_omega0, drawn_euler0 = _resolve(scenario, impacts, omega0, euler0,
                                                         n_bodies, first_body)
    sizes = {name: len(v) for name, v in (('impacts', drawn_impacts), ('omega0', drawn_omega0),
                                          ('euler0', drawn_euler0))
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
    omega: FloatArray | None = None
    euler: FloatArray | None = None
    bodies: list[tuple[Impact, ...]] | None = None
    if drawn_omega0 is not None:
        omega = np.asarray(drawn_omega0, dtype=float)
        if omega.shape != (n, 3) or not np.all(np.isfinite(omega)):
            raise ScenarioError(f'omega0: must be a finite (N, 3) array, got shape {omega.shape}')
        # the bounds of Scenario (every body of the reference path is one), checked here for the
        # compiled path too
        fastest = _fastest_spin(omega)
        if fastest > MAX_OMEGA:
            raise ScenarioError(
                f'omega0: |omega0| = {fastest:.3g} rad/yr exceeds {MAX_OMEGA:g} rad/yr')
        if fastest * scenario.duration > MAX_ROTATION:
            raise ScenarioError(f'duration: a body turns by |omega0| * duration = '
                                f'{fastest * scenario.duration:.3g} rad, above '
                                f'{MAX_ROTATION:.0e} rad')
    if drawn_euler0 is not None:
        euler = np.asarray(drawn_euler0, dtype=float)
        if euler.shape != (n, 3) or not np.all(np.isfinite(euler)):
            raise ScenarioError(f'euler0: must be a finite (N, 3) array, got shape {euler.shape}')
    if drawn_impacts is not None:
        bodies = [tuple(body) for body in drawn_impacts]
        for b, body in enumerate(bodies):
            for k, impact in enumerate(body):
                if not isinstance(impact, Impact):
                    raise ScenarioError(f'impacts[{b}][{k}]: must be an Impact, got {impact!r}')
                if impact.end > scenario.duration:
                    raise ScenarioError(f'impacts[{b}][{k}].start: the pulse must end by the end '
                                        f'of the run ({scenario.duration:g} yr); it ends at '
                                        f'{impact.end!r}')
    return n, bodies, omega, euler


def ensemble_scenarios(scenario: Scenario, *, impacts: ImpactsInput = None,
                       omega0: VectorsInput = None, euler0: VectorsInput = None,
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
        changes: dict[str, Any] = {}
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
                   seed: int | None = None) -> list[tuple[Impact, ...]]:
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


def _sequence(starts: FloatArray, directions: FloatArray, torque: float, pulse: float,
              frame: str) -> tuple[Impact, ...]:
    """Return the impacts of one body: sorted ``starts`` [yr], unit ``directions`` (k, 3)."""
    return tuple(Impact(float(s), pulse, (float(torque * d[0]), float(torque * d[1]),
                                          float(torque * d[2])), frame)
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


def _check_seed(seed: object) -> int:
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

    def draw(self, first: int, count: int, stream: int) -> FloatArray:
        """Return the (count, 3) vectors of bodies ``first`` ... ``first + count - 1``."""
        out = np.empty((count, 3))
        center, sigma = np.array(self.center), np.array(self.sigma)
        for k in range(count):
            out[k] = center + sigma * body_rng(self.seed, first + k, stream).normal(size=3)
        return out


# ---------------------------------------------------------------------------------------
# The ensemble
# ---------------------------------------------------------------------------------------
def simulate_ensemble(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
                      impacts: ImpactsInput = None, omega0: VectorsInput = None,
                      euler0: VectorsInput = None, n_bodies: int | None = None,
                      fast: bool | None = None, progress: Progress | None = None,
                      checkpoints: int | None = None,
                      threads: int | None = None, first_body: int = 0,
                      euler_angles: bool = True) -> EnsembleResult:
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
    euler_angles
        False: the compiled loops neither follow nor write out the continuous Euler angles
        (~30 % of a lockstep ``splitting`` body-step) and the result's ``euler`` is NaN (a
        read-only view of one NaN, no memory); every other output, the steps and the states
        are the same bits (``nfev`` counts no tracking evaluations).

    Notes
    -----
    The same ensemble as chunks on a Dask cluster, gathered here or written to a store (the
    same results, bit for bit): ``tumble_ros.ensembles.run_ensemble(..., client=...)`` and
    ``run_ensemble_to_store`` (:mod:`tumble_ros.runs.ensembles`).

    """
    times = sample_times(scenario, t_eval)
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
        run = next(runner for refusal, runner in ENSEMBLE_LOOPS.values()
                   if not refusal(scenario, impacts, method))
        with small_pages():
            return run(scenario, times, n, impacts, omega0, euler0, method, progress,
                       max(1, int(checkpoints)), threads, euler_angles=euler_angles)
    result = _ensemble_reference(scenario, times, n, impacts, omega0, euler0, progress)
    return result if euler_angles else replace(result, euler=_no_euler(n, times.size),
                                               euler_angles=False)


_PAGES_LOCK = threading.Lock()
_pages_users: list[Any] = [0, None]      # calls inside small_pages, numpy's setting before them


@contextlib.contextmanager
def small_pages() -> Iterator[None]:
    """
    Let numpy allocate its arrays without transparent huge pages inside the block.

    numpy advises the kernel to back every array of 4 MB or more with huge pages (``madvise``).
    Where the kernel then compacts memory at the first touch of each
    (``/sys/kernel/mm/transparent_hugepage/defrag`` = ``madvise``, this project's machine), a
    fresh process's N = 10^6 ensemble spent ~1.4 s more outside its loop (benchmarks/HISTORY.md,
    "The samples' post-processing compiled"). numpy's setting is the process's: it is switched
    off by the first of concurrent callers and restored by the last. The arrays and their
    values are the same either way; a no-op where numpy has no such switch.
    """
    multiarray = getattr(getattr(np, '_core', None), 'multiarray', None)
    toggle = getattr(multiarray, '_set_madvise_hugepage', None)
    if toggle is None:       # pragma: no cover - numpy without the switch
        yield
        return
    with _PAGES_LOCK:
        if _pages_users[0] == 0:
            _pages_users[1] = toggle(False)
        _pages_users[0] += 1
    try:
        yield
    finally:
        with _PAGES_LOCK:
            _pages_users[0] -= 1
            if _pages_users[0] == 0:
                toggle(_pages_users[1])


def _no_euler(n: int, m: int) -> FloatArray:
    """Return the ``euler`` of an ensemble run without Euler angles: (n, m, 3) NaN, no memory."""
    return np.broadcast_to(np.float64(np.nan), (n, m, 3))


def _ensemble_reference(scenario: Scenario, times: FloatArray, n: int,
                        impacts: list[tuple[Impact, ...]] | None, omega0: FloatArray | None,
                        euler0: FloatArray | None, progress: Progress | None
                        ) -> EnsembleResult:
    """Run the bodies one after the other with the reference :func:`simulate`."""
    per_body = any(v is not None for v in (impacts, omega0, euler0))
    bodies = ensemble_scenarios(scenario, impacts=impacts, omega0=omega0, euler0=euler0,
                                n_bodies=None if per_body else n)
    m = times.size
    omega, euler = np.full((n, m, 3), np.nan), np.full((n, m, 3), np.nan)
    quat, jac = np.full((n, m, 4), np.nan), np.full((n, m), np.nan)
    success, n_steps, nfev = np.zeros(n, bool), np.zeros(n, np.int64), np.zeros(n, np.int64)
    messages: list[str] = []
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


def _config(scenario: Scenario, omega0: FloatArray | None, method: type[Stepper],
            euler_angles: bool = True) -> FloatArray:
    """Return the config array (layout ``K.CF``) of the method, its work budget included."""
    settings = scenario.integrator
    gammas = method.composition() if hasattr(method, 'composition') else ()
    # the work budget at the fastest body's rate (limits.step_budget; adaptive methods only)
    spin = 0.0 if omega0 is None else _fastest_spin(np.atleast_2d(omega0))
    budget = (step_budget(scenario.output_interval, max(scenario.own_rate, spin),
                          settings.max_step) if method.adaptive else (math.inf, math.inf))
    if method.kernel is None:
        raise ValueError(f'method {method.name!r} has no compiled loop')
    return K.config_array(method.kernel, settings, gammas, method.order or 0, budget,
                          euler_angles)


def _segment_tables(scenario: Scenario, per_body: list[list[Any]]
                    ) -> tuple[FloatArray, FloatArray]:
    """Return (seg_t (S, 2) [yr], problems (S, K.PR.SIZE)) of the bodies' segments, in order."""
    total = sum(len(s) for s in per_body)
    seg_t = np.empty((total, 2))
    torques = np.zeros((total, 6))
    j = 0
    for segs in per_body:
        for t0, t1, body, orbital in segs:
            seg_t[j] = t0, t1
            torques[j, :3], torques[j, 3:] = body, orbital
            j += 1
    return seg_t, K.problem_arrays(scenario.inertia, scenario.orbit_rate, torques)


def _initial_states(scenario: Scenario, n: int, omega0: FloatArray | None,
                    euler0: FloatArray | None) -> tuple[FloatArray, FloatArray]:
    """Return y0 (n, 7) (omega [rad/yr], quaternion) and the Euler tracks (n, 3) [rad]."""
    model = ATTITUDE_MODELS[scenario.attitude]
    y0 = np.zeros((n, K.N))
    y0[:, :3] = scenario.omega0 if omega0 is None else omega0
    if euler0 is None:
        y0[:, 3:] = model.from_euler(*scenario.euler0)
        tracks = np.tile(np.array(scenario.euler0, dtype=float), (n, 1))
    else:
        y0[:, 3:] = [model.from_euler(*e) for e in euler0]
        tracks = np.array(euler0, dtype=float)
    return y0, tracks


def _ensemble_compiled(scenario: Scenario, times: FloatArray, n: int,
                       impacts: list[tuple[Impact, ...]] | None, omega0: FloatArray | None,
                       euler0: FloatArray | None, method: type[Stepper],
                       progress: Progress | None, checkpoints: int, threads: int, *,
                       euler_angles: bool = True, lanes: int = 0) -> EnsembleResult:
    """
    Run the bodies in blocks of the compiled ensemble loop, on ``threads`` threads.

    ``lanes`` > 0: the bodies share their segments (:func:`_lanes_refusal`) and each block is
    stepped by the lanes loop (:mod:`.kernels.lanes`), ``lanes`` bodies at a time; each body
    gets the same bits as in the per-body loop whatever the blocks.
    """
    cfg = _config(scenario, omega0, method, euler_angles)
    # segment tables
    if impacts is None:
        per_body = [split_at_impacts(scenario.duration, scenario.impacts,
                                     scenario.segment_cuts)] * n
    else:
        per_body = [split_at_impacts(scenario.duration, body, scenario.segment_cuts)
                    for body in impacts]
    seg_ptr = np.zeros(n + 1, dtype=np.int64)
    seg_ptr[1:] = np.cumsum([len(s) for s in per_body])
    seg_t, probs = _segment_tables(scenario, per_body)
    extra = extra_torque_arrays(scenario.extra_torques)
    # initial states
    y0, tracks = _initial_states(scenario, n, omega0, euler0)
    states = np.zeros((n, K.ST.SIZE))
    states[:, K.ST.Y:K.ST.Y + K.N] = y0
    m = times.size
    times = np.ascontiguousarray(times, dtype=float)
    y_out, e_out = _outputs(n, m, euler_angles)
    k_out = np.zeros(n, dtype=np.int64)
    steps = np.zeros(n, dtype=np.int64)
    cur = seg_ptr[:-1].copy()

    # blocks of bodies: a few per thread, so that uneven bodies (impacts) balance out
    threads = min(threads, n)
    n_blocks = 1 if threads == 1 else min(n, 4 * threads)
    edges = np.linspace(0, n, n_blocks + 1).astype(np.int64)
    blocks = list(zip(edges[:-1].tolist(), edges[1:].tolist()))

    kernel = K.kernel_name(cfg)
    lp = K.loops(kernel)
    t_end = float(times[-1])
    scratch: tuple[FloatArray, ...] = ()
    advance = lp.ensemble_advance
    if lanes:
        assert lp.lanes_advance is not None
        advance = lp.lanes_advance
        scratch = (np.empty((K.LN.SIZE, lanes)),)    # a call's own (threads)
    label = f'{kernel} {"lanes" if lanes else "ensemble"} loops'
    with first_use(advance, label):   # outside the timing
        load_for(lp.ensemble_init, extra, cfg, probs, seg_t, seg_ptr, states, *blocks[0])
        load_for(advance, extra, cfg, probs, seg_t, seg_ptr, cur, states, tracks,
                 t_end, times, y_out, e_out, k_out, steps, *blocks[0], *scratch)

    def run(blk: tuple[int, int], t_stop: float) -> None:
        own = tuple(np.empty_like(a) for a in scratch)
        advance(extra, cfg, probs, seg_t, seg_ptr, cur, states, tracks, t_stop, times, y_out,
                e_out, k_out, steps, *blk, *own)

    start = time.perf_counter()
    with ThreadPoolExecutor(threads) if threads > 1 else _NoPool() as pool:
        list(pool.map(lambda blk: lp.ensemble_init(extra, cfg, probs, seg_t, seg_ptr, states,
                                                   *blk), blocks))
        stops = [t_end * (c + 1) / checkpoints for c in range(checkpoints - 1)] + [t_end]
        for c, t_stop in enumerate(stops):
            list(pool.map(lambda blk: run(blk, t_stop), blocks))
            if progress is not None:
                progress((c + 1) / len(stops), t_stop, int(steps.sum()))
    wall = time.perf_counter() - start

    failed = states[:, K.ST.STATUS] == K.STATUS.FAILED
    messages = tuple(failure_message(states[b], method.name) if failed[b] else ''
                     for b in range(n))
    nfev = (states[:, K.ST.NFEV_DONE] + states[:, K.ST.NFEV]).astype(np.int64)
    return _result(scenario, times, y_out, e_out, k_out, failed, messages, steps, nfev, wall,
                   threads)


def _outputs(n: int, m: int, euler_angles: bool = True) -> tuple[FloatArray, FloatArray]:
    """
    Return the loops' outputs y_out (n, m, K.N) and e_out (n, m, 3), not initialised.

    The loops write every sample a body reaches; :func:`_result` blanks the others (NaN). Not
    filled first: at N = 10^6 filling them took seconds of page faults on one thread, which the
    loops' threads now take as they write. Without Euler angles e_out holds no sample.
    """
    return np.empty((n, m, K.N)), np.empty((n, m if euler_angles else 0, 3))


def _result(scenario: Scenario, times: FloatArray, y_out: FloatArray, e_out: FloatArray,
            k_out: npt.NDArray[np.int64], failed: npt.NDArray[np.bool_],
            messages: tuple[str, ...], steps: npt.NDArray[np.int64],
            nfev: npt.NDArray[np.int64], wall: float, threads: int = 1) -> EnsembleResult:
    """
    Post-process the loops' samples (quaternions made continuous, Jacobi integral).

    One compiled pass over each body's samples (``kernels.samples.ensemble_samples``: the bits
    of ``rotation.continuous_quaternions`` and ``dynamics.jacobi_integral``, which a single
    body's :func:`simulate` calls), in groups of :data:`POST_SAMPLES` samples on ``threads``
    threads; each body's numbers do not depend on the groups. The samples a body did not reach
    are NaN. The result's omega and quaternion are views of ``y_out`` (its columns 0-2 and
    3-6, the quaternions made continuous in place): no copy of the biggest output.
    """
    n, m = y_out.shape[:2]
    euler_angles = e_out.shape[1] == m
    success = (k_out == m) & ~failed
    jac = np.empty((n, m))
    inertia = np.ascontiguousarray(scenario.inertia, dtype=float)
    rate = scenario.orbit_rate
    sun_x, sun_y = np.sin(rate * times), np.cos(rate * times)   # (jacobi_integral's)
    size = max(1, POST_SAMPLES // max(1, m))
    k_out = np.ascontiguousarray(k_out, dtype=np.int64)

    def group(b0: int) -> None:
        samples.ensemble_samples(sun_x, sun_y, y_out, e_out, k_out, inertia, rate,
                                 tidal_potential_coefficient(rate), jac, b0, min(n, b0 + size))

    starts = range(0, n, size)
    with ThreadPoolExecutor(threads) if threads > 1 and len(starts) > 1 else _NoPool() as pool:
        list(pool.map(group, starts))
    return EnsembleResult(times, y_out[:, :, :3], e_out if euler_angles else _no_euler(n, m),
                          y_out[:, :, 3:], jac, success, messages, steps, nfev, wall, True,
                          euler_angles)


#: Most samples (bodies x times) post-processed at once by :func:`_result`.
POST_SAMPLES = 2**16


#: Bodies per block of the lockstep loop: its buffers, (2 K.BK.SIZE + K.BT.SIZE + K.BB.SIZE) x 8
#: bytes a body (936: 234 KB a block), stay in the core's L2 cache.
BLOCK_BODIES = 256


def _lockstep_refusal(scenario: Scenario, impacts: list[tuple[Impact, ...]] | None,
                      method: type[Stepper]) -> str:
    """Empty if the bodies can be stepped in lockstep (:mod:`.kernels.lockstep`), else why not."""
    if method.kernel is None or not K.has_lockstep(method.kernel):
        return f'method {method.name!r} has no lockstep loop'
    if scenario.impacts or (impacts is not None and any(impacts)):
        return ('impacts: the bodies do not share one time grid (a pulse segment takes '
                'steps that depend on the body)')
    return ''


def _ensemble_lockstep(scenario: Scenario, times: FloatArray, n: int,
                       impacts: list[tuple[Impact, ...]] | None, omega0: FloatArray | None,
                       euler0: FloatArray | None, method: type[Stepper],
                       progress: Progress | None, checkpoints: int, threads: int,
                       block: int | None = None, *, euler_angles: bool = True
                       ) -> EnsembleResult:
    """
    Run blocks of ``block`` bodies (default :data:`BLOCK_BODIES`) in lockstep, on ``threads``.

    The bodies share their segments (no impact: :func:`_lockstep_refusal`), so every block
    steps through one time grid; each body gets the bits of its own run whatever the blocks.
    """
    size = BLOCK_BODIES if block is None else int(block)
    cfg = _config(scenario, omega0, method, euler_angles)
    seg_t, probs = _segment_tables(
        scenario, [split_at_impacts(scenario.duration, (), scenario.segment_cuts)])
    extra = extra_torque_arrays(scenario.extra_torques)
    y0, tracks0 = _initial_states(scenario, n, omega0, euler0)
    n_blocks = -(-n // size)
    padded = n_blocks * size
    flat_tracks = np.zeros((padded, 3))
    flat_tracks[:n] = tracks0
    tracks = flat_tracks.reshape(n_blocks, size, 3)
    bodies = np.zeros((n_blocks, K.BB.SIZE, size))
    counters = np.zeros((n_blocks, K.LI.SIZE), dtype=np.int64)
    bst = np.zeros((n_blocks, K.ST.SIZE))
    m = times.size
    times = np.ascontiguousarray(times, dtype=float)
    y_out, e_out = _outputs(n, m, euler_angles)
    counts = [min(size, n - i * size) for i in range(n_blocks)]
    kernel = K.kernel_name(cfg)
    lp = K.loops(kernel)
    block_init, block_advance = lp.block_init, lp.block_advance
    assert block_init is not None and block_advance is not None

    def started(i: int) -> FloatArray:
        """Return block i's two state buffers (2, BK.SIZE, size), its first segment started."""
        soa = _block_buffers(y0, i * size, counts[i], size)
        block_init(extra, cfg, probs, seg_t, soa, bodies[i], counters[i], bst[i], counts[i])
        return soa

    def advance(soa: FloatArray, i: int, t_stop: float) -> None:
        tmp = np.empty((K.BT.SIZE, size))   # scratch of a step: a call's own, not a block's
        block_advance(extra, cfg, probs, seg_t, soa, tmp, bodies[i], counters[i], bst[i],
                      tracks[i], t_stop, times, y_out, e_out, i * size, counts[i])

    t_end = float(times[-1])
    with first_use(block_advance, f'{kernel} lockstep loops'):      # outside the timing
        soa0 = _block_buffers(y0, 0, counts[0], size)
        load_for(block_init, extra, cfg, probs, seg_t, soa0, bodies[0], counters[0], bst[0],
                 counts[0])
        load_for(block_advance, extra, cfg, probs, seg_t, soa0, np.empty((K.BT.SIZE, size)),
                 bodies[0], counters[0], bst[0], tracks[0], t_end, times, y_out, e_out, 0,
                 counts[0])
    start = time.perf_counter()
    threads = min(threads, n_blocks)
    with ThreadPoolExecutor(threads) if threads > 1 else _NoPool() as pool:
        stops = [t_end * (c + 1) / checkpoints for c in range(checkpoints - 1)] + [t_end]
        # one stop: a block's buffers live in its one task (~80 KB); several: they hold its
        # state between the stops, every block's kept (~320 bytes a body)
        buffers = (started if len(stops) == 1
                   else list(pool.map(started, range(n_blocks))).__getitem__)
        for c, t_stop in enumerate(stops):
            list(pool.map(lambda i: advance(buffers(i), i, t_stop), range(n_blocks)))
            if progress is not None:
                done = sum(_lockstep_steps(counters[i], bodies[i], counts[i]).sum()
                           for i in range(n_blocks))
                progress((c + 1) / len(stops), t_stop, int(done))
    wall = time.perf_counter() - start

    def row(r: int) -> FloatArray:   # row r of every body's BB column, body order
        return bodies[:, r, :].reshape(padded)[:n]

    failed = row(K.BB.FAILED) != 0.0
    every = np.repeat(np.arange(n_blocks), size)[:n]
    steps = np.where(failed, row(K.BB.STEPS), counters[every, K.LI.STEPS]).astype(np.int64)
    k_out = np.where(failed, row(K.BB.K), counters[every, K.LI.K]).astype(np.int64)
    nfev = np.where(failed, row(K.BB.NFEV),
                    bst[every, K.ST.NFEV_DONE] + bst[every, K.ST.NFEV]
                    + row(K.BB.NFEV_ADJ)).astype(np.int64)
    messages = tuple(_lockstep_message(bodies[b // size, :, b % size], bst[every[b]],
                                       method.name) if failed[b]
                     else '' for b in range(n)) if failed.any() else ('',) * n
    return _result(scenario, times, y_out, e_out, k_out, failed, messages, steps, nfev, wall,
                   threads)


def _block_buffers(y0: FloatArray, body0: int, count: int, size: int) -> FloatArray:
    """
    Return a lockstep block's two state buffers (2, BK.SIZE, size), its bodies' y0 in the first.

    Column i of buffer 0 holds body ``body0 + i``'s initial state (i < count); the padding
    columns (i >= count) copies of the first body's, never written out; everything else 0.
    """
    soa = np.zeros((2, K.BK.SIZE, size))
    soa[0, K.BK.Y:K.BK.Y + K.N, :count] = y0[body0:body0 + count].T
    soa[0, K.BK.Y:K.BK.Y + K.N, count:] = y0[0][:, None]
    return soa


def _lockstep_steps(counters: npt.NDArray[np.int64], bodies: FloatArray,
                    count: int) -> npt.NDArray[np.int64]:
    """Return the steps of a block's ``count`` bodies so far (a failed body's stop there)."""
    failed = bodies[K.BB.FAILED, :count] != 0.0
    return np.where(failed, bodies[K.BB.STEPS, :count], counters[K.LI.STEPS]).astype(np.int64)


def _lockstep_message(body: FloatArray, bst: FloatArray, method_name: str) -> str:
    """Return the message of a body that failed in a lockstep block (its row of ``K.BB``)."""
    st = bst.copy()
    st[K.ST.FAIL] = body[K.BB.FAIL]
    st[K.ST.FAIL_T] = body[K.BB.FAIL_T]
    st[K.ST.FAIL_DT] = body[K.BB.FAIL_DT]
    return failure_message(st, method_name)


#: Bodies a block of the lanes loop steps at once: its scratch, (K.LN.SIZE) x 8 bytes a
#: lane (1,128: 141 KB), stays in the core's L2 cache.
LANE_BODIES = 128


def _lanes_refusal(scenario: Scenario, impacts: list[tuple[Impact, ...]] | None,
                   method: type[Stepper]) -> str:
    """Empty if the bodies can be stepped as lanes (:mod:`.kernels.lanes`), else why not."""
    if method.kernel is None or not K.has_lanes(method.kernel):
        return f'method {method.name!r} has no lanes loop'
    if impacts is not None and any(impacts):     # (the scenario's own impacts: every body's)
        return 'impacts per body: the bodies do not share their segments'
    return ''


def _ensemble_lanes(*args: Any, **kwargs: Any) -> EnsembleResult:
    """Run the compiled ensemble with its blocks stepped as lanes (:func:`_ensemble_compiled`)."""
    return _ensemble_compiled(*args, **kwargs, lanes=LANE_BODIES)


#: The compiled ensemble loops, by name: (refusal, runner); the first whose refusal is empty
#: runs. ``lockstep`` steps blocks of bodies sharing one time grid together; ``lanes`` steps
#: blocks of bodies sharing their segments, each with its own steps (an adaptive method);
#: ``per-body`` steps each body through its own segments (impacts), the general case.
ENSEMBLE_LOOPS: dict[str, tuple[Callable[..., str], Callable[..., EnsembleResult]]] = {
    'lockstep': (_lockstep_refusal, _ensemble_lockstep),
    'lanes': (_lanes_refusal, _ensemble_lanes),
    'per-body': (lambda *args: '', _ensemble_compiled),
}


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


def _is_sampler(value: object) -> bool:
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


def prepare_inputs(scenario: Scenario, impacts: ImpactsInput, omega0: VectorsInput,
                   euler0: VectorsInput, n_bodies: int | None) -> tuple[int, Inputs]:
    """
    Validate an ensemble's inputs once (the driver of a chunked run); return N and the inputs.

    The inputs come back as a dict (``impacts``, ``omega0``, ``euler0``): explicit ones
    validated and converted (arrays, tuples of :class:`Impact`), samplers as given.
    """
    if n_bodies is None and any(_is_sampler(v) for v in (impacts, omega0, euler0)):
        raise ScenarioError('n_bodies: needed with RandomImpacts or GaussianSpread inputs '
                            '(they draw one entry per body)')
    n, e_impacts, e_omega0, e_euler0 = _bodies(
        scenario, None if _is_sampler(impacts) else impacts,
        None if _is_sampler(omega0) else omega0, None if _is_sampler(euler0) else euler0,
        n_bodies)
    inputs = {'impacts': impacts if _is_sampler(impacts) else e_impacts,
              'omega0': omega0 if _is_sampler(omega0) else e_omega0,
              'euler0': euler0 if _is_sampler(euler0) else e_euler0}
    return n, inputs


def _chunk_inputs(inputs: Inputs, start: int, stop: int) -> Inputs:
    """Samplers travel whole (the task draws its own bodies); explicit inputs are sliced."""
    return {k: v if v is None or _is_sampler(v) else v[start:stop] for k, v in inputs.items()}


@dataclass(frozen=True)
class ChunkTask:
    """
    One chunk to run: the arguments of :func:`run_chunk` besides the scenario and times.

    ``inputs``: the chunk's own (samplers whole, explicit per-body values sliced).
    """

    index: int
    start: int
    stop: int
    inputs: Inputs


@dataclass(frozen=True)
class ChunkPlan:
    """
    An ensemble cut into chunks: what every engine runs, whatever it runs on.

    Attributes
    ----------
    times : (n,) the sample times [yr], checked.
    n_bodies, chunk_size : N and the bodies per chunk (the last chunk may be shorter).
    inputs : the whole ensemble's checked inputs (:func:`prepare_inputs`).
    tasks : the chunks to run (those not skipped), in order of index.

    """

    times: FloatArray
    n_bodies: int
    chunk_size: int
    inputs: Inputs
    tasks: tuple[ChunkTask, ...]


def plan_chunks(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
                impacts: ImpactsInput = None, omega0: VectorsInput = None,
                euler0: VectorsInput = None, n_bodies: int | None = None,
                chunk_size: int | None = None, workers: int = 1,
                skip: Collection[int] = frozenset()) -> ChunkPlan:
    """
    Check an ensemble's inputs and cut its bodies into chunks; return the plan.

    Inputs as :func:`simulate_ensemble`. ``chunk_size`` None: :func:`default_chunk_size` for
    ``workers`` workers. Chunks whose index is in ``skip`` are left out of ``tasks``.
    """
    times = sample_times(scenario, t_eval)
    n, inputs = prepare_inputs(scenario, impacts, omega0, euler0, n_bodies)
    size = default_chunk_size(n, times.size, workers) if chunk_size is None else chunk_size
    tasks = tuple(ChunkTask(i, a, b, _chunk_inputs(inputs, a, b))
                  for i, (a, b) in enumerate(chunk_ranges(n, size)) if i not in skip)
    return ChunkPlan(times, n, int(size), inputs, tasks)


def run_chunk(scenario: Scenario, t_eval: npt.ArrayLike | None, inputs: Inputs, index: int,
              start: int, stop: int, fast: bool | None = None,
              threads: int | None = 1, euler_angles: bool = True) -> ChunkResult:
    """
    Integrate bodies ``start`` ... ``stop - 1`` of an ensemble: the task of a chunk.

    ``inputs`` holds ``impacts``, ``omega0`` and ``euler0``, each None, the chunk's slice of
    an explicit per-body input, or a sampler (drawn here for bodies start ... stop - 1).
    ``fast``, ``threads``, ``euler_angles``: as :func:`simulate_ensemble`.
    """
    n = stop - start
    impacts, omega0, euler0 = _resolve(scenario, inputs.get('impacts'), inputs.get('omega0'),
                                       inputs.get('euler0'), n, start)
    result = simulate_ensemble(scenario, t_eval, impacts=impacts, omega0=omega0,
                               euler0=euler0, n_bodies=n, fast=fast, threads=threads,
                               euler_angles=euler_angles)
    omega0 = np.tile(scenario.omega0, (n, 1)) if omega0 is None else np.asarray(omega0, float)
    euler0 = np.tile(scenario.euler0, (n, 1)) if euler0 is None else np.asarray(euler0, float)
    n_impacts = (np.full(n, len(scenario.impacts), dtype=np.int32) if impacts is None
                 else np.array([len(b) for b in impacts], dtype=np.int32))
    return ChunkResult(index, start, stop, result, omega0, euler0, n_impacts)


def iter_chunks(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
                impacts: ImpactsInput = None, omega0: VectorsInput = None,
                euler0: VectorsInput = None, n_bodies: int | None = None,
                chunk_size: int | None = None, fast: bool | None = None,
                skip: Collection[int] = frozenset(), threads: int | None = None,
                euler_angles: bool = True) -> Iterator[ChunkResult]:
    """
    Yield the results of the ensemble's chunks, one after the other, in this process.

    Inputs as :func:`simulate_ensemble`; the chunks of :func:`plan_chunks` (those in ``skip``
    not run), each on ``threads`` threads (default all cores). The same chunks on a Dask
    cluster, as they finish: ``tumble_ros.ensembles.run_chunks(..., client=...)``.
    """
    plan = plan_chunks(scenario, t_eval, impacts=impacts, omega0=omega0, euler0=euler0,
                       n_bodies=n_bodies, chunk_size=chunk_size, skip=skip)
    for task in plan.tasks:
        yield run_chunk(scenario, plan.times, task.inputs, task.index, task.start, task.stop,
                        fast, threads, euler_angles)


def concatenate_results(parts: Iterable[EnsembleResult]) -> EnsembleResult:
    """
    Join the results of consecutive groups of bodies (same times) into one, in the given order.

    ``wall_time`` is the sum of the parts' (the caller may replace it with
    ``dataclasses.replace``); ``compiled`` holds if it holds for every part. Parts run without
    Euler angles join into a result without them (the parts must agree: ValueError).
    """
    parts = list(parts)
    if not parts:
        raise ValueError('concatenate_results: no parts')
    t = parts[0].t
    if any(p.t.shape != t.shape or np.any(p.t != t) for p in parts):
        raise ValueError('concatenate_results: the parts have different sample times')
    euler_angles = parts[0].euler_angles
    if any(p.euler_angles != euler_angles for p in parts):
        raise ValueError('concatenate_results: some parts have Euler angles, some not')

    def cat(name: str) -> Any:
        return np.concatenate([getattr(p, name) for p in parts])

    success = cat('success')
    euler = cat('euler') if euler_angles else _no_euler(success.size, t.size)
    return EnsembleResult(t, cat('omega'), euler, cat('quaternion'), cat('jacobi'),
                          success, tuple(m for p in parts for m in p.messages),
                          cat('n_steps'), cat('nfev'), float(sum(p.wall_time for p in parts)),
                          all(p.compiled for p in parts), euler_angles)


class _NoPool:
    """``ThreadPoolExecutor`` stand-in that runs in the calling thread."""

    def __enter__(self) -> _NoPool:
        return self

    def __exit__(self, *exc: object) -> Literal[False]:
        return False

    @staticmethod
    def map(fn: Callable[[Any], Any],  # noqa: A003 (the name of the Executor method)
            items: Iterable[Any]) -> Iterator[Any]:
        return map(fn, items)

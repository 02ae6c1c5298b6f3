"""
Run an ensemble into a store: each chunk written as its task finishes, a restart resumes.

:func:`run_ensemble_to_store` is :func:`~.chunks.run_chunks` (in this process, or as tasks on a
Dask client) feeding :class:`tumble_ros.io.EnsembleStore`: the store is created with
its full shape, every finished chunk is written into its region and marked done, so memory
holds only the chunks in flight, whatever N. Run again with the same store and the same run
(checked by a fingerprint of the scenario, sample times, inputs, N and chunk size), it skips
the chunks marked done. A body that fails (a diverging state, a collapsing step) is stored
with status 'failed' and its reason; it does not stop the run. A run without Euler angles
(``euler_angles=False``) writes no ``euler`` array and records why (:data:`EULER_LEFT_OUT`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, is_dataclass
import hashlib
import json
from pathlib import Path
import time
from typing import Any

import numpy as np
import numpy.typing as npt

from tumble_ros.core import dump_scenario, Scenario
from tumble_ros.core.propagation.ensemble import (default_chunk_size, ImpactsInput, Inputs,
                                                  prepare_inputs, Progress, VectorsInput)
from tumble_ros.core.propagation.simulate import sample_times
from tumble_ros.io.ensemble_store import (EnsembleStore, SCENARIO_ATTR, STATUS_FAILED,
                                          STATUS_PENDING, STATUS_SUCCEEDED, store_lock)

from .chunks import run_chunks, workers_of

__all__ = ['EnsembleRunSummary', 'run_ensemble_to_store', 'run_fingerprint']

#: Failed bodies listed by name in a summary.
MAX_LISTED_FAILURES = 10
#: How a run without Euler angles left them out: what reading them from its store says.
EULER_LEFT_OUT = ('the run left out the Euler angles (euler_angles=False, the ensemble '
                  "command's --no-euler-angles); run it again without that option to have them")


@dataclass(frozen=True)
class EnsembleRunSummary:
    """
    What a run into a store did.

    Attributes
    ----------
    path : the store.
    n_bodies, n_chunks, chunk_size : the run's size and chunking.
    chunks_run, chunks_skipped : chunks computed now / found written by an earlier run.
    succeeded, failed, pending : bodies in the store by status, after this run.
    body_steps : integration steps of the bodies computed now.
    wall_time : seconds for this call (set-up and writing included).
    engine : where the chunks ran.
    failures : up to 10 (body, reason) of failed bodies.

    """

    path: Path
    n_bodies: int
    n_chunks: int
    chunk_size: int
    chunks_run: int
    chunks_skipped: int
    succeeded: int
    failed: int
    pending: int
    body_steps: int
    wall_time: float
    engine: str
    failures: tuple[tuple[int, str], ...]

    def lines(self) -> list[str]:
        """Return the summary as text lines."""
        rate = self.body_steps / self.wall_time if self.wall_time > 0 else 0.0
        out = [f'store: {self.path} ({self.n_bodies} bodies in {self.n_chunks} chunks of '
               f'{self.chunk_size})',
               f'chunks: {self.chunks_run} run now, {self.chunks_skipped} already written '
               f'(skipped); engine: {self.engine}',
               f'bodies: {self.succeeded} succeeded, {self.failed} failed, '
               f'{self.pending} pending',
               f'{self.body_steps} body-steps in {self.wall_time:.3f} s = {rate:.3g} '
               f'body-steps/s (writing included)']
        out += [f'body {b} failed: {reason}' for b, reason in self.failures]
        if self.failed > len(self.failures):
            out.append(f'... and {self.failed - len(self.failures)} more failed bodies '
                       '(status == 2 in the store, reason in its variable "reason")')
        return out


def _describe(value: object) -> object:
    """Return a JSON-able description of one per-body input (samplers by their fields)."""
    if value is None:
        return "the scenario's"
    if is_dataclass(value) and not isinstance(value, type):
        return {'kind': type(value).__name__, **asdict(value)}
    return {'kind': 'explicit per-body values'}


def _digest(value: object) -> str:
    """Return a hash of an explicit per-body input (impact tuples or an array)."""
    h = hashlib.sha256()
    if isinstance(value, np.ndarray):
        h.update(np.ascontiguousarray(value, dtype=float).tobytes())
    else:
        h.update(repr(value).encode())
    return h.hexdigest()


def run_fingerprint(scenario: Scenario, times: npt.NDArray[np.float64], inputs: Inputs,
                    n_bodies: int, chunk_size: int, euler_angles: bool = True) -> str:
    """
    Return the hash that identifies a run in its store (what a restart must match).

    ``euler_angles`` False enters the hash; True does not (the hash of stores written before
    the choice existed, which have the Euler angles).
    """
    h = hashlib.sha256()
    h.update(dump_scenario(scenario).encode())
    h.update(np.ascontiguousarray(times, dtype=float).tobytes())
    for name in ('impacts', 'omega0', 'euler0'):
        value = inputs.get(name)
        h.update(name.encode())
        h.update((json.dumps(_describe(value), sort_keys=True) if value is None or is_dataclass(
            value) else _digest(value)).encode())
    h.update(f'{n_bodies}/{chunk_size}'.encode())
    if not euler_angles:
        h.update(b'without euler angles')
    return h.hexdigest()


def _engine(client: Any) -> str:
    if client is None:
        return 'threads in this process'
    workers = client.nthreads()
    return (f'dask, {len(workers)} workers / {sum(workers.values())} threads at '
            f'{client.scheduler.address}')


def run_ensemble_to_store(scenario: Scenario, store: str | Path, *,
                          n_bodies: int | None = None, impacts: ImpactsInput = None,
                          omega0: VectorsInput = None, euler0: VectorsInput = None,
                          t_eval: npt.ArrayLike | None = None, chunk_size: int | None = None,
                          client: Any = None, fast: bool | None = None,
                          threads: int | None = None, overwrite: bool = False,
                          progress: Progress | None = None,
                          euler_angles: bool = True) -> EnsembleRunSummary:
    """
    Integrate an ensemble chunk by chunk into the Zarr store ``store``; return a summary.

    Parameters
    ----------
    scenario, t_eval, n_bodies, impacts, omega0, euler0, fast, euler_angles
        As :func:`tumble_ros.core.simulate_ensemble` (``euler_angles`` False: the store gets
        no ``euler``, and says why when it is read): ``impacts`` a :class:`RandomImpacts` or
        per-body Impact sequences, ``omega0`` [rad/yr, body axes] and ``euler0`` [rad] a
        :class:`GaussianSpread` or (N, 3) arrays; samples at ``t_eval`` [yr] (default the
        scenario's output grid).
    store
        Path of the Zarr store (a directory). If it exists and holds this same run, the
        chunks already written are skipped; if it holds another run, EnsembleStoreError
        (unless ``overwrite``: it is replaced).
    chunk_size
        Bodies per chunk (task and store chunk); default: the store's when resuming, else
        :func:`tumble_ros.core.propagation.ensemble.default_chunk_size`.
    client
        A Dask ``distributed.Client`` (``tumble_ros.ensembles.dask_client``), or None: the
        chunks run in this process one after the other.
    threads
        Without a client: threads per chunk (default all cores). Results do not depend on it.
    overwrite
        Replace an existing store instead of resuming it.
    progress
        ``progress(fraction of bodies written, t_end [yr], body-steps so far)`` after each
        chunk (e.g. ``ProgressBar(..., by='bodies')`` of :mod:`tumble_ros.cli.progress`).

    """
    start = time.perf_counter()
    times = sample_times(scenario, t_eval)
    n, inputs = prepare_inputs(scenario, impacts, omega0, euler0, n_bodies)
    path = Path(store)
    with store_lock(path):
        return _run_locked(scenario, path, times, n, inputs, chunk_size, client, fast, threads,
                           overwrite, progress, start, euler_angles)


def _run_locked(scenario: Scenario, path: Path, times: npt.NDArray[np.float64], n: int,
                inputs: Inputs, chunk_size: int | None, client: Any, fast: bool | None,
                threads: int | None, overwrite: bool, progress: Progress | None,
                start: float, euler_angles: bool) -> EnsembleRunSummary:
    """:func:`run_ensemble_to_store` once it holds the store's lock."""
    resuming = path.exists() and not overwrite
    if resuming:
        existing = EnsembleStore(path)
        size = existing.chunk_size if chunk_size is None else int(chunk_size)
        out = EnsembleStore.resume(path, fingerprint=run_fingerprint(scenario, times, inputs, n,
                                                                     size, euler_angles))
    else:
        size = default_chunk_size(n, times.size, workers_of(client)) if chunk_size is None \
            else int(chunk_size)
        attrs = {'title': 'tumble_ros ensemble',
                 SCENARIO_ATTR: dump_scenario(scenario),
                 'inputs': json.dumps({k: _describe(v) for k, v in inputs.items()}),
                 'duration_yr': float(scenario.duration),
                 'integrator': scenario.integrator.method,
                 'fingerprint': run_fingerprint(scenario, times, inputs, n, size, euler_angles),
                 'created_utc': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())}
        out = EnsembleStore.create(path, n_bodies=n, times=times, chunk_size=size, attrs=attrs,
                                   overwrite=overwrite,
                                   left_out=None if euler_angles else {'euler': EULER_LEFT_OUT})
    done = out.done()
    skip = frozenset(np.flatnonzero(done).tolist())
    written = int(sum(min(n, (i + 1) * size) - i * size for i in skip))
    chunks_run, steps = 0, 0
    for chunk in run_chunks(scenario, times, impacts=inputs['impacts'],
                            omega0=inputs['omega0'], euler0=inputs['euler0'], n_bodies=n,
                            chunk_size=size, client=client, fast=fast, skip=skip,
                            threads=threads, euler_angles=euler_angles):
        r = chunk.result
        out.write_chunk(chunk.index, chunk.start, {
            'omega': r.omega, 'euler': r.euler, 'quaternion': r.quaternion, 'jacobi': r.jacobi,
            'status': np.where(r.success, STATUS_SUCCEEDED, STATUS_FAILED),
            'reason': list(r.messages), 'n_steps': r.n_steps, 'nfev': r.nfev,
            'omega0': chunk.omega0, 'euler0': chunk.euler0, 'n_impacts': chunk.n_impacts})
        chunks_run += 1
        steps += int(r.n_steps.sum())
        written += chunk.stop - chunk.start
        if progress is not None:
            progress(written / n, float(times[-1]), steps)
    status = out.read('status')
    failed = np.flatnonzero(status == STATUS_FAILED)
    failures = tuple((int(b), str(out.read('reason', int(b))))
                     for b in failed[:MAX_LISTED_FAILURES])
    return EnsembleRunSummary(path, n, out.n_chunks, size, chunks_run, len(skip),
                              int(np.sum(status == STATUS_SUCCEEDED)), int(failed.size),
                              int(np.sum(status == STATUS_PENDING)), steps,
                              time.perf_counter() - start, _engine(client), failures)

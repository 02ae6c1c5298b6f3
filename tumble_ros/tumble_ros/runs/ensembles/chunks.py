"""
Where an ensemble's chunks run: in this process, or as tasks on a Dask client.

The chunks and the work of each are core's
(:func:`tumble_ros.core.propagation.ensemble.plan_chunks`,
:func:`tumble_ros.core.propagation.ensemble.run_chunk`); this module picks the engine:
:func:`run_chunks` yields the chunks' results as they finish, :func:`run_ensemble` gathers them
into one :class:`~tumble_ros.core.EnsembleResult` (``client=None``: the in-process
:func:`tumble_ros.core.simulate_ensemble` itself). Body k's numbers do not depend on the
engine, the chunk size or the number of workers (test_ensemble_dask.py).
"""
from __future__ import annotations

from collections.abc import Collection, Iterator, Sized
from dataclasses import replace
import time
from typing import Any

import numpy.typing as npt

from tumble_ros.core import concatenate_results, EnsembleResult, iter_chunks, Scenario
from tumble_ros.core import simulate_ensemble
from tumble_ros.core.propagation.ensemble import (ChunkResult, ImpactsInput, plan_chunks, Progress,
                                                  run_chunk, VectorsInput)

from .dask_engine import map_as_completed

__all__ = ['run_chunks', 'run_ensemble', 'workers_of']


def workers_of(client: Any) -> int:
    """Return the number of workers of a Dask client (1 for None: this process)."""
    return 1 if client is None else max(1, len(client.nthreads()))


def run_chunks(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
               impacts: ImpactsInput = None, omega0: VectorsInput = None,
               euler0: VectorsInput = None, n_bodies: int | None = None,
               chunk_size: int | None = None, client: Any = None, fast: bool | None = None,
               skip: Collection[int] = frozenset(), threads: int | None = None,
               max_in_flight: int | None = None,
               euler_angles: bool = True) -> Iterator[ChunkResult]:
    """
    Yield the results of the ensemble's chunks as they finish (in any order).

    Inputs and ``euler_angles`` as :func:`tumble_ros.core.simulate_ensemble` (each chunk's
    call gets them). ``client``: a Dask
    ``distributed.Client`` (None: the chunks run here one after the other, each on ``threads``
    threads, default all cores: :func:`tumble_ros.core.iter_chunks`). Chunks whose index is in
    ``skip`` are not run. With a client at most ``max_in_flight`` tasks (default: twice the
    cluster's threads, plus 2) are submitted at once, so neither the workers nor this process
    hold more than that many chunks' results. Closing the iterator early (an exception,
    Ctrl-C) cancels the tasks not finished. With a client, a task that raises anything but a
    ScenarioError raises :class:`~.dask_engine.EnsembleRunError` here.
    """
    if client is None:
        yield from iter_chunks(scenario, t_eval, impacts=impacts, omega0=omega0, euler0=euler0,
                               n_bodies=n_bodies, chunk_size=chunk_size, fast=fast, skip=skip,
                               threads=threads, euler_angles=euler_angles)
        return
    plan = plan_chunks(scenario, t_eval, impacts=impacts, omega0=omega0, euler0=euler0,
                       n_bodies=n_bodies, chunk_size=chunk_size, workers=workers_of(client),
                       skip=skip)
    yield from map_as_completed(
        client, run_chunk,
        [(scenario, plan.times, task.inputs, task.index, task.start, task.stop, fast, 1,
          euler_angles) for task in plan.tasks],
        names=[f'chunk-{task.index}' for task in plan.tasks], max_in_flight=max_in_flight)


def run_ensemble(scenario: Scenario, t_eval: npt.ArrayLike | None = None, *,
                 impacts: ImpactsInput = None, omega0: VectorsInput = None,
                 euler0: VectorsInput = None, n_bodies: int | None = None,
                 fast: bool | None = None, progress: Progress | None = None,
                 threads: int | None = None, client: Any = None,
                 chunk_size: int | None = None, euler_angles: bool = True) -> EnsembleResult:
    """
    Return an ensemble's result in memory, run in this process or as chunks on ``client``.

    Inputs and ``euler_angles`` as :func:`tumble_ros.core.simulate_ensemble` (which this is,
    with ``client=None``).
    ``client``: a Dask ``distributed.Client`` (:func:`~.dask_engine.dask_client`): the bodies
    are cut into chunks of ``chunk_size`` (default
    :func:`tumble_ros.core.propagation.ensemble.default_chunk_size`), each integrated in a task
    on the cluster's workers (one thread per task) and gathered here, with the same results bit for
    bit. With a client, ``progress(fraction of bodies done, t_end [yr], body-steps so far)`` is
    called as each chunk finishes and ``wall_time`` is the wall-clock time of the whole run.
    Results bigger than memory go to a store instead: :func:`~.to_store.run_ensemble_to_store`.
    """
    if client is None:
        return simulate_ensemble(scenario, t_eval, impacts=impacts, omega0=omega0,
                                 euler0=euler0, n_bodies=n_bodies, fast=fast,
                                 progress=progress, threads=threads, euler_angles=euler_angles)
    start = time.perf_counter()
    parts: dict[int, EnsembleResult] = {}
    done, steps, total = 0, 0, None
    for chunk in run_chunks(scenario, t_eval, impacts=impacts, omega0=omega0, euler0=euler0,
                            n_bodies=n_bodies, chunk_size=chunk_size, client=client,
                            fast=fast, euler_angles=euler_angles):
        parts[chunk.index] = chunk.result
        done += chunk.stop - chunk.start
        steps += int(chunk.result.n_steps.sum())
        if progress is not None:
            if total is None:
                total = _n_bodies(impacts, omega0, euler0, n_bodies)
            progress(done / total, float(chunk.result.t[-1]), steps)
    result = concatenate_results(parts[i] for i in sorted(parts))
    return replace(result, wall_time=time.perf_counter() - start)


def _n_bodies(impacts: ImpactsInput, omega0: VectorsInput, euler0: VectorsInput,
              n_bodies: int | None) -> int:
    """Return N of inputs already checked by a run (``n_bodies``, else an explicit input's)."""
    if n_bodies is not None:
        return int(n_bodies)
    for value in (impacts, omega0, euler0):
        if isinstance(value, Sized):
            return len(value)
    return 1

r"""
The Dask engine of ensembles: tasks on a ``distributed`` cluster, results as they finish.

:func:`~.chunks.run_chunks` and :func:`~.chunks.run_ensemble` run the chunks of an ensemble
(:func:`tumble_ros.core.propagation.ensemble.plan_chunks`); with a Dask client, each chunk is
one task (:func:`tumble_ros.core.propagation.ensemble.run_chunk`: the compiled loop runs inside
it) on the workers of a ``distributed`` cluster: an embedded ``LocalCluster`` (the default way
to use every core in separate processes) or a cluster started with Dask's own ``dask
scheduler`` and ``dask worker`` commands (docs/python.md, "Running on a cluster"). Dask does
the scheduling, the transport and the fault tolerance (a task whose worker dies is run again
elsewhere); this module only submits, hands results back as they finish and cancels what is
left when the caller stops::

    from tumble_ros.core import load_scenario, RandomImpacts
    from tumble_ros.ensembles import dask_client, run_ensemble
    sc = load_scenario('tumble_ros/config/fig9.yaml').replace(duration=20.0, output_interval=1.0)
    with dask_client(workers=2) as client:
        res = run_ensemble(sc, impacts=RandomImpacts(rate=0.5, torque=1e6, seed=1),
                           n_bodies=100_000, client=client)

**Same answer everywhere.** Body k's result depends on body k's inputs only: the compiled
loop integrates each body on its own, and the per-body random inputs (``RandomImpacts``,
``GaussianSpread``) are drawn from (seed, body) alone, inside the task. So the results are
bit-identical whatever the chunk size, the number of workers or the engine (threads in this
process, local cluster, remote cluster): ``test_ensemble_dask.py``.

Results bigger than memory go to a labelled store chunk by chunk instead of being gathered:
:func:`tumble_ros.ensembles.run_ensemble_to_store`. Dask is imported on first use only.
"""
from __future__ import annotations

from contextlib import contextmanager
import functools
import logging
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence, TypeVar
import uuid

import numpy as np

from tumble_ros.core import ScenarioError
from tumble_ros.core.compiling.user_cache import user_cache_dir
from tumble_ros.errors import CoreError

__all__ = ['EnsembleRunError', 'dask_client', 'map_as_completed', 'LOOPBACK']

R = TypeVar('R')


class EnsembleRunError(CoreError):
    """A distributed ensemble run that could not run: no cluster, a task that raised."""


def map_as_completed(client: Any, fn: Callable[..., R], calls: Sequence[tuple[Any, ...]], *,
                     names: Sequence[str] | None = None,
                     max_in_flight: int | None = None) -> Iterator[R]:
    """
    Yield ``fn(*args)`` for each ``args`` of ``calls``, run as tasks on ``client``, as they finish.

    At most ``max_in_flight`` tasks (default: twice the cluster's threads, plus 2) are submitted
    at a time, so that the results waiting on the workers and here stay bounded whatever the
    number of calls. A task that raises a ScenarioError re-raises it here; any other exception
    becomes an :class:`EnsembleRunError` naming the task. Closing the iterator early (an
    exception in the caller, Ctrl-C) cancels the tasks not finished.
    """
    from distributed import as_completed

    if max_in_flight is None:
        max_in_flight = 2 * max(1, sum(client.nthreads().values())) + 2
    run = uuid.uuid4().hex[:8]
    names = [str(k) for k in range(len(calls))] if names is None else list(names)
    waiting = iter(zip(names, calls))
    futures = as_completed()  # type: ignore[no-untyped-call]  # (distributed has no hints here)
    submitted: list[Any] = []

    def submit_next() -> None:
        item = next(waiting, None)
        if item is not None:
            name, args = item
            future = client.submit(fn, *args, key=f'tumble-ensemble-{run}-{name}')
            submitted.append(future)
            futures.add(future)  # type: ignore[no-untyped-call]  # (distributed has no hints here)

    try:
        for _ in range(max(1, int(max_in_flight))):
            submit_next()
        for future in futures:
            try:
                value: R = future.result()
            except ScenarioError:
                raise
            except Exception as err:  # the task's own exception, re-raised by Dask here
                raise EnsembleRunError(f'ensemble task {future.key} failed: '
                                       f'{type(err).__name__}: {err}') from err
            future.release()
            submit_next()
            yield value
    finally:
        pending = [f for f in submitted if not f.done()]
        if pending:
            client.cancel(pending)


#: Where every listener of an embedded cluster binds: the loopback interface only (the
#: scheduler, the nannies, the workers and their HTTP servers), never all interfaces.
LOOPBACK = '127.0.0.1'


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None, *,
                timeout: float = 30.0, dashboard: bool = False) -> Iterator[Any]:
    """
    Yield a Dask ``distributed.Client``; close it (and its local cluster) on exit.

    ``workers=N``: an embedded ``LocalCluster`` of N worker processes with one thread each,
    every one of its listeners (scheduler, nannies, workers, the scheduler's HTTP server) on
    :data:`LOOPBACK` and a free port (two runs at once do not collide; nothing is reachable
    from the network). ``dashboard``: also serve Dask's dashboard (it needs bokeh) on that
    HTTP server, still on 127.0.0.1; off by default. ``scheduler='tcp://host:8786'``: the
    cluster of that scheduler, started with ``dask scheduler`` and ``dask worker`` (its workers
    must run in this workspace's environment: ``scripts/env.sh dask worker ADDRESS``). Raises
    :class:`EnsembleRunError` when the scheduler cannot be reached within ``timeout`` seconds,
    or a local cluster does not start (a worker that dies while it starts).
    """
    if (workers is None) == (scheduler is None):
        raise ScenarioError('dask_client: give workers (a local cluster) or scheduler '
                            '(an address), one of them')
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            # (distributed has no type hints here)
            client = Client(scheduler, timeout=timeout)  # type: ignore[no-untyped-call]
        except (OSError, TimeoutError, ValueError) as err:
            raise EnsembleRunError(f'cannot reach the Dask scheduler at {scheduler!r}: '
                                   f'{err}') from None
        try:
            yield client
        finally:
            client.close()  # type: ignore[no-untyped-call]  # (distributed has no hints here)
        return
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ScenarioError(f'workers: must be an integer >= 1, got {workers!r}')
    with _workers_ignore_sigint():
        try:
            cluster = LocalCluster(  # type: ignore[no-untyped-call]  # (no hints in distributed)
                n_workers=int(workers), threads_per_worker=1, processes=True, host=LOOPBACK,
                dashboard_address=f'{LOOPBACK}:0', worker_dashboard_address=None,
                silence_logs=logging.CRITICAL, scheduler_kwargs={'dashboard': bool(dashboard)})
        except (RuntimeError, OSError, TimeoutError, ValueError) as err:
            raise EnsembleRunError(f'cannot start a local Dask cluster of {workers} workers: '
                                   f'{type(err).__name__}: {err}') from None
        try:
            with Client(cluster) as client:  # type: ignore[no-untyped-call]  # (no hints)
                yield client
        finally:
            cluster.close()


@contextmanager
def _workers_ignore_sigint() -> Iterator[None]:
    """
    Start the processes multiprocessing spawns meanwhile with SIGINT ignored.

    A Ctrl-C at a terminal goes to the whole process group: the worker processes of a local
    cluster died of it, each with its KeyboardInterrupt traceback (or 'Nanny failed to start'
    when they were starting). Spawned through a shell that ignores SIGINT (an ignored signal
    stays ignored across exec, and Python then installs no handler for it), they leave the
    interrupt to this process, which stops the cluster in order (the nannies end their
    workers with SIGTERM). Restarts of killed workers during the run are covered too.
    """
    import multiprocessing.spawn as mp_spawn

    previous = mp_spawn.get_executable()
    mp_spawn.set_executable(str(_sigint_ignoring_python()))
    try:
        yield
    finally:
        mp_spawn.set_executable(previous)


@functools.lru_cache(maxsize=1)
def _sigint_ignoring_python() -> Path:
    """
    Return a shell wrapper that runs this Python with SIGINT ignored (made once, then kept).

    It is never removed: a Ctrl-C while the cluster starts ends this process while a nanny
    (its child) may still be spawning a worker through it, and a wrapper removed then, even at
    the interpreter's exit, printed "/bin/sh: 0: cannot open .../python" (and the resource
    tracker it failed to start warned it died). Its text depends only on ``sys.executable``, so
    one file per interpreter serves every run: in the user's cache folder
    (``core.compiling.user_cache.user_cache_dir``: ``~/.cache/tumble_ros``, made private), written
    whole then renamed into place (concurrent runs never see half a file); where that folder
    cannot be written, in a private temporary folder.
    """
    import hashlib
    import os
    import shlex
    import sys
    import tempfile

    text = f"#!/bin/sh\ntrap '' INT\nexec {shlex.quote(sys.executable)} \"$@\"\n"
    name = 'python-sigint-ignored-' + hashlib.sha256(sys.executable.encode()).hexdigest()[:16]
    cache = user_cache_dir()
    try:
        cache.mkdir(mode=0o700, parents=True, exist_ok=True)
        folder = cache
    except OSError:
        folder = Path(tempfile.mkdtemp(prefix='tumble-dask-'))
    wrapper = folder / name
    try:
        if wrapper.read_text() == text and os.access(wrapper, os.X_OK):
            return wrapper
    except OSError:
        pass
    handle, scratch = tempfile.mkstemp(dir=folder, prefix=name + '.')
    with os.fdopen(handle, 'w') as file:
        file.write(text)
    os.chmod(scratch, 0o700)
    os.replace(scratch, wrapper)
    return wrapper

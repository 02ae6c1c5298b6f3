"""
Ensemble runs: where the chunks of an ensemble run and where their results go.

    from tumble_ros.core import load_scenario, RandomImpacts
    from tumble_ros.ensembles import dask_client, open_ensemble, run_ensemble_to_store
    sc = load_scenario('tumble_ros/config/fig9.yaml').replace(duration=20.0, output_interval=1.0)
    with dask_client(workers=2) as client:               # or dask_client(scheduler='tcp://...')
        summary = run_ensemble_to_store(sc, 'ens.zarr', n_bodies=1_000_000, client=client,
                                        impacts=RandomImpacts(rate=0.5, torque=1e6, seed=1))
    ds = open_ensemble('ens.zarr')                       # xarray Dataset: omega (body, time, ...)

The numbers are core's (:mod:`tumble_ros.core.propagation.ensemble`: the in-process ensemble,
the chunks and the task of one chunk); the store is io's (:mod:`tumble_ros.io.ensemble_store`).
Here:
:mod:`.dask_engine` (the Dask client, tasks as they finish), :mod:`.chunks` (the engine of a
run: this process or Dask; :func:`run_ensemble` in memory), :mod:`.to_store` (a run into a
store, chunk by chunk, resumable). ``tumble_ros.ensembles`` re-exports these names.
"""
from tumble_ros.io.ensemble_store import ensemble_variable, EnsembleStoreError, open_ensemble

from .chunks import run_chunks, run_ensemble
from .dask_engine import dask_client, EnsembleRunError
from .to_store import EnsembleRunSummary, run_ensemble_to_store, run_fingerprint

__all__ = ['EnsembleRunError', 'EnsembleRunSummary', 'EnsembleStoreError', 'dask_client',
           'ensemble_variable', 'open_ensemble', 'run_chunks', 'run_ensemble',
           'run_ensemble_to_store', 'run_fingerprint']

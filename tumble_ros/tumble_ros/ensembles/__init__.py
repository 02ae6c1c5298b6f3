"""
Ensembles that outgrow one machine: chunks of bodies on Dask, labelled results on disk.

    from tumble_ros.core import load_scenario, RandomImpacts
    from tumble_ros.ensembles import dask_client, open_ensemble, run_ensemble_to_store
    sc = load_scenario('tumble_ros/config/fig9.yaml').replace(duration=20.0, output_interval=1.0)
    with dask_client(workers=2) as client:               # or dask_client(scheduler='tcp://...')
        summary = run_ensemble_to_store(sc, 'ens.zarr', n_bodies=1_000_000, client=client,
                                        impacts=RandomImpacts(rate=0.5, torque=1e6, seed=1))
    ds = open_ensemble('ens.zarr')                       # xarray Dataset: omega (body, time, ...)

The work is :func:`tumble_ros.core.iter_chunks` (the compiled ensemble loop inside each task),
the store :mod:`tumble_ros.io.ensemble_store`; this package joins them. It imports core and io.
"""
from tumble_ros.core.ensemble_dask import dask_client, EnsembleRunError
from tumble_ros.io.ensemble_store import EnsembleStoreError, open_ensemble

from .runner import EnsembleRunSummary, run_ensemble_to_store, run_fingerprint

__all__ = ['EnsembleRunError', 'EnsembleRunSummary', 'EnsembleStoreError', 'dask_client',
           'open_ensemble', 'run_ensemble_to_store', 'run_fingerprint']

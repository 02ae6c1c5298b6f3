"""
The ensemble runs' public import path, kept for users: a thin re-export of the run layer.

Everything here is :mod:`tumble_ros.runs.ensembles` (the Dask engine, the runs in memory and
into stores) and :func:`tumble_ros.io.ensemble_store.open_ensemble` and ``ensemble_variable``;
see there::

    from tumble_ros.ensembles import dask_client, open_ensemble, run_ensemble_to_store
"""
from tumble_ros.runs.ensembles import (dask_client, ensemble_variable, EnsembleRunError,
                                       EnsembleRunSummary, EnsembleStoreError, open_ensemble,
                                       run_chunks, run_ensemble, run_ensemble_to_store,
                                       run_fingerprint)

__all__ = ['EnsembleRunError', 'EnsembleRunSummary', 'EnsembleStoreError', 'dask_client',
           'ensemble_variable', 'open_ensemble', 'run_chunks', 'run_ensemble',
           'run_ensemble_to_store', 'run_fingerprint']

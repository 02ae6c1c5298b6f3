"""Ensemble runs: the engines (this process, Dask) and the runs into stores."""

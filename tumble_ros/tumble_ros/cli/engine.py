"""
Where an ensemble command runs its bodies: threads here, a local Dask cluster, or a cluster.

One set of options for every ensemble command (``--workers N``, ``--scheduler ADDRESS``,
``--scheduler-timeout S``) and the client they ask for
(:func:`tumble_ros.ensembles.dask_client`).
"""
from __future__ import annotations

import argparse
from contextlib import nullcontext

from tumble_ros.core import ScenarioError
from tumble_ros.ensembles import dask_client

__all__ = ['add_engine_arguments', 'engine']


def add_engine_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--workers``, ``--scheduler`` (one of them) and ``--scheduler-timeout``."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument('--workers', type=int, metavar='N',
                       help='run chunks of bodies on an embedded Dask LocalCluster of N '
                            'worker processes (one thread each)')
    group.add_argument('--scheduler', metavar='ADDRESS',
                       help='run chunks of bodies on the Dask cluster of this scheduler '
                            '(tcp://host:8786; started with `dask scheduler` and '
                            '`dask worker`)')
    parser.add_argument('--scheduler-timeout', type=float, default=30.0,
                        help='seconds to wait for --scheduler (default 30)')


def engine(args: argparse.Namespace):
    """
    Return a context manager yielding the Dask client the options ask for, or None.

    None: the bodies run on threads in this process. Raises ScenarioError for --workers < 1.
    """
    if args.workers is not None:
        if args.workers < 1:
            raise ScenarioError(f'--workers: must be >= 1, got {args.workers}')
        return dask_client(workers=args.workers)
    if args.scheduler:
        return dask_client(scheduler=args.scheduler, timeout=args.scheduler_timeout)
    return nullcontext()

"""
Where an ensemble command runs its bodies: threads here, a local Dask cluster, or a cluster.

One set of options for every ensemble command (``--workers N``, ``--dashboard``,
``--scheduler ADDRESS``, ``--scheduler-timeout S``) and the client they ask for
(:func:`tumble_ros.ensembles.dask_client`). An embedded cluster listens on 127.0.0.1 only;
its dashboard is off unless ``--dashboard`` asks for it (then on 127.0.0.1 too, its address
on stderr).
"""
from __future__ import annotations

import argparse
from contextlib import contextmanager, nullcontext
import math
import sys

from tumble_ros.core import ScenarioError
from tumble_ros.ensembles import dask_client

__all__ = ['add_engine_arguments', 'engine', 'MAX_SCHEDULER_TIMEOUT']

#: Longest --scheduler-timeout [s]: an hour.
MAX_SCHEDULER_TIMEOUT = 3600.0


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
    parser.add_argument('--dashboard', action='store_true',
                        help="with --workers: serve Dask's dashboard (needs bokeh) on "
                             '127.0.0.1, its address printed on stderr (default: off)')


def engine(args: argparse.Namespace):
    """
    Return a context manager yielding the Dask client the options ask for, or None.

    None: the bodies run on threads in this process. Raises ScenarioError for --workers < 1,
    a --scheduler-timeout that is not a finite number > 0, or --dashboard without --workers.
    """
    dashboard = getattr(args, 'dashboard', False)
    if dashboard and args.workers is None:
        raise ScenarioError('--dashboard: needs --workers N (the dashboard of a running '
                            "cluster is its scheduler's)")
    if args.workers is not None:
        if args.workers < 1:
            raise ScenarioError(f'--workers: must be >= 1, got {args.workers}')
        return _announced(dask_client(workers=args.workers, dashboard=dashboard), dashboard)
    if args.scheduler:
        timeout = args.scheduler_timeout
        if not (math.isfinite(timeout) and 0 < timeout <= MAX_SCHEDULER_TIMEOUT):
            raise ScenarioError(f'--scheduler-timeout: must be in (0, {MAX_SCHEDULER_TIMEOUT:g}] '
                                f's, got {timeout:g}')
        return dask_client(scheduler=args.scheduler, timeout=timeout)
    return nullcontext()


@contextmanager
def _announced(clients, dashboard: bool):
    """Enter ``clients``; with ``dashboard``, print where the dashboard is (stderr)."""
    with clients as client:
        if dashboard:
            print(f'dask dashboard: {client.dashboard_link}', file=sys.stderr, flush=True)
        yield client

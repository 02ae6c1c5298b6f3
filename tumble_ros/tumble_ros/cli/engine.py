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
import signal
import sys
import threading
from typing import Iterator

from tumble_ros.core import ScenarioError
from tumble_ros.ensembles import dask_client

__all__ = ['add_engine_arguments', 'engine', 'Interrupted', 'interrupts', 'MAX_SCHEDULER_TIMEOUT']

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


class Interrupted(BaseException):
    """
    A stop asked by a signal (SIGINT, SIGTERM, SIGHUP), raised where the program is.

    A BaseException, as KeyboardInterrupt is: no ``except Exception`` (Dask's included) on the
    way up swallows it. ``exit_code`` is 128 + the signal's number (130, 143, 129).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)
        self.name = signal.Signals(self.signum).name
        self.exit_code = 128 + self.signum


#: The signals that stop an ensemble command, alike.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextmanager
def interrupts() -> Iterator[None]:
    """
    Turn SIGINT, SIGTERM and SIGHUP into :class:`Interrupted` while the block runs.

    The first signal raises; any later one is ignored while the program cleans up (a local
    cluster stopping, a store's lock released). A KeyboardInterrupt raised by someone else's
    handler becomes Interrupted(SIGINT) too. The previous handlers are restored on exit.

    Python runs a signal's handler wherever the main thread is, a finaliser or a garbage
    collector's callback included (Dask's ``GCDiagnosis``), where an exception is not raised
    but printed as "Exception ignored" (``sys.unraisablehook``): the stop was lost, and the
    run went on to its end with every later Ctrl-C ignored. Such an Interrupted is raised
    again where the program is (:func:`_raise_again`), silently.
    """
    previous = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    previous_hook = sys.unraisablehook

    def stop(signum, frame) -> None:
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)
        raise Interrupted(signum)

    def swallowed(unraisable) -> None:
        if isinstance(unraisable.exc_value, Interrupted):
            _raise_again(unraisable.exc_value.signum, stop)
        else:
            previous_hook(unraisable)

    for sig in STOP_SIGNALS:
        signal.signal(sig, stop)
    sys.unraisablehook = swallowed
    try:
        yield
    except KeyboardInterrupt:
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)
        raise Interrupted(signal.SIGINT) from None
    except Interrupted:
        raise
    except BaseException:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        raise
    finally:
        sys.unraisablehook = previous_hook
    for sig, handler in previous.items():
        signal.signal(sig, handler)


#: How long after a swallowed Interrupted its signal comes again [s] (:func:`_raise_again`).
AGAIN_AFTER = 0.01


def _raise_again(signum: int, stop) -> None:
    """
    Send signal ``signum`` to the main thread again in :data:`AGAIN_AFTER`, to handler ``stop``.

    For an Interrupted that a finaliser swallowed (this runs in ``sys.unraisablehook``, in the
    main thread, where signal handlers run). Not at once: the handler would run in the hook
    itself, whose exceptions are swallowed too. A few milliseconds later the finaliser has
    returned and the handler raises where the program is (or, landing in a finaliser again,
    comes back here).
    """
    signal.signal(signum, stop)
    again = threading.Timer(AGAIN_AFTER, signal.pthread_kill,
                            (threading.main_thread().ident, signum))
    again.daemon = True
    again.start()

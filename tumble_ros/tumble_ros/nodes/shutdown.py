"""
Stopping cleanly: SIGINT, SIGTERM and SIGHUP alike, served once, between callbacks.

rclpy's own signal handler shuts the context down the moment SIGINT arrives, so a node can no
longer publish its goodbye (``consumer_progress``) or log; SIGTERM (how containers, CI and systemd
stop a process) is not handled at all, nor SIGHUP (a closed terminal or ssh session); and a second
SIGINT (``ros2 launch`` forwards Ctrl-C to a process group that already received it) raises
KeyboardInterrupt in the middle of the clean-up. :class:`StopSignals` replaces these behaviours:
the first SIGINT, SIGTERM or SIGHUP only records a stop request, which the spin loop
(:func:`spin_until_stopped`) sees between callbacks (within ``POLL`` seconds); the node then closes
with its context still valid; later signals are absorbed with one line on stderr, and ignored for
good once the clean-up is over. No exception is ever raised inside a callback, so a file being
written is never left half-written by a signal.
SIGQUIT is left to Python's default: it ends the process at once, unfinalised (the way out of a
hung clean-up). A :class:`StopSignals` entered while another one is active (the early one of
``python -m tumble_ros``, installed before the executable is imported) takes over a stop the
outer one already received.
"""
from __future__ import annotations

from contextlib import contextmanager
import os
import signal
import threading
from types import FrameType
from typing import Any, Callable, Iterator, TYPE_CHECKING

if TYPE_CHECKING:   # rclpy is imported when spinning only: StopSignals is installed before it
    from rclpy.executors import Executor

__all__ = ['StopSignals', 'StopDuringSetUp', 'spin_until_stopped', 'POLL', 'STOP_SIGNALS']

#: The signals that request a stop.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: Longest wait of the spin loop [s] before it looks at the stop request again.
POLL = 0.1


class StopDuringSetUp(BaseException):
    """
    A stop signal received while a node is being built (:meth:`StopSignals.interrupting`).

    A BaseException (as KeyboardInterrupt): no ``except Exception`` on the way swallows it.
    """


class StopSignals:
    """
    Context manager: while active, SIGINT/SIGTERM/SIGHUP request a stop instead of interrupting.

    ``signum`` is the first signal received (None: none yet). Outside the main thread (where
    Python cannot install handlers) it does nothing and ``signum`` stays None. The previous
    handlers are restored on exit.
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.signum: int | None = None
        self._saved: dict[int, Callable[[int, FrameType | None], Any] | int | None] = {}
        self._outer: StopSignals | None = None
        self._interrupting = False

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                self._saved[signum] = signal.signal(signum, self._handle)
            outer = getattr(self._saved[signal.SIGINT], '__self__', None)
            if isinstance(outer, StopSignals):
                self._outer = outer
                self.signum = outer.signum   # a stop that came before this one was entered
        return self

    def __exit__(self, *exc) -> None:
        """
        Restore the previous handlers, unless a stop was requested.

        Then the caller is being stopped, and later SIGINT/SIGTERM are ignored for good
        (``ros2 launch`` sends two; a late one must not kill the interpreter while it exits).
        """
        for signum, handler in self._saved.items():
            signal.signal(signum, signal.SIG_IGN if self.requested else handler)
        self._saved.clear()
        if self._outer is not None and self._outer.signum is None:
            self._outer.signum = self.signum   # the outer one ignores later signals too

    @contextmanager
    def interrupting(self) -> Iterator[None]:
        """
        Within: a stop signal raises :class:`StopDuringSetUp` at once, instead of waiting.

        For building a node (reading a shape file, checking it: seconds for a large one), where
        nothing is half-written and the spin loop that would see the request has not started.
        Python runs the handler between two bytecodes, so the stop is served within the
        longest single C call of the set-up (each bounded: docs/ros.md, "Limits of the
        inputs"). A stop requested before entering raises on entry.
        """
        if self.requested:
            raise StopDuringSetUp(self.signum)
        self._interrupting = True
        try:
            yield
        finally:
            self._interrupting = False

    def _handle(self, signum: int, _frame) -> None:
        if self.signum is None:
            self.signum = signum
            if self._interrupting:
                self._interrupting = False
                raise StopDuringSetUp(signum)
            return
        # os.write, not print: a handler may run while the main thread is inside a print.
        name = signal.Signals(signum).name
        os.write(2, f'{self.name}: {name} again: already stopping\n'.encode())

    @property
    def requested(self) -> bool:
        """Return True once SIGINT, SIGTERM or SIGHUP arrived."""
        return self.signum is not None

    @property
    def exit_code(self) -> int:
        """128 + the signal number (130 SIGINT, 143 SIGTERM, 129 SIGHUP), as a shell reports it."""
        return 128 + (self.signum or 0)


def spin_until_stopped(executor: Executor, stop: Callable[[], bool]) -> None:
    """Run callbacks until ``stop()`` is true or the context is shut down from outside."""
    from rclpy.executors import ExternalShutdownException

    try:
        while not stop() and executor.context.ok():
            executor.spin_once(timeout_sec=POLL)
    except ExternalShutdownException:
        pass

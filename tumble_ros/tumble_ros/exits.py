"""
How a command ends when its output's reader has gone, or when a signal asks it to stop.

A closed pipe (``command | head -1``): as Unix tools do, exit 141 (128 + SIGPIPE, what a shell
reports for a process killed by SIGPIPE), no traceback, no further output. Python ignores
SIGPIPE, so a write to a closed pipe raises BrokenPipeError instead; every command entry (the
installed executables through ``tumble_ros.__main__``, and the ``python -m tumble_ros.<module>``
entries) calls its ``main`` through :func:`call_closing_quietly`.

A stop (SIGINT, SIGTERM, SIGHUP) while an offline command works: :func:`interrupts` raises
:class:`Interrupted` where the program is, whatever the entry (``python -m tumble_ros
<command>`` runs it under the nodes' StopSignals, which only records a stop: the block takes
one recorded before it over), and the command ends with 128 + the signal (130, 143, 129). What
it was writing is removed on the way up (``except BaseException``/``finally``); a worker
process it started is ended by its owner. No tumble_ros imports: every layer with an entry
uses it.
"""
from __future__ import annotations

import atexit
from contextlib import contextmanager
import os
import signal
import sys
import threading
from typing import Any, Callable, Iterator

__all__ = ['BROKEN_PIPE_EXIT', 'call_closing_quietly', 'end_if_stopped', 'quick_exit',
           'quiet_broken_pipe', 'Interrupted', 'interrupts', 'STOP_SIGNALS']

#: Exit code after a closed pipe, as a shell reports a process killed by SIGPIPE.
BROKEN_PIPE_EXIT = 128 + signal.SIGPIPE


def call_closing_quietly(target: Callable[..., Any], argv: list[str], **options: Any) -> int:
    """Return ``target(argv, **options)``'s exit code (None: 0); a closed stdout gives 141."""
    try:
        code: int = target(argv, **options) or 0
        sys.stdout.flush()    # a closed pipe is seen here, not in the interpreter's exit
        return code
    except BrokenPipeError:
        return quiet_broken_pipe()


def quick_exit(code: int) -> None:
    """
    End the process with ``code`` without the interpreter's teardown; return if it cannot.

    How the main job ends (``tumble_ros.__main__``), and a command a stop signal ended
    (:func:`end_if_stopped`): the teardown of ~800-1,200 modules took 0.2-0.35 s at load 3,
    0.7-2 s at load 8 (2026-12-07), after the stop itself was served within 0.02 s.

    The atexit handlers run (coverage's, multiprocessing's) and stdout and stderr are flushed
    (a closed pipe: exit 141, as :func:`call_closing_quietly`), then ``os._exit``: the modules are
    not cleared nor their objects collected one by one, the OS frees the memory at once. It
    returns (the caller exits as usual) while another thread runs, which teardown would join.
    """
    if threading.active_count() > 1:
        return
    atexit._run_exitfuncs()     # as the interpreter's exit does, first
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (BrokenPipeError, ValueError):
        code = BROKEN_PIPE_EXIT
    except OSError:
        code = code or 1
    os._exit(code)


def end_if_stopped(code: int) -> int:
    """
    Return ``code``; after a stop :func:`interrupts` raised here, end the process with it now.

    For the commands' entries (``sys.exit(end_if_stopped(...))``): a stopped command ends
    without the interpreter's teardown (:func:`quick_exit`), the files it wrote closed or
    removed on the way up; otherwise the usual exit.
    """
    if _stopped_by is not None:
        quick_exit(code)
    return code


def quiet_broken_pipe() -> int:
    """After EPIPE: no more output (the interpreter's last flush would raise again); 141."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())
        except (OSError, ValueError):
            pass
    return BROKEN_PIPE_EXIT


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


#: The signals that stop a command, alike.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: The signal whose stop the last :func:`interrupts` raised in this process (None: none).
_stopped_by: int | None = None


@contextmanager
def interrupts() -> Iterator[None]:
    """
    Turn SIGINT, SIGTERM and SIGHUP into :class:`Interrupted` while the block runs.

    The first signal raises; any later one is ignored while the program cleans up (a local
    cluster stopping, a store's lock released, a temporary file removed). A KeyboardInterrupt
    raised by someone else's handler becomes Interrupted(SIGINT) too. The previous handlers are
    restored on exit. Outside the main thread (where Python runs no handler) it does nothing.

    A stop the previous handler recorded and did not serve (the nodes' StopSignals, which
    ``python -m tumble_ros <command>`` installs before the import: an object whose ``signum``
    is set) is raised on entry; a stop raised here is recorded there too (its exit then leaves
    the signals ignored, as here).

    Python runs a signal's handler wherever the main thread is, a finaliser or a garbage
    collector's callback included (Dask's ``GCDiagnosis``), where an exception is not raised
    but printed as "Exception ignored" (``sys.unraisablehook``): the stop was lost, and the
    run went on to its end with every later Ctrl-C ignored. Such an Interrupted is raised
    again where the program is (:func:`_raise_again`), silently.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    global _stopped_by
    _stopped_by = None
    previous = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    previous_hook = sys.unraisablehook
    recorder = getattr(previous[signal.SIGINT], '__self__', None)
    recorded = getattr(recorder, 'signum', None)

    def stop(signum, frame) -> None:
        _stopping(signum)
        if recorder is not None and hasattr(recorder, 'signum') and recorder.signum is None:
            recorder.signum = signum
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
        if isinstance(recorded, int):      # stopped before this block: served now
            stop(recorded, None)
        yield
    except KeyboardInterrupt:
        _stopping(signal.SIGINT)
        raise Interrupted(signal.SIGINT) from None
    except Interrupted:
        raise
    except BaseException:
        if _stopped_by is not None:
            # the stop was raised inside code that turned it into another error (matplotlib's
            # Agg draw gave "ValueError: Invalid bounding box" for a SIGTERM mid-frame): it is
            # still the stop
            raise Interrupted(_stopped_by) from None
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        raise
    finally:
        sys.unraisablehook = previous_hook
    for sig, handler in previous.items():
        signal.signal(sig, handler)


def _stopping(signum: int) -> None:
    """Record the stop by ``signum``; ignore the stop signals from now on (cleaning up)."""
    global _stopped_by
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    _stopped_by = signum


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

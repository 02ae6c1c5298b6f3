"""
How a command ends when its output's reader has gone (``command | head -1``).

As Unix tools do: exit 141 (128 + SIGPIPE, what a shell reports for a process killed by
SIGPIPE), no traceback, no further output. Python ignores SIGPIPE, so a write to a closed pipe
raises BrokenPipeError instead; every command entry (the installed executables through
``tumble_ros.__main__``, and the ``python -m tumble_ros.<module>`` entries) calls its ``main``
through :func:`call_closing_quietly`. No tumble_ros imports: every layer with an entry uses it.
"""
from __future__ import annotations

import os
import signal
import sys
from typing import Any, Callable

__all__ = ['BROKEN_PIPE_EXIT', 'call_closing_quietly', 'quiet_broken_pipe']

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


def quiet_broken_pipe() -> int:
    """After EPIPE: no more output (the interpreter's last flush would raise again); 141."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())
        except (OSError, ValueError):
            pass
    return BROKEN_PIPE_EXIT

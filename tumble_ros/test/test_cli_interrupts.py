"""A stop signal ends a command wherever it lands (tumble_ros.exits.interrupts); each long offline command stops promptly."""
from __future__ import annotations

import gc
import os
import signal
import sys
import time

import pytest

from tumble_ros.exits import Interrupted, interrupts, STOP_SIGNALS

#: Longest wait for a stop that should come at once [s].
PATIENCE = 10.0


@pytest.fixture(autouse=True)
def _handlers_restored():
    """Give this process its handlers back (a stop leaves the signals ignored: it is ending)."""
    before = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    yield
    for sig, handler in before.items():
        signal.signal(sig, handler)


def _busy_until_stopped() -> None:
    """Run Python bytecode (where signal handlers run) until stopped, or fail."""
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline:
        pass
    pytest.fail(f'no Interrupted within {PATIENCE} s')


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_a_stop_is_raised_where_the_program_is(signum):
    with pytest.raises(Interrupted) as raised, interrupts():
        os.kill(os.getpid(), signum)
        _busy_until_stopped()
    assert raised.value.exit_code == 128 + signum
    assert all(signal.getsignal(sig) is signal.SIG_IGN for sig in STOP_SIGNALS)  # (cleaning up)


def test_a_stop_that_lands_in_a_garbage_collectors_callback_is_raised_after_it(capfd):
    """
    Dask's GCDiagnosis is such a callback: Python printed "Exception ignored" and ran on.

    The signal is sent and handled inside the callback, which swallows the Interrupted; the
    command still stops, right after the callback, and prints nothing of it.
    """
    handled_inside = []

    def callback(phase, info) -> None:
        if phase != 'start' or handled_inside:
            return
        deadline = time.monotonic() + PATIENCE
        try:
            os.kill(os.getpid(), signal.SIGINT)   # the handler runs here, in the callback
            while time.monotonic() < deadline:
                pass
        except Interrupted:
            handled_inside.append(True)
            raise

    gc.callbacks.append(callback)
    try:
        with pytest.raises(Interrupted) as raised, interrupts():
            gc.collect()
            _busy_until_stopped()
    finally:
        gc.callbacks.remove(callback)
    assert handled_inside == [True]
    assert raised.value.signum == signal.SIGINT
    assert 'Exception ignored' not in capfd.readouterr().err


def test_other_unraisable_exceptions_are_still_reported(monkeypatch):
    """They go to the hook there was before (Python's prints them; pytest's warns)."""
    reported = []
    monkeypatch.setattr(sys, 'unraisablehook', reported.append)

    class Failing:
        def __del__(self) -> None:
            raise ValueError('a finaliser failed')

    with interrupts():
        Failing()
    assert [str(u.exc_value) for u in reported] == ['a finaliser failed']
    assert sys.unraisablehook == reported.append            # given back

"""
A stop signal ends a command wherever it lands (tumble_ros.exits.interrupts).

In this process: where the signal lands (a finaliser, a collector's callback), a stop recorded
before the block (``python -m tumble_ros``'s early StopSignals). In processes: each long step
of ``analyze`` (animating, drawing the figures, searching a photometry CSV) through both its
entries, ``python -m tumble_ros analyze`` (as ``ros2 run``) and ``python -m
tumble_ros.analysis``, ends on SIGINT and on SIGTERM with 128 + the signal and leaves no file.
"""
from __future__ import annotations

import gc
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from tumble_ros import exits
from tumble_ros.core import load_scenario
from tumble_ros.exits import end_if_stopped, Interrupted, interrupts, STOP_SIGNALS
from tumble_ros.nodes.shutdown import StopSignals
from tumble_ros.runs.offline import record_offline

#: Longest wait for a stop that should come at once [s].
PATIENCE = 10.0


@pytest.fixture(autouse=True)
def _handlers_restored(monkeypatch):
    """Give this process its handlers back (a stop leaves the signals ignored: it is ending)."""
    before = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    monkeypatch.setattr(exits, '_stopped_by', None)     # (end_if_stopped: not this process)
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


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_a_stop_that_code_turned_into_another_error_is_still_the_stop(signum):
    """
    A stop raised inside code that replaces the exception is still the stop (exit 128 + n).

    Seen once in the full suite: a SIGTERM while matplotlib's Agg renderer drew a frame of
    ``--animate`` came out as "ValueError: Invalid bounding box" and the command exited 1.
    """
    with pytest.raises(Interrupted) as raised, interrupts():
        try:
            os.kill(os.getpid(), signum)
            _busy_until_stopped()
        except Interrupted:
            raise ValueError('Invalid bounding box') from None
    assert raised.value.exit_code == 128 + signum


def test_an_error_without_a_stop_is_left_as_it_is():
    with pytest.raises(ValueError, match='not a stop'), interrupts():
        raise ValueError('not a stop')


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


def test_a_stop_recorded_before_the_block_is_raised_when_it_is_entered():
    """``python -m tumble_ros analyze``: a signal between the import and the command's block."""
    with StopSignals('analyze') as early:
        os.kill(os.getpid(), signal.SIGTERM)
        deadline = time.monotonic() + PATIENCE
        while not early.requested and time.monotonic() < deadline:
            pass
        with pytest.raises(Interrupted) as raised, interrupts():
            _busy_until_stopped()
    assert raised.value.exit_code == 128 + signal.SIGTERM


def test_a_stop_raised_in_the_block_is_recorded_by_the_early_handler_too():
    """Its exit then leaves the signals ignored: a second Ctrl-C does not break the ending."""
    with StopSignals('analyze') as early:
        with pytest.raises(Interrupted), interrupts():
            os.kill(os.getpid(), signal.SIGINT)
            _busy_until_stopped()
        assert early.signum == signal.SIGINT
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN


#: A command in a process of its own: stopped by SIGTERM (argument 'stop') or not; an object
#: that says so when the interpreter's teardown collects it.
ENDING = """
import os, signal, sys
from tumble_ros.exits import end_if_stopped, Interrupted, interrupts

class Collected:
    def __del__(self):
        sys.stderr.write('torn down')

kept = Collected()
code = 0
if sys.argv[1] == 'stop':
    try:
        with interrupts():
            os.kill(os.getpid(), signal.SIGTERM)
            while True:
                pass
    except Interrupted as stop:
        code = stop.exit_code
sys.exit(end_if_stopped(code))
"""


@pytest.mark.parametrize('how, code, teardown', [('stop', 143, ''), ('run', 0, 'torn down')])
def test_a_stopped_command_ends_without_the_interpreters_teardown(how, code, teardown):
    """It took 0.7-2 s at load 8 after a stop served in 0.02 s (docs/ros.md, "Signals")."""
    done = subprocess.run([sys.executable, '-c', ENDING, how], capture_output=True, text=True,
                          timeout=120)
    assert (done.returncode, done.stderr) == (code, teardown)


def test_a_command_that_was_not_stopped_ends_as_usual():
    assert end_if_stopped(3) == 3           # (a stop in this process would have ended it)


# ---- analyze's long steps, in processes of their own ----

CONFIG = Path(__file__).resolve().parents[1] / 'config'
#: Longest wait for a stopped command to end [s]: generous (a shared, loaded machine); the
#: latencies measured are in docs/ros.md ("Signals and exit codes").
STOPPED_WITHIN = 20.0
#: Longest wait for a step to start [s] (imports, numba's cache, the recording read).
STARTED_WITHIN = 180.0
#: The entries of analyze: (name of the log, ``module`` of processes.Process).
ENTRIES = {'python -m tumble_ros analyze': ('analyze', True),
           'python -m tumble_ros.analysis': ('analysis', 'tumble_ros.analysis')}


def _importtime_line(module: str) -> str:
    """Return what ``-X importtime`` prints when ``module`` is imported (a step's import)."""
    return f' {module}\n'


#: Each long step: its arguments (recording, CSV, output directory) and the line the command
#: prints once the step runs (its progress bar, or the import the step starts with).
STEPS = {
    'animate': (lambda rec, csv, out: [rec, '--animate', out / 'tumble.gif', '--frames', 2000],
                'of 2000 frames)'),
    'figures': (lambda rec, csv, out: [rec, '--figures', out / 'figures'],
                _importtime_line('tumble_ros.analysis.figures')),
    'photometry': (lambda rec, csv, out: ['--photometry', csv, '--period-range', 2, 100],
                   _importtime_line('tumble_ros.analysis.photometry_file')),
}


@pytest.fixture(scope='module')
def long_inputs(tmp_path_factory):
    """
    Return a recording and a photometry CSV whose steps last long (2,000 frames: minutes).

    Fig 9 over 200 yr (20,001 samples: ~3 s of drawing the figures alone); 300 points over 20
    days searched from 2 to 100 h (~12 s of CPU).
    """
    tmp = tmp_path_factory.mktemp('long')
    rec = record_offline(load_scenario(CONFIG / 'fig9.yaml').replace(duration=200.0),
                         tmp / 'fig9.mcap').output
    # uneven times and a noise-like term without a random generator (each test of this file
    # that draws numbers draws them from its own: test_random_inputs.py)
    k = np.arange(300)
    t = np.sort((k * 0.6180339887498949) % 1.0 * 20 * 24.0)
    mag = (15.0 + 0.3 * np.sin(2 * np.pi * t / 5.0) + 0.2 * np.sin(2 * np.pi * t / 13.7)
           + 0.01 * np.sin(12345.678 * k))
    csv = tmp / 'obs.csv'
    csv.write_text('time_h,mag\n' + ''.join(f'{a:.6f},{b:.5f}\n' for a, b in zip(t, mag)))
    return rec, csv


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
@pytest.mark.parametrize('entry', ENTRIES)
@pytest.mark.parametrize('step', STEPS)
def test_a_long_step_of_analyze_stops_at_once_and_leaves_no_file(spawn, tmp_path, long_inputs,
                                                                 step, entry, signum):
    """
    The signal is sent once the step runs; the command ends with 128 + it, one line, no file.

    They were ignored under ``python -m tumble_ros analyze`` (its early StopSignals records a
    stop that nothing served: a GIF animated on, the figures written, exit 0); the module entry
    died on SIGTERM leaving its temporary GIF, and exited 1 on SIGINT.
    """
    out = tmp_path / 'out'
    out.mkdir()
    arguments, running = STEPS[step]
    name, module = ENTRIES[entry]
    process = spawn(name, *arguments(*long_inputs, out), module=module,
                    env={**os.environ, 'PYTHONPROFILEIMPORTTIME': '1'})
    assert process.wait_for(running, STARTED_WITHIN), process.output[-3000:]
    process.signal(signum)
    assert process.wait(STOPPED_WITHIN) == 128 + signum, process.output[-3000:]
    assert f'analyze: stopped by {signal.Signals(signum).name}' in process.output
    assert [p for p in out.rglob('*') if not p.is_dir()] == []

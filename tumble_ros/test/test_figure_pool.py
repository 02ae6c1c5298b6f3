"""
The figures drawn in a FigurePool's workers (the main job's) against the figures drawn here.

The same files, byte for byte (names, order, PNG bytes), drawn by two processes (the worker
and a helper it forks) and by the worker alone, after the worker's warm-up figure, and when the
worker or a helper has died, with the recording handed over through shared memory or the pipe;
the errors of the in-process path (existing files, an error raised in a helper); and the main
job's process never imports matplotlib; a pool closed while it draws ends its worker and helpers.
"""
import dataclasses
import gc
import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from tumble_ros.analysis import analyze, figure_pool, load_recording
from tumble_ros.analysis.figure_files import FigureExistsError
from tumble_ros.analysis.figure_pool import FigurePool, SHARES
from tumble_ros.analysis.figures import FIGURES, write_figures
from tumble_ros.analysis.summary import SummaryParts
from tumble_ros.core import load_scenario
from tumble_ros.errors import AnalysisError
from tumble_ros.runs.offline import record_offline

CONFIG = Path(__file__).resolve().parents[1] / 'config'


@pytest.fixture(scope='module')
def recordings(tmp_path_factory):
    """fig9 over 200 yr (20,001 samples: the zoomed windows, a departing model), fig10."""
    tmp = tmp_path_factory.mktemp('pool')
    fig9 = record_offline(load_scenario(CONFIG / 'fig9.yaml').replace(duration=200.0),
                          tmp / 'fig9.mcap').output
    fig10 = record_offline(load_scenario(CONFIG / 'fig10.yaml'), tmp / 'fig10.mcap').output
    return [load_recording(fig9), load_recording(fig10)]


def _files(paths):
    return [(Path(p).name, Path(p).read_bytes()) for p in paths]


@pytest.fixture(scope='module')
def drawn_here(recordings, tmp_path_factory):
    """Return the files of each recording's figures drawn here (analyze's defaults), once."""
    tmp = tmp_path_factory.mktemp('here')
    return [_files(write_figures(rec, tmp / f'here{k}', analyze(rec)))
            for k, rec in enumerate(recordings)]


def test_every_figure_is_in_a_share_once():
    names = [n for share in SHARES for n in share]
    assert len(names) == len(set(names)) and set(names) == set(FIGURES)


@pytest.mark.parametrize('workers', [2, 1])
def test_the_pool_writes_the_same_files(tmp_path, recordings, drawn_here, workers):
    with FigurePool.start(workers) as pool:
        for k, rec in enumerate(recordings):
            there = pool.write_figures(rec, tmp_path / f'pool{k}', analyze(rec))
            assert [p.name for p in there] == [name for name, _ in drawn_here[k]]
            assert _files(there) == drawn_here[k]
    names = [name for name, _ in drawn_here[1]]
    assert 'omega_windows.png' not in names and 'impact_0_id0.png' in names   # fig10
    assert len([n for n, _ in drawn_here[0] if n.endswith('.png')]) == 5  # fig9: 5, windows too


@pytest.mark.parametrize('shared_bytes, way', [(figure_pool.SHARED_BYTES, '_draw_shared'),
                                               (0, '_draw_shares'), (4096, '_draw_shares')])
def test_the_recording_goes_through_shared_memory_when_it_fits(tmp_path, recordings,
                                                               drawn_here, shared_bytes, way):
    """Shared memory (the default), none, too small (the pipe): the same files."""
    rec = recordings[0]
    summary = analyze(rec)
    with FigurePool.start(2, shared_bytes) as pool:
        submitted = []
        submit = pool._executor.submit

        def spy(function, *args):
            submitted.append(function.__name__)
            return submit(function, *args)
        pool._executor.submit = spy
        there = pool.write_figures(rec, tmp_path / 'pool', summary)
        again = pool.write_figures(recordings[1], tmp_path / 'again', analyze(recordings[1]))
    assert submitted == [way, way]
    assert _files(there) == drawn_here[0] and _files(again) == drawn_here[1]


def test_summary_parts_are_the_summarys_values(recordings):
    """What the figures take from the summary, computed alone, as analyze computes it."""
    for rec in recordings:
        summary = analyze(rec, n_peaks=3)
        parts = SummaryParts(rec, 3)
        assert parts.comparator is not None and parts.theory and parts.spectrum is not None
        assert _same(parts.comparator, summary.comparator)
        assert _same(parts.theory, summary.theory)
        assert _same(parts.spectrum, summary.spectrum)


def _same(a, b):
    """Equal field by field, arrays bit for bit (NaN where NaN)."""
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, (tuple, list)):
        return type(a) is type(b) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a, b, equal_nan=a.dtype.kind == 'f')
    return a == b or (a != a and b != b)        # (NaN: equal here)


def test_the_figures_started_before_the_analysis_are_the_same(tmp_path, recordings,
                                                              drawn_here):
    """Begun with the summary's parts (the main job), finished after analyze: the same files."""
    rec = recordings[0]
    peaks = 3                   # not analyze's default: the spectrum's markers differ
    summary = analyze(rec, n_peaks=peaks)
    here = write_figures(rec, tmp_path / 'here', summary)
    assert _files(here) != drawn_here[0]        # (else this test could not tell them apart)
    with FigurePool.start(2) as pool:
        pending = pool.begin(rec, SummaryParts(rec, peaks))
        other = pool.begin(recordings[1], SummaryParts(recordings[1]))  # beside it: the pipe
        assert _files(pool.finish(pending, tmp_path / 'pool')) == _files(here)
        assert _files(pool.finish(other, tmp_path / 'other')) == drawn_here[1]


def test_the_worker_draws_with_its_warm_state_frozen_and_the_collector_off(
        tmp_path, recordings, drawn_here):
    """Its warm-up frozen, the collector off from its first drawing on (the same bytes)."""
    rec = recordings[1]
    summary = analyze(rec)
    with FigurePool.start(2) as pool:
        ask = pool._executor.submit
        assert ask(gc.isenabled).result() and ask(gc.get_freeze_count).result() > 0
        there = pool.write_figures(rec, tmp_path / 'pool', summary)
        assert not ask(gc.isenabled).result()
        again = pool.write_figures(rec, tmp_path / 'again', summary)
    assert gc.isenabled()                       # this process: as it was
    assert _files(there) == drawn_here[1] and _files(again) == drawn_here[1]


def test_the_pool_refuses_a_negative_shared_size():
    with pytest.raises(ValueError, match='shared_bytes: must be >= 0, got -1'):
        FigurePool.start(2, -1)


def test_existing_files_are_refused_as_in_the_process(tmp_path, recordings):
    rec = recordings[1]
    summary = analyze(rec)
    write_figures(rec, tmp_path, summary)
    with FigurePool.start(2) as pool:
        with pytest.raises(FigureExistsError, match='not overwritten'):
            pool.write_figures(rec, tmp_path, summary)
        assert len(pool.write_figures(rec, tmp_path, summary, overwrite=True)) >= 5


def test_the_figures_of_a_dead_worker_are_drawn_here(tmp_path, recordings, drawn_here):
    rec = recordings[1]
    summary = analyze(rec)
    pool = FigurePool.start(2)
    try:
        pool.write_figures(rec, tmp_path / 'before', summary)       # the workers are up
        for pid in list(pool._executor._processes):
            os.kill(pid, signal.SIGKILL)
        there = pool.write_figures(rec, tmp_path / 'after', summary)
    finally:
        pool.close()
    assert _files(there) == drawn_here[1]


def _in_a_helper(then):
    """Patch figure_pool._draw so that a helper (a child of the worker) runs ``then``."""
    main, real = os.getpid(), figure_pool._draw

    def draw(rec, summary, share):
        if os.getppid() != main and os.getpid() != main:      # a helper, not the worker
            then()
        return real(rec, summary, share)
    return draw


def test_the_share_of_a_dead_helper_is_drawn_by_the_worker(tmp_path, recordings, drawn_here,
                                                           monkeypatch):
    rec = recordings[1]
    summary = analyze(rec)
    died = tmp_path / 'a helper died'

    def die():
        died.write_text('')
        os._exit(3)
    monkeypatch.setattr(figure_pool, '_draw', _in_a_helper(die))
    with FigurePool.start(2) as pool:           # the worker inherits the patched module
        there = pool.write_figures(rec, tmp_path / 'pool', summary)
    monkeypatch.undo()
    assert died.exists()
    assert _files(there) == drawn_here[1]


def test_an_error_in_a_helper_is_raised_as_in_the_process(tmp_path, recordings, monkeypatch):
    def fail():
        raise AnalysisError('cannot draw this share')
    monkeypatch.setattr(figure_pool, '_draw', _in_a_helper(fail))
    with FigurePool.start(2) as pool:
        with pytest.raises(AnalysisError, match='cannot draw this share'):
            pool.write_figures(recordings[1], tmp_path, analyze(recordings[1]))
    assert not list(tmp_path.glob('*.png'))


def test_the_main_job_never_imports_matplotlib(tmp_path):
    scenario = tmp_path / 'short.yaml'
    scenario.write_text('sim:\n  ros__parameters:\n    duration: 0.2\n'
                        '    output_interval: 0.002\n')
    code = ('import sys\nfrom tumble_ros.__main__ import main\n'
            f'code = main([{str(scenario)!r}])\n'
            "print('matplotlib loaded:', 'matplotlib' in sys.modules)\nsys.exit(code)\n")
    done = subprocess.run([sys.executable, '-c', code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert 'matplotlib loaded: False' in done.stdout
    figures = sorted(p.name for p in tmp_path.glob('recordings/short_*_figures/*.png'))
    assert 'omega.png' in figures and 'error.png' in figures


def _gone(pid: int) -> bool:
    """Tell whether process ``pid`` has ended (a zombie that nobody reaped has ended too)."""
    try:
        return Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0] == 'Z'
    except (FileNotFoundError, ProcessLookupError):
        return True


def test_a_pool_closed_while_it_draws_ends_its_worker_and_helpers(tmp_path, monkeypatch):
    """
    The main job's analysis stopped by a signal while the figures are drawn: no wait for them.

    The drawing here never ends (an hour); close waited for it (shutdown(wait=True)).
    """
    rec = load_recording(Path(__file__).resolve().parent / 'data' / 'golden.mcap')
    summary = analyze(rec)
    drawing = tmp_path / 'drawing'

    def draw_for_an_hour(rec, summary, share):
        with open(drawing, 'a') as pids:
            pids.write(f'{os.getpid()}\n')
        time.sleep(3600)
    monkeypatch.setattr(figure_pool, '_draw', draw_for_an_hour)
    pool = FigurePool.start(2)               # the worker inherits the patched module
    pool.begin(rec, summary)
    deadline = time.monotonic() + 120
    while (not drawing.exists() or len(drawing.read_text().split()) < 2) \
            and time.monotonic() < deadline:
        time.sleep(0.05)
    pids = [int(pid) for pid in drawing.read_text().split()]
    assert len(pids) == 2                    # the worker and its helper, drawing
    closing = threading.Thread(target=pool.close, daemon=True)
    closing.start()
    closing.join(60)
    deadline = time.monotonic() + 30
    try:
        assert not closing.is_alive()
        while not all(_gone(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.05)        # (the helper's SIGKILL is delivered as the worker ends)
        assert [pid for pid in pids if not _gone(pid)] == []
    finally:
        for pid in pids:
            if not _gone(pid):
                os.kill(pid, signal.SIGKILL)

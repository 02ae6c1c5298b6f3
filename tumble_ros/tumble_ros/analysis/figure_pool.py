"""
The figures drawn in a worker process started ahead of time (the main job's figures).

Drawing the five figures of the Fig 9 run costs ~1.7 s of CPU in one process, 0.6 s of which
is importing matplotlib and the first use of its fonts and mathtext parser. The main job
(``python -m tumble_ros``) knows from the start that it will draw them: it starts a
:class:`FigurePool` before the recording, whose worker (forked from the main process, so
numpy, numba, scipy and the analysis are already loaded) imports the figures module and draws
a throw-away figure (:func:`~.figures.warm_up`) on the other core while the main process
simulates and records. :meth:`FigurePool.write_figures` then hands the worker the recording
and its summary (pickled once, ~40 MB and ~0.05 s for Fig 9); the worker forks one helper per
further share of :data:`SHARES` (each inherits the warm matplotlib and the recording: no
second warm-up, no second copy sent), draws the first share itself, collects the helpers'
drawings through pipes, and the main process writes the PNG bytes in the usual order: the same
bytes as drawn in one process (tests/test_figure_pool.py). Two shares, two cores drawing.

This module imports no matplotlib: the main process never loads it. Without ``fork`` (not
POSIX) :meth:`FigurePool.start` returns None and the figures are drawn in the process. If the
worker dies (:class:`~concurrent.futures.process.BrokenProcessPool`) the figures are drawn in
the process; a helper that dies has its share drawn by the worker. Exceptions raised while
drawing are raised by :meth:`FigurePool.write_figures`, as in the process. The worker and its
helpers ignore SIGINT (the main process handles it and ends the pool): a pool closed while a
drawing is still running (the main process stopped by a signal, or failed) ends its worker at
once with SIGTERM, on which the worker kills its helpers (:func:`_end_drawing`), instead of
waiting for a drawing nobody will write. :meth:`FigurePool.begin`
starts the drawing and :meth:`FigurePool.finish` writes it: the main job begins with the
summary's parts (:class:`~.summary.SummaryParts`, computed by the drawing processes) and
analyses while the figures are drawn. The worker freezes its warm state and draws with the
garbage collector off (:func:`_collector_off`).

The recording and its summary reach the worker through memory shared since the fork
(:data:`SHARED_BYTES` of an anonymous shared mapping, untouched until used): pickled with
their arrays out of band (protocol 5), the arrays' bytes copied into that memory and the rest
sent through the executor's pipe; the worker's arrays are views of the shared memory (no
copy), and its helpers see the same pages. ~0.03 s for Fig 9's 40 MB instead of the ~0.14 s of
the pipe (its feeder thread and 64-kB writes). Larger, they take the pipe as before: the same
drawings.
"""
from __future__ import annotations

from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
import gc
import mmap
import multiprocessing
import os
from pathlib import Path
import pickle
import signal
from typing import Any, TYPE_CHECKING

from .figure_files import Drawing, write_files

if TYPE_CHECKING:
    from .recording import Recording
    from .summary import AnalysisSummary, SummaryParts

    #: What the figures take their summary's values from.
    Summary = AnalysisSummary | SummaryParts

__all__ = ['FigurePool', 'PendingFigures', 'SHARED_BYTES', 'SHARES', 'WORKERS']

#: Processes drawing at once (the machine measured has two cores; the main process waits).
WORKERS = 2
#: The figures of each drawing process (names of :data:`~.figures.FIGURES`), about equal
#: shares of the drawing time of the Fig 9 run: the windows, wy-vs-wx and the spectrum
#: 1.07-1.12 s against omega, error and the impacts 0.99-1.01 s (CPU, load 4.6-4.9,
#: 2026-12-04 22:08; the most even split measured). The worker draws the first, a helper each
#: other; a figure in no share gets a helper of its own; with one drawing process the worker
#: draws them all.
SHARES: tuple[tuple[str, ...], ...] = (('omega_windows', 'wy_vs_wx', 'spectrum'),
                                       ('omega', 'error', 'impacts'))


#: Bytes of memory shared with the worker for the pickled recording and summary (virtual until
#: used: pages are allocated as they are written; Fig 9's 2000 yr take 42 MB).
SHARED_BYTES = 512 << 20
#: The worker's view of that memory (set by :func:`_warm`).
_shared: mmap.mmap | None = None


def _warm(shared: mmap.mmap | None = None) -> None:
    """
    Initialise a worker: SIGINT ignored, SIGTERM ends its helpers too, fonts loaded, frozen.

    The figures module is imported and its fonts loaded (:func:`~.figures.warm_up`).
    """
    global _shared, _worker
    _shared = shared
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _end_drawing)
    from . import figures
    figures.warm_up()
    _worker = True
    gc.freeze()         # the warm state: never traversed by the collector (no pass over it now)


#: Whether this process is a worker (:func:`_warm` ran).
_worker = False
#: The helpers a worker forked that are still drawing (process ids).
_helpers: set[int] = set()


def _end_drawing(signum: int, _frame: Any) -> None:
    """
    End a worker on SIGTERM (its pool closed while it draws): its helpers first (SIGKILL).

    Helpers hold nothing to finalise (drawings in memory, a pipe to this worker); without this
    they would draw on, orphaned, until their share is done.
    """
    for pid in _helpers:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    os._exit(128 + signum)


def _collector_off() -> None:
    """
    In a worker: collect what an earlier drawing left, then turn the collector off.

    Drawing makes ~10^5 objects in cycles (figures, axes, artists, texts): the collector's
    passes over them took ~0.1 s of each drawing process's ~1 s for the Fig 9 run (the same
    PNG bytes without them, tests/test_figure_pool.py). A drawing's garbage (tens of MB) is
    then collected when the worker's next drawing starts; a helper, forked while the collector
    is off, ends after its share. Elsewhere (a share drawn in the main process) nothing changes.
    """
    if _worker:
        gc.collect()
        gc.disable()


def _ready() -> bool:
    return True


#: What a worker returns: name -> drawings of its share, and the files' order of all figures.
_Drawn = tuple[dict[str, list['Drawing']], tuple[str, ...]]


def _draw(rec: Recording, summary: Summary, share: tuple[str, ...]) -> _Drawn:
    """
    Draw the figures of ``share`` in this worker.

    ``share``: names of :data:`~.figures.FIGURES`, ``('*',)`` for those in no share of
    :data:`SHARES`, ``('**',)`` for all.
    """
    from .figures import draw_figures, figure_order
    return draw_figures(rec, summary, _names(share)), figure_order()


def _names(share: tuple[str, ...]) -> tuple[str, ...]:
    """Return the figure names of a share (see :func:`_draw`), in the files' order."""
    from .figures import figure_order
    order = figure_order()
    if share == ('**',):
        return order
    if share == ('*',):
        return tuple(n for n in order if not any(n in s for s in SHARES))
    return tuple(n for n in order if n in share)


def _helper(rec: Recording, summary: Summary, share: tuple[str, ...]
            ) -> tuple[int, int]:
    """Fork a helper that draws ``share`` and writes (ok, drawn or error) pickled to a pipe."""
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid:
        os.close(write_fd)
        _helpers.add(pid)
        return pid, read_fd
    try:                            # the helper: never returns into the worker's loop
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _helpers.clear()
        os.close(read_fd)
        try:
            payload = pickle.dumps((True, _draw(rec, summary, share)))
        except BaseException as err:  # noqa: BLE001 - handed to the worker, raised there
            try:
                payload = pickle.dumps((False, err))
            except Exception:  # noqa: BLE001 - an error that does not pickle: its text
                payload = pickle.dumps((False, RuntimeError(f'{type(err).__name__}: {err}')))
        with os.fdopen(write_fd, 'wb') as out:
            out.write(payload)
    finally:
        os._exit(0)


def _collect(pid: int, read_fd: int) -> tuple[bool, Any] | None:
    """Return what the helper ``pid`` sent (None if it died before sending it); reap it."""
    with os.fdopen(read_fd, 'rb') as pipe:
        data = pipe.read()
    os.waitpid(pid, 0)
    _helpers.discard(pid)
    return pickle.loads(data) if data else None


def _draw_shares(rec: Recording, summary: Summary,
                 shares: tuple[tuple[str, ...], ...]) -> _Drawn:
    """In the worker: a forked helper per share but the first, which is drawn here."""
    _collector_off()
    shares = tuple(share for share in shares if _names(share))
    if not shares:
        return {}, _names(('**',))
    helpers = []
    try:
        for share in shares[1:]:
            helpers.append((share, *_helper(rec, summary, share)))
        drawn, order = _draw(rec, summary, shares[0])
    finally:
        sent = [(share, _collect(pid, read_fd)) for share, pid, read_fd in helpers]
    for share, result in sent:
        if result is None:          # the helper died: its share is drawn here
            part, _ = _draw(rec, summary, share)
        elif not result[0]:
            raise result[1]
        else:
            part, _ = result[1]
        drawn.update(part)
    return drawn, order


#: Where each out-of-band buffer lies in the shared memory: (offset, bytes).
_Spans = list[tuple[int, int]]
#: Offsets of the buffers in the shared memory are multiples of this [bytes] (numpy's arrays
#: stay aligned as allocated).
_ALIGN = 64


def _to_shared(shared: mmap.mmap, payload: Any) -> tuple[bytes, _Spans] | None:
    """
    Pickle ``payload`` with its buffers (numpy's arrays) copied into ``shared``.

    Return (the pickle without them, where each lies), or None when they do not fit.
    """
    buffers: list[pickle.PickleBuffer] = []
    head = pickle.dumps(payload, protocol=5, buffer_callback=buffers.append)
    raws = [buffer.raw() for buffer in buffers]
    spans, at = [], 0
    for raw in raws:
        spans.append((at, raw.nbytes))
        at += -(-raw.nbytes // _ALIGN) * _ALIGN
    if at > len(shared):
        return None
    with memoryview(shared) as view:
        for (start, size), raw in zip(spans, raws):
            view[start:start + size] = raw
    return head, spans


def _draw_shared(head: bytes, spans: _Spans, shares: tuple[tuple[str, ...], ...]) -> _Drawn:
    """:func:`_draw_shares` of the recording and summary whose arrays are in shared memory."""
    if _shared is None:
        raise RuntimeError('figure pool: no shared memory in this worker')
    view = memoryview(_shared)      # the arrays are views of it: kept while they live
    rec, summary = pickle.loads(head, buffers=[view[a:a + n] for a, n in spans])
    return _draw_shares(rec, summary, shares)


@dataclass(frozen=True)
class PendingFigures:
    """Figures being drawn (:meth:`FigurePool.begin`): what they are drawn from, their future."""

    rec: Recording
    summary: Summary
    future: Future[_Drawn] | None     # None: the worker had died; drawn in the process


class FigurePool:
    """A worker process that draws figures (see the module docstring); a context manager."""

    def __init__(self, executor: ProcessPoolExecutor, workers: int,
                 shared: mmap.mmap | None = None,
                 processes: tuple[multiprocessing.process.BaseProcess, ...] = (),
                 given: tuple[Future[Any], ...] = ()) -> None:
        self._executor = executor
        self.workers = workers
        self._shared = shared
        self._in_shared: Future[_Drawn] | None = None  # the drawing using the shared memory
        self._processes = processes     # the executor's worker, ended by close if it draws
        self._given: list[Future[Any]] = list(given)    # what the worker was given

    @classmethod
    def start(cls, workers: int = WORKERS, shared_bytes: int = SHARED_BYTES
              ) -> FigurePool | None:
        """
        Fork the worker now (it warms up at once); None where fork is unavailable.

        ``workers``: processes drawing at once (1: the worker alone; more: the shares of
        :data:`SHARES`). Call it before any thread that must not be forked starts (rclpy's
        context, DDS). ``shared_bytes``: size of the memory shared with the worker for the
        recording (0: none; the executor's pipe).
        """
        if workers < 1:
            raise ValueError(f'workers: must be >= 1, got {workers}')
        if shared_bytes < 0:
            raise ValueError(f'shared_bytes: must be >= 0, got {shared_bytes}')
        try:
            context = multiprocessing.get_context('fork')
        except ValueError:
            return None
        try:        # shared with the worker through the fork (see the module docstring)
            shared: mmap.mmap | None = mmap.mmap(-1, shared_bytes) if shared_bytes else None
        except (OSError, ValueError):   # no such mapping here: the pipe
            shared = None
        executor = ProcessPoolExecutor(max_workers=1, mp_context=context, initializer=_warm,
                                       initargs=(shared,))
        before = set(multiprocessing.active_children())
        ready = executor.submit(_ready)     # starts the worker now (forked in submit)
        return cls(executor, workers, shared,
                   tuple(p for p in multiprocessing.active_children() if p not in before),
                   (ready,))

    def write_figures(self, rec: Recording, out_dir: str | os.PathLike[str],
                      summary: Summary, *, overwrite: bool = False) -> list[Path]:
        """
        :func:`~.figures.write_figures`, the figures drawn in the worker: the same files.

        Drawn in shares (:data:`SHARES`) by the worker and its helpers, written here in order
        (:func:`~.figure_files.write_files`: all drawn before any is written). Exceptions
        raised while drawing (AnalysisError, ...) are raised here, as in the process; the
        figures of a worker that died are drawn here. :meth:`begin` and :meth:`finish` in
        one call.
        """
        return self.finish(self.begin(rec, summary), out_dir, overwrite=overwrite)

    def begin(self, rec: Recording, summary: Summary) -> PendingFigures:
        """
        Start drawing every figure in the worker and its helpers; :meth:`finish` writes them.

        ``summary``: the recording's :class:`~.summary.AnalysisSummary`, or its
        :class:`~.summary.SummaryParts` (what the figures take from it, computed by the drawing
        processes as :func:`~.summary.analyze` computes it): then the figures are drawn while
        this process analyses (the main job), the same bytes (tests/test_figure_pool.py).
        """
        shares: tuple[tuple[str, ...], ...] = (SHARES + (('*',),) if self.workers > 1
                                               else (('**',),))
        try:
            return PendingFigures(rec, summary, self._submit(rec, summary, shares))
        except BrokenProcessPool:   # the worker died: drawn here, by finish
            return PendingFigures(rec, summary, None)

    def finish(self, pending: PendingFigures, out_dir: str | os.PathLike[str], *,
               overwrite: bool = False) -> list[Path]:
        """Wait for the figures :meth:`begin` started; write them (as :meth:`write_figures`)."""
        return write_files(self._drawn(pending), out_dir, overwrite)

    def draw(self, rec: Recording, summary: Summary) -> list[Drawing]:
        """Draw every figure in the worker and its helpers; return them in the files' order."""
        return self._drawn(self.begin(rec, summary))

    def _drawn(self, pending: PendingFigures) -> list[Drawing]:
        """Return the drawings of ``pending`` in the files' order (here if the worker died)."""
        try:
            if pending.future is None:
                raise BrokenProcessPool('figure pool: the worker died before the drawing')
            drawn, order = pending.future.result()
        except BrokenProcessPool:   # the worker died: drawn here
            drawn, order = _draw(pending.rec, pending.summary, ('**',))
        return [drawing for name in order for drawing in drawn.get(name, [])]

    def _submit(self, rec: Recording, summary: Summary,
                shares: tuple[tuple[str, ...], ...]) -> Future[_Drawn]:
        """
        Hand the drawing to the worker: through the shared memory if they fit, else the pipe.

        The shared memory holds one drawing's arrays: while an earlier drawing that uses it is
        not done (:meth:`begin` twice before :meth:`finish`), the pipe.
        """
        if self._shared is not None and (self._in_shared is None or self._in_shared.done()):
            shared = _to_shared(self._shared, (rec, summary))
            if shared is not None:
                self._in_shared = self._executor.submit(_draw_shared, *shared, shares)
                self._given.append(self._in_shared)
                return self._in_shared
        future = self._executor.submit(_draw_shares, rec, summary, shares)
        self._given.append(future)
        return future

    def close(self) -> None:
        """
        End the worker; pending work is cancelled.

        A worker still busy (a drawing :meth:`finish` did not wait for, the warm-up) is ended
        at once (SIGTERM: its helpers too, :func:`_end_drawing`), not waited for: its drawing
        would be written nowhere (the main process stopped by a signal, or failed).
        """
        if any(not future.done() for future in self._given):
            for process in self._processes:
                process.terminate()
        self._executor.shutdown(wait=True, cancel_futures=True)
        if self._shared is not None:
            self._shared.close()
            self._shared = None

    def __enter__(self) -> FigurePool:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

"""
The figures drawn in worker processes started ahead of time (the main job's figures).

Drawing the five figures of the Fig 9 run costs ~1.7 s of CPU in one process, 0.6 s of which
is importing matplotlib and the first use of its fonts and mathtext parser. The main job
(``python -m tumble_ros``) knows from the start that it will draw them: it starts a
:class:`FigurePool` before the recording, whose workers (forked from the main process, so
numpy, numba, scipy and the analysis are already loaded) import the figures module and draw a
throw-away figure (:func:`~.figures.warm_up`) on the other core while the main process
simulates and records. :meth:`FigurePool.write_figures` then hands each worker its share of
the figures (:data:`SHARES`, the recording and its summary pickled once per worker, ~40 MB
and ~0.05 s for Fig 9) and writes the PNG bytes they return, in the usual order: the same
bytes as drawn in one process (tests/test_figure_pool.py).

This module imports no matplotlib: the main process never loads it. Without ``fork`` (not
POSIX) :meth:`FigurePool.start` returns None and the figures are drawn in the process. A worker
that dies (:class:`~concurrent.futures.process.BrokenProcessPool`) is not retried: its figures
are drawn in the process. The workers ignore SIGINT (the main process handles it and ends
the pool).
"""
from __future__ import annotations

from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
import multiprocessing
import os
from pathlib import Path
import signal
from typing import Any, TYPE_CHECKING

from .figure_files import Drawing, write_files

if TYPE_CHECKING:
    from .recording import Recording
    from .summary import AnalysisSummary

__all__ = ['FigurePool', 'SHARES', 'WORKERS']

#: Worker processes (the machine measured has two cores; the main process waits meanwhile).
WORKERS = 2
#: The figures of each worker (names of :data:`~.figures.FIGURES`), about equal shares of the
#: drawing time of the Fig 9 run, the longer first (it is handed over first): the windows,
#: wy-vs-wx and the spectrum 1.1 s against omega, error and the impacts 0.85 s (CPU, warm
#: workers, 2026-12-04). A pool of one worker draws them all; a figure in no share is drawn by
#: a third task.
SHARES: tuple[tuple[str, ...], ...] = (('omega_windows', 'wy_vs_wx', 'spectrum'),
                                       ('omega', 'error', 'impacts'))


def _warm() -> None:
    """Initialise a worker: SIGINT ignored, the figures module imported, fonts loaded."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from . import figures
    figures.warm_up()


def _ready() -> bool:
    return True


#: What a worker returns: name -> drawings of its share, and the files' order of all figures.
_Drawn = tuple[dict[str, list['Drawing']], tuple[str, ...]]


def _draw(rec: Recording, summary: AnalysisSummary, share: tuple[str, ...]) -> _Drawn:
    """
    Draw the figures of ``share`` in this worker.

    ``share``: names of :data:`~.figures.FIGURES`, ``('*',)`` for those in no share of
    :data:`SHARES`, ``('**',)`` for all.
    """
    from .figures import draw_figures, figure_order
    order = figure_order()
    if share == ('**',):
        names = order
    elif share == ('*',):
        names = tuple(n for n in order if not any(n in s for s in SHARES))
    else:
        names = tuple(n for n in share if n in order)
    return draw_figures(rec, summary, names), order


class FigurePool:
    """Worker processes that draw figures (see the module docstring); a context manager."""

    def __init__(self, executor: ProcessPoolExecutor, workers: int) -> None:
        self._executor = executor
        self.workers = workers

    @classmethod
    def start(cls, workers: int = WORKERS) -> FigurePool | None:
        """
        Fork ``workers`` processes now (they warm up at once); None where fork is unavailable.

        Call it before any thread that must not be forked starts (rclpy's context, DDS).
        """
        if workers < 1:
            raise ValueError(f'workers: must be >= 1, got {workers}')
        try:
            context = multiprocessing.get_context('fork')
        except ValueError:
            return None
        executor = ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                       initializer=_warm)
        executor.submit(_ready)     # with fork, all the workers start at the first task
        return cls(executor, workers)

    def write_figures(self, rec: Recording, out_dir: str | os.PathLike[str],
                      summary: AnalysisSummary, *, overwrite: bool = False) -> list[Path]:
        """
        :func:`~.figures.write_figures`, the figures drawn in the workers: the same files.

        Drawn in the workers' shares (:data:`SHARES`), written here in the usual order
        (:func:`~.figure_files.write_files`: all drawn before any is written). Exceptions
        raised while drawing (AnalysisError, ...) are raised here, as in the process; the
        figures of a worker that died are drawn here.
        """
        return write_files(self.draw(rec, summary), out_dir, overwrite)

    def draw(self, rec: Recording, summary: AnalysisSummary) -> list[Drawing]:
        """Draw every figure in the workers; return the drawings in the files' order."""
        futures: list[tuple[tuple[str, ...], Future[_Drawn] | None]] = []
        shares: tuple[tuple[str, ...], ...] = (SHARES + (('*',),) if self.workers > 1
                                               else (('**',),))
        for share in shares:
            try:
                futures.append((share, self._executor.submit(_draw, rec, summary, share)))
            except (BrokenProcessPool, RuntimeError):   # a worker died, or the pool is closed
                futures.append((share, None))
        drawn: dict[str, list[Drawing]] = {}
        order: tuple[str, ...] = ()
        for done, future in futures:
            try:
                if future is None:
                    raise BrokenProcessPool('not submitted')
                part, order = future.result()
            except BrokenProcessPool:
                part, order = _draw(rec, summary, done)
            drawn.update(part)
        return [drawing for name in order for drawing in drawn.get(name, [])]

    def close(self) -> None:
        """End the workers (those drawing finish first); pending work is cancelled."""
        self._executor.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> FigurePool:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

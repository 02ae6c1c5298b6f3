"""
The ensemble loop: many bodies, each with its own segments (impact sequences).

Bodies share the method (``cfg``) and the extra torques (``extra``); each has its segments'
problems ``probs[seg_ptr[b]:seg_ptr[b+1]]`` (layout :data:`~.layout.PR`) and edges ``seg_t``,
its state ``states[b]`` and Euler track ``tracks[b]``. ``core/propagation/ensemble.py`` builds
the arrays and runs blocks of bodies in threads (the loops release the GIL).
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import jit
from tumble_ros.core.kernels.layout import Array, Extra, ST, STATUS
from tumble_ros.core.kernels.stepping import advance, emit, seg_init

__all__ = ['body_advance', 'ensemble_advance', 'ensemble_init', 'LOOP_FUNCTIONS']

#: The functions :mod:`.methods` copies per method (they call the :mod:`.stepping` loop).
LOOP_FUNCTIONS = ('body_advance', 'ensemble_advance', 'ensemble_init')


@jit
def body_advance(extra: Extra, cfg: Array, probs: Array, seg_t: Array, first: int, last: int,
                 cur: int, st: Array, track: Array, t_stop: float, t_out: Array, y_out: Array,
                 e_out: Array, k: int) -> tuple[int, int, int]:
    """
    Advance one body through its segments probs[first:last] until t >= t_stop.

    A new segment starts where the propagator would start it (``Propagator.advance_to``).
    Returns (cur, k, steps).
    """
    steps = 0
    while True:
        k = emit(probs[cur], extra, cfg, st, track, t_out, y_out, e_out, k)
        if st[ST.T] >= t_stop or st[ST.STATUS] == STATUS.FAILED:
            break
        if st[ST.STATUS] == STATUS.FINISHED:
            if cur + 1 >= last:
                break
            cur += 1
            seg_init(probs[cur], extra, cfg, st, st[ST.T], seg_t[cur, 1])
            continue
        k, n, _ = advance(probs[cur], extra, cfg, st, track, t_stop, t_out, y_out, e_out, k,
                          np.inf)
        steps += n
    return cur, k, steps


@jit
def ensemble_advance(extra: Extra, cfg: Array, probs: Array, seg_t: Array,
                     seg_ptr: npt.NDArray[np.int64], cur: npt.NDArray[np.int64], states: Array,
                     tracks: Array, t_stop: float, t_out: Array, y_out: Array, e_out: Array,
                     k_out: npt.NDArray[np.int64], steps_out: npt.NDArray[np.int64], b0: int,
                     b1: int) -> None:
    """Run :func:`body_advance` for bodies b0 .. b1-1 (releases the GIL)."""
    for b in range(b0, b1):
        c, k, n = body_advance(extra, cfg, probs, seg_t, seg_ptr[b], seg_ptr[b + 1], cur[b],
                               states[b], tracks[b], t_stop, t_out, y_out[b], e_out[b], k_out[b])
        cur[b] = c
        k_out[b] = k
        steps_out[b] += n


@jit
def ensemble_init(extra: Extra, cfg: Array, probs: Array, seg_t: Array,
                  seg_ptr: npt.NDArray[np.int64], states: Array, b0: int, b1: int) -> None:
    """seg_init of the first segment of bodies b0 .. b1-1 (their states hold y0)."""
    for b in range(b0, b1):
        s = seg_ptr[b]
        seg_init(probs[s], extra, cfg, states[b], seg_t[s, 0], seg_t[s, 1])

"""A progress display for long runs on a stream (stderr): a bar on a terminal, else lines."""
from __future__ import annotations

import math
import sys
import time

from tumble_ros.core.units import from_years

__all__ = ['ProgressBar']


class ProgressBar:
    """
    Progress display of a long run on a stream (stderr).

    A bar redrawn in place on a terminal, a line every 10 % otherwise. Call with (fraction
    done, t [yr], body-steps so far). ``by='time'``: the fraction is of the simulated time
    span (every body advancing together); ``by='bodies'``: of the bodies (a chunked run, where
    chunks of bodies finish one after the other). ``total_time`` [yr]; times are shown in
    ``unit`` (the scenario's ``time_unit``).
    """

    def __init__(self, total_time: float, n_bodies: int, stream=None, width: int = 30,
                 by: str = 'time', unit: str = 'yr') -> None:
        if by not in ('time', 'bodies'):
            raise ValueError(f"by: must be 'time' or 'bodies', got {by!r}")
        self.stream = stream if stream is not None else sys.stderr
        self.total_time, self.n_bodies, self.width, self.by = total_time, n_bodies, width, by
        self.unit = unit
        self.start = time.perf_counter()
        self._tty = hasattr(self.stream, 'isatty') and self.stream.isatty()
        self._last_decile = -1

    def __call__(self, fraction: float, t: float, body_steps: int) -> None:
        elapsed = time.perf_counter() - self.start
        rate = body_steps / elapsed if elapsed > 0 else 0.0
        eta = elapsed * (1.0 - fraction) / fraction if fraction > 0 else math.inf
        filled = int(round(self.width * fraction))
        u = self.unit
        where = (f't = {from_years(t, u):.6g}/{from_years(self.total_time, u):.6g} {u}  '
                 f'{self.n_bodies} bodies'
                 if self.by == 'time' else
                 f'{int(round(fraction * self.n_bodies))}/{self.n_bodies} bodies done')
        text = (f"[{'#' * filled}{'.' * (self.width - filled)}] {100 * fraction:5.1f}%  "
                f'{where}  {rate:.3g} body-steps/s  elapsed {elapsed:.1f} s  ETA {eta:.1f} s')
        if self._tty:
            self.stream.write('\r' + text + ('\n' if fraction >= 1.0 else ''))
            self.stream.flush()
        else:
            decile = int(fraction * 10 + 1e-9)
            if decile != self._last_decile:
                self._last_decile = decile
                self.stream.write(text + '\n')
                self.stream.flush()

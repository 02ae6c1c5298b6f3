"""
The one mapping between simulated years and ROS time stamps.

Every message the simulator publishes is stamped with ROS time ``ns`` (integer nanoseconds,
``builtin_interfaces/Time`` = ``sec`` * 10^9 + ``nanosec``). The simulated time in years is

    t [yr] = ns / (10^9 * seconds_per_year)        (one float64 division)

and the simulator integrates to exactly that float, so a reader applying the same formula to
a stamp recovers, bit for bit, the time the sample was computed at. ``seconds_per_year`` is a
parameter of the simulator (default 1: one ROS second per simulated year, so a 10,000-year
run ends at 10,000 s, far from the int32 limit of ``Time.sec`` at 2^31 s ~ 68 years of ROS
time; the integer nanoseconds also stay below 2^53, where float64 stops being exact).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from tumble_ros.core.model.limits import MAX_SAMPLES, ScenarioError

__all__ = ['TimeBase', 'SampleGrid', 'MAX_STAMP_NS']

#: Largest stamp: Time.sec is an int32.
MAX_STAMP_NS = (2**31 - 1) * 10**9


@dataclass(frozen=True)
class TimeBase:
    """
    Conversion between simulated years and integer ROS nanoseconds.

    Attributes
    ----------
    seconds_per_year : float
        ROS seconds per simulated year (> 0).

    """

    seconds_per_year: float = 1.0

    def __post_init__(self) -> None:
        s = self.seconds_per_year
        if (isinstance(s, bool) or not isinstance(s, (int, float)) or not math.isfinite(s)
                or s <= 0):
            raise ValueError(f'seconds_per_year: must be a finite number > 0, got {s!r}')

    @property
    def ns_per_year(self) -> float:
        """ROS nanoseconds per simulated year."""
        return 1e9 * self.seconds_per_year

    def to_years(self, ns: int) -> float:
        """Convert a stamp in integer nanoseconds to simulated time [yr]."""
        return ns / self.ns_per_year

    def to_ns(self, t: float) -> int:
        """Nearest integer-nanosecond stamp of a simulated time [yr]."""
        return int(round(t * self.ns_per_year))

    @staticmethod
    def stamp_ns(sec: int, nanosec: int) -> int:
        """Integer nanoseconds of a ``builtin_interfaces/Time`` (sec, nanosec)."""
        return int(sec) * 1_000_000_000 + int(nanosec)

    def check_span(self, duration: float) -> None:
        """Raise ScenarioError (a ValueError) if ``duration`` years overflow Time.sec (int32)."""
        # compared as a float first: 1e300 yr has no integer stamp
        ns = duration * self.ns_per_year
        if not ns <= MAX_STAMP_NS or self.to_ns(duration) > MAX_STAMP_NS:
            limit = MAX_STAMP_NS / self.ns_per_year
            raise ScenarioError(
                f'duration: {duration:g} yr at seconds_per_year = {self.seconds_per_year:g} ends '
                f'past the int32 limit of builtin_interfaces/Time ({limit:.4g} yr); lower '
                f'seconds_per_year'
            )

    def check(self, interval: float, duration: float) -> None:
        """
        Raise ScenarioError (naming the field) unless the output grid fits ROS stamps.

        The grid of ``interval`` years over ``duration`` years fits when the run ends within the
        int32 limit (:meth:`check_span`), the interval is at least 1 ns of ROS time (the stamps'
        resolution: a shorter one would be rounded to a different interval, or to 0) and the grid
        has at most ``limits.MAX_SAMPLES`` samples.
        """
        self.check_span(duration)
        ns = interval * self.ns_per_year
        # (1e-9: an interval computed as 1 / ns_per_year may round below 1)
        if not ns >= 1.0 - 1e-9:
            raise ScenarioError(
                f'output_interval: {interval:g} yr is {ns:.3g} ns of ROS time at '
                f'seconds_per_year = {self.seconds_per_year:g}, below the 1 ns resolution of the '
                f'stamps; raise output_interval to >= {1.0 / self.ns_per_year:.3g} yr or '
                f'seconds_per_year'
            )
        samples = self.to_ns(duration) // max(1, self.to_ns(interval)) + 1
        if samples > MAX_SAMPLES:
            raise ScenarioError(
                f'output_interval: {samples:.3g} samples of {interval:g} yr over {duration:g} yr '
                f'exceed {MAX_SAMPLES:.0e}'
            )

    def grid(self, interval: float, duration: float) -> 'SampleGrid':
        """Return the output grid of ``interval`` years over ``duration`` years."""
        interval_ns, n = self.sample_grid(interval, duration)
        return SampleGrid(self, interval_ns, n)

    def sample_grid(self, interval: float, duration: float) -> tuple[int, int]:
        """
        Output grid in stamps: (interval_ns, n_samples) with samples at k * interval_ns.

        The interval is rounded to whole nanoseconds; every sample time
        ``to_years(k * interval_ns)`` lies in [0, duration]. Raises ScenarioError (see
        :meth:`check`) for a grid that ROS stamps cannot carry.
        """
        self.check(interval, duration)
        interval_ns = max(1, self.to_ns(interval))
        n = self.to_ns(duration) // interval_ns + 1
        while n > 1 and self.to_years((n - 1) * interval_ns) > duration:
            n -= 1  # the stamp rounded up past the end: the last sample must lie within the run
        return interval_ns, n


@dataclass(frozen=True)
class SampleGrid:
    """
    The output grid, the one for every consumer: sample k at stamp k * interval_ns.

    Its time is ``timebase.to_years(k * interval_ns)`` [yr], the float the simulator integrates
    to and a reader recovers from the stamp bit for bit. ``Scenario.output_times`` (the default
    of ``simulate``) is this grid at the default time base; the sim node publishes it at its own
    ``seconds_per_year``, and the comparator evaluates its model on it.

    Attributes
    ----------
    timebase : TimeBase
    interval_ns : int
        Spacing of the stamps [ns] (the output interval rounded to whole nanoseconds).
    count : int
        Number of samples; the last lies within the run.

    """

    timebase: TimeBase
    interval_ns: int
    count: int

    def stamp(self, k: int) -> int:
        """Return the stamp [ns] of sample k."""
        return k * self.interval_ns

    def time(self, k: int) -> float:
        """Return the time [yr] of sample k."""
        return self.timebase.to_years(k * self.interval_ns)

    def times(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Return the times [yr] of samples start .. stop - 1 (default: all), as :meth:`time`."""
        stop = self.count if stop is None else stop
        stamps = np.arange(start, stop, dtype=np.int64) * self.interval_ns
        return stamps / self.timebase.ns_per_year

    def index_of(self, stamp_ns: int) -> int | None:
        """Return k if ``stamp_ns`` is the stamp of sample k, else None."""
        if stamp_ns % self.interval_ns or not 0 <= stamp_ns // self.interval_ns < self.count:
            return None
        return stamp_ns // self.interval_ns

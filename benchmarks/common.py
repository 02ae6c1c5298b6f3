"""Shared pieces of the benchmarks: the section registry, the run context, table printing.

Adding a section to ``make bench`` is one function in any module of this folder::

    # benchmarks/my_section.py
    from common import section

    @section("My measurement", order=50)
    def my_measurement(ctx):
        rows = [("case A", 1.23, 4.5e6)]
        ctx.table(["case", "wall [s]", "rate [/s]"], rows)
        ctx.note("what was measured, and how")
        return {"case A": 1.23}          # optional: kept in ctx.results / --json

``run.py`` imports every ``*.py`` module here (except ``run.py``, ``common.py`` and names
starting with ``_``), then runs the registered sections in ``order`` (core sections use
10-29; 30+ is free, e.g. the ROS throughput section). ``ctx.quick`` asks for a shorter
version (``make bench BENCH_ARGS=--quick``); ``ctx.full`` for the long one.
"""
from __future__ import annotations

import contextlib
import math
import os
import platform
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable

SECTIONS: list[tuple[int, str, Callable]] = []


def section(title: str, order: int = 50):
    """Register ``fn(ctx)`` as a benchmark section titled ``title``."""

    def register(fn):
        SECTIONS.append((order, title, fn))
        fn.bench_title = title
        return fn

    return register


@dataclass
class Context:
    """What a section gets: options, printing helpers, results of earlier sections."""

    quick: bool = False
    full: bool = False
    out: Any = sys.stdout
    results: dict = field(default_factory=dict)

    def print(self, *args) -> None:
        print(*args, file=self.out, flush=True)

    def verdict(self, met: bool, missed: str = "MISSED") -> str:
        """Return "MET" or ``missed``; a quick run judges nothing (its workloads are reduced)."""
        if self.quick:
            return "not judged (quick run: reduced workload)"
        return "MET" if met else missed

    def note(self, text: str) -> None:
        for line in text.strip().splitlines():
            self.print(f"  {line}")

    def table(self, headers, rows) -> None:
        """A plain-text table (also valid Markdown)."""
        cells = [[fmt(v) for v in row] for row in rows]
        widths = [max(len(str(h)), *(len(r[i]) for r in cells)) if cells else len(str(h))
                  for i, h in enumerate(headers)]
        line = "| " + " | ".join(str(h).ljust(w) for h, w in zip(headers, widths)) + " |"
        self.print(line)
        self.print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
        for r in cells:
            self.print("| " + " | ".join(c.rjust(w) if _numeric(c) else c.ljust(w)
                                         for c, w in zip(r, widths)) + " |")


def _numeric(text: str) -> bool:
    try:
        float(text.replace("x", "").replace("~", "").replace("×", ""))
        return True
    except ValueError:
        return False


def fmt(v) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        if v == 0:
            return "0"
        if abs(v) >= 1e5 or abs(v) < 1e-2:
            return f"{v:.2e}"
        return f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"
    return str(v)


class Timer:
    """``with Timer() as t: ...`` then ``t.seconds``."""

    def __enter__(self):
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self.start
        return False


@contextlib.contextmanager
def busy_processes(n: int = 2):
    """
    Within: ``n`` processes spinning a CPU each (``while True: pass``), killed on the way out.

    The "under load" rows of the ROS sections: on this 2-core machine two busy processes take
    both cores, as a test suite or a second run beside the nodes would.
    """
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"],
                             start_new_session=True) for _ in range(n)]
    try:
        time.sleep(0.5)     # they are running before the measurement starts
        yield
    finally:
        for hog in hogs:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(hog.pid, signal.SIGKILL)
            hog.wait()


def machine_description() -> list[str]:
    """CPU, cores, load and library versions, for the header of a run."""
    lines = []
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    lines.append(f"CPU: {cpu}, {os.cpu_count()} logical cores; Python {platform.python_version()}")
    try:
        load = os.getloadavg()
        lines.append(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
                     "(other work on the machine slows every number below)")
    except OSError:
        pass
    versions = []
    for name in ("numpy", "scipy", "numba"):
        try:
            versions.append(f"{name} {__import__(name).__version__}")
        except ImportError:
            versions.append(f"{name} not installed")
    lines.append(", ".join(versions))
    return lines

"""
The spectrum of one component of w: its dominant frequencies, matched to the theory's lines.

Amplitudes in rad/yr (a sinusoid of amplitude A gives about A), frequencies in rad/yr, times in
simulated years; the component is a body-axis one (``wx`` in the summary). Window: Blackman.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Sequence

import numpy as np

from .theory import alias, TheoryLine
from .timeaxis import UNIFORM_TOL

__all__ = ['PEAK_THRESHOLD', 'Peak', 'Spectrum', 'WINDOW', 'spectrum']

#: Spectral window (numpy.blackman): sidelobes below -58 dB, main lobe +-3 bins.
WINDOW = 'blackman'
#: Peaks weaker than this fraction of the strongest are not reported (well above the
#: Blackman window's sidelobes, 1.3e-3).
PEAK_THRESHOLD = 5e-3


@dataclass(frozen=True)
class Peak:
    """A local maximum of the amplitude spectrum and the theory line nearest to it."""

    omega: float             # [rad/yr], refined between bins
    amplitude: float         # estimated amplitude of the sinusoid [rad/yr]
    nearest: str | None      # the theory line whose apparent frequency is nearest
    nearest_omega: float | None    # that line's frequency [rad/yr]
    offset: float | None     # omega - the line's apparent frequency [rad/yr]
    nearest_aliased: bool = False  # the line lies above pi/dt: its apparent frequency is its alias

    @property
    def period(self) -> float:
        """Return 2 pi/omega [yr] (inf for omega = 0)."""
        return 2 * math.pi / self.omega if self.omega > 0 else math.inf


@dataclass(frozen=True)
class Spectrum:
    """Amplitude spectrum of one component (mean removed, Blackman window, rfft)."""

    component: str
    n: int
    dt: float
    resampled: bool          # linearly interpolated onto a uniform grid first
    window: str
    resolution: float        # bin spacing 2 pi/(n dt) [rad/yr]
    nyquist: float           # pi/dt [rad/yr]
    peaks: tuple[Peak, ...]
    omega_axis: np.ndarray = field(repr=False, metadata={'json': False})
    amplitude: np.ndarray = field(repr=False, metadata={'json': False})


def _uniform(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, float, bool]:
    t, first = np.unique(t, return_index=True)
    x = x[first]
    d = np.diff(t)
    dt = float(np.median(d))
    if np.all(np.abs(d - dt) <= UNIFORM_TOL * dt):
        return x, dt, False
    grid = t[0] + dt * np.arange(int(math.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1)
    return np.interp(grid, t, x), dt, True


def _local_maxima(amp: np.ndarray) -> list[int]:
    """
    Return the bins k >= 1 above the bin before and not below the next, strongest first.

    The last bin has no next. Equal amplitudes keep the order of their bins (a stable sort),
    as sorting the bins by ``-amp[k]`` in Python does (tests/test_analysis_spectrum_peaks.py).
    """
    if len(amp) < 2:
        return []
    rising = amp[1:] > amp[:-1]
    rising[:-1] &= amp[1:-1] >= amp[2:]
    k = np.flatnonzero(rising) + 1
    return k[np.argsort(-amp[k], kind='stable')].tolist()


def spectrum(t: np.ndarray, x: np.ndarray, lines: Sequence[TheoryLine] = (), *,
             component: str = 'wx', n_peaks: int = 5,
             threshold: float = PEAK_THRESHOLD) -> Spectrum | None:
    """
    Return the dominant frequencies of ``x(t)``.

    They are the ``n_peaks`` strongest local maxima of the windowed amplitude spectrum above
    ``threshold`` times the strongest, at least 3 bins apart, each refined by a parabola through
    the log amplitudes of its bin and the two neighbours and matched to the theory line whose
    apparent frequency (the line itself, or its alias if it lies above pi/dt) is nearest. None for
    fewer than 8 distinct samples.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if len(np.unique(t)) < 8:
        return None
    y, dt, resampled = _uniform(t, x)
    n = len(y)
    window = np.blackman(n)
    spec = np.fft.rfft((y - y.mean()) * window)
    amp = 2.0 * np.abs(spec) / window.sum()
    omega_axis = 2 * math.pi * np.fft.rfftfreq(n, dt)
    resolution = 2 * math.pi / (n * dt)
    candidates = _local_maxima(amp)
    chosen: list[int] = []
    top = amp[candidates[0]] if candidates else 0.0
    for k in candidates:
        if top <= 0 or amp[k] < threshold * top or len(chosen) >= n_peaks:
            break
        if all(abs(k - c) >= 3 for c in chosen):
            chosen.append(k)
    nyquist = math.pi / dt
    # where each line shows up in a spectrum sampled at dt (its alias above the Nyquist rate)
    apparent = [(line, line.omega if line.omega <= nyquist else alias(line.omega, nyquist))
                for line in lines]
    peaks = []
    for k in chosen:
        shift = 0.0
        if 0 < k < len(amp) - 1 and min(amp[k - 1], amp[k], amp[k + 1]) > 0:
            a, b, c = np.log(amp[k - 1]), np.log(amp[k]), np.log(amp[k + 1])
            denom = a - 2 * b + c
            if denom < 0:
                shift = float(np.clip(0.5 * (a - c) / denom, -0.5, 0.5))
        w = float(omega_axis[k] + shift * resolution)
        if lines:
            line, seen = min(apparent, key=lambda item: abs(item[1] - w))
            peaks.append(Peak(w, float(amp[k]), line.name, line.omega, w - seen,
                              line.omega > nyquist))
        else:
            peaks.append(Peak(w, float(amp[k]), None, None, None))
    return Spectrum(component, n, dt, resampled, WINDOW, resolution, nyquist,
                    tuple(peaks), omega_axis, amp)

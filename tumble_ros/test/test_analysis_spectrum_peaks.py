"""
The spectrum's local maxima and the pairing of stamps, against their plain definitions.

spectrum._local_maxima (numpy) against the Python loop it replaced: a bin above the one before
and not below the next (the last bin has no next), strongest first, equal amplitudes in bin
order; on random spectra, plateaus, ties and edges. timeaxis.same_stamps against
numpy.intersect1d, with equal, shifted, repeated and unordered stamps.
"""
import numpy as np
import pytest

from tumble_ros.analysis.spectrum import _local_maxima
from tumble_ros.analysis.timeaxis import same_stamps


def _by_loop(amp):
    candidates = [k for k in range(1, len(amp))
                  if amp[k] > amp[k - 1] and (k + 1 == len(amp) or amp[k] >= amp[k + 1])]
    candidates.sort(key=lambda k: -amp[k])
    return candidates


@pytest.mark.parametrize('seed', range(20))
def test_local_maxima_are_the_loops(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 300))
    amp = rng.integers(0, 6, n).astype(float)          # many ties and plateaus
    if seed % 2:
        amp = rng.random(n)
    assert _local_maxima(amp) == _by_loop(amp)


@pytest.mark.parametrize('amp, expected', [
    ([], []), ([1.0], []), ([1.0, 2.0], [1]), ([2.0, 1.0], []),
    ([0.0, 3.0, 3.0, 1.0], [1]),                  # a plateau: its first bin only
    ([0.0, 2.0, 0.0, 2.0, 0.0, 5.0], [5, 1, 3]),  # the last bin; a tie in bin order
    ([1.0, np.nan, 2.0, 1.0], []),                # nothing is above NaN nor NaN above it
])
def test_local_maxima_by_hand(amp, expected):
    amp = np.array(amp, dtype=float)
    assert _local_maxima(amp) == _by_loop(amp) == expected


@pytest.mark.parametrize('t_a, t_b', [
    (np.arange(10.0), np.arange(10.0)),                    # the same: paired at once
    (np.arange(10.0), np.arange(3.0, 14.0)),
    (np.array([0.0, 1.0, 1.0, 2.0]), np.array([0.0, 1.0, 1.0, 2.0])),   # repeated
    (np.array([3.0, 1.0, 2.0]), np.array([3.0, 1.0, 2.0])),             # not in order
    (np.array([5.0]), np.array([5.0])), (np.array([]), np.array([])),
])
def test_same_stamps_are_intersect1d(t_a, t_b):
    _, ia, ib = np.intersect1d(t_a, t_b, assume_unique=False, return_indices=True)
    got_a, got_b = same_stamps(t_a, t_b)
    assert got_a.dtype == ia.dtype and got_b.dtype == ib.dtype
    assert got_a.tolist() == ia.tolist() and got_b.tolist() == ib.tolist()

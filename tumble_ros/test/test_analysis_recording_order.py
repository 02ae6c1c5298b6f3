"""
load_recording's ordering of each topic by stamp (analysis.recording._sorted).

Recordings are written in stamp order, so the sort is skipped when the stamps are in order
already: the result must be what the stable argsort gives in every case (in order, out of
order, equal stamps kept in arrival order, empty), and arrays of their own (not views of the
columns they came from), except for load_recording's own columns already in order (``owned``:
no copy).
"""
import numpy as np
import pytest

from tumble_ros.analysis.recording import _sorted

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 3


def _by_argsort(ns, rows, k):
    stamps = np.asarray(ns, dtype=np.int64)
    values = np.asarray(rows, dtype=float).reshape(-1, k)
    order = np.argsort(stamps, kind='stable')
    return stamps[order], values[order]


@pytest.mark.parametrize('stamps', [
    np.arange(0, 5000, 5, dtype=np.int64),                          # in order
    np.repeat(np.arange(300, dtype=np.int64), 3),                    # in order, equal stamps
    np.random.default_rng(SEED).permutation(1000).astype(np.int64),  # shuffled
    np.r_[np.arange(500), np.arange(250, 750)].astype(np.int64),     # a late message
    np.array([7], dtype=np.int64),
])
@pytest.mark.parametrize('k', [2, 3])
@pytest.mark.parametrize('owned', [False, True])
def test_the_order_is_the_stable_argsorts(stamps, k, owned):
    rng = np.random.default_rng(SEED)
    rows = rng.normal(size=(len(stamps), k))
    got_t, got_v = _sorted(stamps, rows, k, owned=owned)
    want_t, want_v = _by_argsort(stamps, rows, k)
    assert got_t.dtype == want_t.dtype and got_v.dtype == want_v.dtype
    assert got_t.tobytes() == want_t.tobytes() and got_v.tobytes() == want_v.tobytes()
    assert got_v.flags.c_contiguous and got_v.shape == (len(stamps), k)
    in_order = bool((stamps[1:] >= stamps[:-1]).all())
    # arrays of their own, unless the caller owns its columns and they are in order (no copy)
    shared = owned and in_order
    assert np.shares_memory(got_t, stamps) == np.shares_memory(got_v, rows) == shared


def test_no_samples():
    t, v = _sorted(np.empty(0, dtype=np.int64), [], 3)
    assert t.shape == (0,) and v.shape == (0, 3)

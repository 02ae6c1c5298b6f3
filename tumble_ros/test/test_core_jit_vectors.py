"""The kernels' vector width: 512-bit registers where the CPU has AVX-512 (core.jit)."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tumble_ros.core.jit import COMPILED, PREFER_512_BIT, wide_vector_features

needs_numba = pytest.mark.skipif(not COMPILED, reason='numba not available')

#: Run in a fresh interpreter: what the import of core.jit chose, and a compiled loop's code.
PROBE = """
import json
import numpy as np
import numba
from numba.core.codegen import get_host_cpu_features
from tumble_ros.core.jit import jit

def axpy(a, x, y):
    for i in range(x.shape[0]):
        y[i] = y[i] + a * x[i]

axpy = jit(axpy, cache=False)
x = np.arange(64.0)
y = np.ones(64)
axpy(2.0, x, y)
assert np.array_equal(y, 1.0 + 2.0 * x)
print(json.dumps({'features': numba.config.CPU_FEATURES, 'host': get_host_cpu_features(),
                  'asm': next(iter(axpy.inspect_asm().values()))}))
"""


def _probe(**env: str) -> dict[str, str]:
    """Run :data:`PROBE` with the environment's NUMBA_CPU_* replaced by ``env``."""
    clean = {k: v for k, v in os.environ.items() if not k.startswith('NUMBA_CPU_')}
    done = subprocess.run([sys.executable, '-c', PROBE], capture_output=True, text=True,
                          env={**clean, **env}, timeout=120)
    assert done.returncode == 0, done.stderr
    answer: dict[str, str] = json.loads(done.stdout.splitlines()[-1])
    return answer


def test_a_cpu_with_avx512_is_told_to_prefer_512_bit_vectors():
    host = '+avx2,+avx512f,+avx512dq,+fma,+prefer-256-bit,-amx-tile'
    wide = wide_vector_features(host)
    assert wide is not None
    listed = wide.split(',')
    assert listed[-1] == PREFER_512_BIT == '-prefer-256-bit'
    assert '+prefer-256-bit' not in listed          # the host's own tuning replaced, not doubled
    assert listed[:-1] == ['+avx2', '+avx512f', '+avx512dq', '+fma', '-amx-tile']


def test_a_cpu_without_avx512_keeps_numbas_choice():
    assert wide_vector_features('+avx2,+fma,-avx512f,+sse4.2') is None
    assert wide_vector_features('') is None


@needs_numba
def test_the_kernels_compile_on_512_bit_registers_where_the_cpu_has_them():
    """The import chose the features; a vectorised loop uses zmm exactly where AVX-512 is."""
    probe = _probe()
    wide = wide_vector_features(probe['host'])
    assert probe['features'] == wide
    if wide is None:     # this CPU: no AVX-512, numba's own features, no 512-bit register
        assert 'zmm' not in probe['asm']
    else:
        assert 'zmm' in probe['asm'], probe['asm'][:2000]


@needs_numba
def test_the_users_choice_of_target_is_left_as_it_is():
    host = _probe()['host']
    assert _probe(NUMBA_CPU_FEATURES=host)['features'] == host    # (256-bit vectors)
    assert 'zmm' not in _probe(NUMBA_CPU_FEATURES=host)['asm']
    generic = _probe(NUMBA_CPU_NAME='generic')     # (numba's portable code: its own features)
    assert PREFER_512_BIT not in (generic['features'] or '')
    assert 'zmm' not in generic['asm']

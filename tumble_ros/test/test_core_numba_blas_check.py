"""numba's BLAS check without scipy.linalg (core.compiling.numba_blas_check): same answer."""
from __future__ import annotations

import inspect
import json
import subprocess
import sys

import pytest

from tumble_ros.core.compiling.jit import COMPILED
from tumble_ros.core.compiling.numba_blas_check import scipy_linalg_installed

needs_numba = pytest.mark.skipif(not COMPILED, reason='numba not available')

#: A fresh process loads (or compiles) a loop, then compiles a function that calls BLAS.
_PROCESS = """
import json, sys
import numpy as np
from tumble_ros.core import IntegratorSettings, Scenario, simulate
simulate(Scenario(duration=1e-3, output_interval=1e-3,
                  integrator=IntegratorSettings(method='dop853')))
from numba.np import arraymath, linalg
after_loop = {'scipy_linalg': 'scipy.linalg' in sys.modules, 'have_blas': arraymath._HAVE_BLAS,
              'ensure_blas_is_numbas': linalg.ensure_blas.__module__ == 'numba.np.linalg'}
import numba
dot = numba.njit(cache=False)(lambda a, b: np.dot(a, b))
a, b = np.arange(1.0, 6.0), np.arange(2.0, 7.0)
print(json.dumps({**after_loop, 'dot': dot(a, b), 'numpy_dot': float(a @ b),
                  'scipy_linalg_after_dot': 'scipy.linalg' in sys.modules}))
"""


@needs_numba
def test_a_process_loads_its_loop_without_scipy_linalg_and_blas_still_works():
    done = subprocess.run([sys.executable, '-c', _PROCESS], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen['scipy_linalg'] is False, seen          # numba's check imported it: 0.17 s
    assert seen['have_blas'] is True, seen              # the answer numba's check gives
    assert seen['ensure_blas_is_numbas'] is True, seen  # numba's own, for what compiles BLAS
    assert seen['dot'] == seen['numpy_dot'], seen
    assert seen['scipy_linalg_after_dot'] is True, seen  # compiling np.dot checked BLAS there


@needs_numba
def test_numbas_registries_are_laid_out_as_the_check_expects():
    """If numba moves the check, this fails (and the process imports scipy.linalg again)."""
    from numba.core import cpu
    from numba.np import arraymath

    # the registries' loading imports linalg, then arraymath, whose import checks BLAS
    assert 'from numba.np import linalg, arraymath' in inspect.getsource(cpu)
    source = inspect.getsource(arraymath)
    assert 'from numba.np.linalg import ensure_blas' in source
    assert '_HAVE_BLAS = _check_blas()' in source


def test_the_check_asks_only_whether_scipy_linalg_is_installed(monkeypatch):
    import importlib.util

    scipy_linalg_installed()                       # installed here: no error
    monkeypatch.setattr(importlib.util, 'find_spec', lambda name: None)
    with pytest.raises(ImportError, match='scipy 0.16\\+ is required for linear algebra'):
        scipy_linalg_installed()

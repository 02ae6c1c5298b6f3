"""
numba's BLAS check without importing ``scipy.linalg``: a process loads its first loop sooner.

The first time numba compiles a function or loads one from its cache, it imports its typing and
lowering modules (``numba.core.cpu.CPUContext.load_additional_registries``). One of them,
``numba.np.arraymath``, checks at its import that a BLAS is there for ``np.dot``
(``_HAVE_BLAS = _check_blas()``): ``numba.np.linalg.ensure_blas`` imports
``scipy.linalg.cython_blas``, so the whole ``scipy.linalg`` package and scipy's own OpenBLAS.
Nothing in this package uses BLAS in compiled code, and no process imports ``scipy.linalg``
otherwise: a node or a run spent ~0.1 s of its start and ~0.17 s of CPU there (a fresh process
loading the ``dop853`` loop from the cache: 0.83 → 0.66 s of CPU, 2026-12-07,
benchmarks/HISTORY.md, "numba's BLAS check").

:func:`check_blas_without_importing_it` makes that one check at arraymath's import ask only
whether ``scipy.linalg`` is installed (:func:`scipy_linalg_installed`), as numba's check does
without importing it: ``_HAVE_BLAS`` is the same. numba's own ``ensure_blas`` stays in place
for everything else: compiling an ``np.dot`` or a ``np.linalg`` call still imports
``scipy.linalg`` and checks its integer width, there, as before.

It wraps ``load_additional_registries`` until its first call, then gives numba's back. On a
numba whose modules are not laid out as this expects, the check is numba's own, and
tests/test_core_numba_blas_check.py fails, so an upgrade gets it looked at again.
"""
from __future__ import annotations

import importlib.util
from typing import Any

__all__ = ['scipy_linalg_installed', 'check_blas_without_importing_it']


def scipy_linalg_installed() -> None:
    """
    Raise numba's ImportError unless ``scipy.linalg`` is installed; do not import it.

    (``find_spec`` imports the parent package, ``scipy``, which the process has already.)
    """
    if importlib.util.find_spec('scipy.linalg') is None:
        raise ImportError('scipy 0.16+ is required for linear algebra')   # numba's words


def check_blas_without_importing_it(cpu: Any) -> None:
    """
    Make numba's first registry loading check BLAS with :func:`scipy_linalg_installed`.

    ``cpu``: numba's ``numba.core.cpu`` module. Its ``CPUContext.load_additional_registries``
    is wrapped: the first call imports ``numba.np.linalg``, puts the check in place of its
    ``ensure_blas`` while numba's own call imports arraymath, puts numba's back, and gives
    the class numba's method back.
    """
    context_class = cpu.CPUContext
    plain = context_class.load_additional_registries
    if getattr(plain, 'edits_numba', False):
        return

    def load_additional_registries(self: Any) -> Any:
        from numba.np import linalg
        ensure_blas = linalg.ensure_blas
        linalg.ensure_blas = scipy_linalg_installed
        try:
            return plain(self)
        finally:
            linalg.ensure_blas = ensure_blas
            context_class.load_additional_registries = plain

    load_additional_registries.edits_numba = True      # type: ignore[attr-defined]
    context_class.load_additional_registries = load_additional_registries

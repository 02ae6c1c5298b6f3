"""
The numba switch: compile the kernels and torque functions, or run them as plain Python.

With numba installed the decorated functions are compiled once (``cache=True``: the machine
code is kept in the user's cache, :func:`shared_cache_folder`, and reused by later processes
and by every clone of the same sources); without numba, or with
``TUMBLE_ROS_NO_JIT=1`` / ``NUMBA_DISABLE_JIT=1``, :data:`COMPILED` is False and the
decorators return the functions unchanged, so the same source runs as plain Python (the
reference path; tests/test_core_fast.py checks both give the same trajectory).

One cache key for all compiled sources
--------------------------------------
numba validates a cached function against its *own* file only, but the kernels inline each
other across files (``kernels/stepping.py`` inlines ``kernels/rk4.py``, which inlines
``torques/gravity_gradient.py``): an edit to rk4.py would leave stale machine code in
stepping.py's cache. :class:`_CompiledSourcesLocator` gives every function of the files in
:data:`COMPILED_SOURCES` one source stamp, the hash of all of them, so an edit to any of them
recompiles them all. It plugs into numba's documented locator list
(``numba.core.caching.CacheImpl._locator_classes``, a private attribute: checked by
tests/test_core_fast.py::test_an_edit_to_any_kernel_file_invalidates_the_cache).

One cache for every clone
-------------------------
The locator keeps the machine code in the user's cache (``~/.cache/tumble_ros/numba``), in a
folder named by that hash, not beside the sources: a second clone or worktree of the same
sources, or a fresh clone for CI, loads the loops another compiled instead of spending ~110 s
of CPU compiling them again (tests/test_core_shared_cache.py). Where that folder cannot be
written, numba's ``__pycache__`` as before; ``NUMBA_CACHE_DIR`` is honoured. The warm-up
deletes the folders of other versions but the last :data:`SHARED_CACHE_KEEP` used.

No reference counting in the kernels
------------------------------------
numba counts references to every array with atomic (``lock``-prefixed) increments and
decrements, and an array handed to an inlined function or sliced inside a loop gets a pair
of them on every pass that its pruning pass cannot remove in branchy code (numba issue 2350).
Profiled on a Fig 9 ensemble (perf, 2026-12-02) they took ~65 % of a splitting step: two
thirds of 187 ns a body-step went to ``NRT_incref``/``NRT_decref``. The kernels allocate
nothing and return no array (they write into arrays their Python caller owns and keeps alive
for the call), so they are compiled without numba's runtime (:data:`JIT_OPTIONS`,
``_nrt=False``: numba's option, underscored, the one its maintainers use in that issue):
~70 ns a body-step. tests/test_core_fast.py checks the compiled code holds no reference count.

Inlining in less CPU
--------------------
numba copies an inlined function's IR once a block, each copy with the whole scope:
:mod:`.numba_inlining` makes it one copy (the same machine code; the warm-up
from an empty cache in a fifth less CPU).

No scipy.linalg at the first load
---------------------------------
numba's first compilation or cache load imports ``scipy.linalg`` to check that ``np.dot`` has
a BLAS, which no kernel calls: :mod:`.numba_blas_check` asks only whether it is
installed (a process's first loop loaded in ~0.17 s less CPU).

512-bit vectors for the loops over a block of bodies
----------------------------------------------------
On a CPU with AVX-512, LLVM still vectorises with 256-bit registers (its tuning for those
CPUs). The functions compiled with ``wide=True`` (:func:`jit_wide`: the lockstep and lanes
loops, which run one body a vector lane) carry the LLVM attribute that lets them use 512-bit
registers (:func:`_wide_ir`); the single-body loops do not (:data:`WIDE_VECTOR_LOOPS`).
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import os
from pathlib import Path
import re
import sys
import threading
import time
import types
from typing import Any, Callable, cast, Iterator, TextIO, TypeVar

from tumble_ros.core.compiling.user_cache import user_cache_dir

__all__ = ['COMPILED', 'NUMBA_VERSION', 'JIT_OPTIONS', 'jit', 'jit_inline', 'called',
           'python_source', 'specialise', 'COMPILED_SOURCES', 'compiled_sources_hash',
           'first_use', 'COMPILE_NOTICE_SECONDS', 'COMPILE_NOTICE_VARIABLE', 'compile_notices',
           'load_for', 'WIDE_VECTOR_LOOPS', 'PREFER_512_BIT', 'jit_wide', 'shared_cache_root',
           'shared_cache_folder', 'prune_shared_cache', 'SHARED_CACHE_KEEP']

#: A function (the decorators return a compiled function typed as the one they are given).
F = TypeVar('F', bound=Callable[..., Any])

_numba: Any  # (numba has no type information)
try:  # pragma: no cover - exercised by the environment, not by a test
    import numba
    _numba = numba
except ImportError:  # pragma: no cover
    _numba = None

NUMBA_VERSION = getattr(_numba, '__version__', None)
#: True when the kernels are compiled (numba present and not disabled).
COMPILED = bool(_numba is not None and not _numba.config.DISABLE_JIT
                and os.environ.get('TUMBLE_ROS_NO_JIT', '') in ('', '0'))

#: numba options of every kernel: cached, numpy's error model (1/0 is inf, not an exception), no
#: GIL (threads), no runtime (no allocation, no reference counting: see the module's docstring).
JIT_OPTIONS: dict[str, Any] = {'cache': True, 'error_model': 'numpy', 'nogil': True, '_nrt': False}

_CORE = Path(__file__).resolve().parents[1]
#: The files whose compiled functions inline each other, the compile machinery (this folder) and
#: every core module they import (``trig``'s sin/cos and atan2 are inlined into the kernels,
#: ``units``' constants frozen into them): one cache stamp for all (tests/test_core_fast.py
#: checks the imports are here).
COMPILED_SOURCES: tuple[Path, ...] = tuple(
    sorted((_CORE / 'compiling').glob('*.py'))
    + sorted((_CORE / 'kernels').glob('*.py')) + sorted((_CORE / 'torques').glob('*.py'))
    + [_CORE / name for name in ('units.py', 'trig.py')])


@functools.lru_cache(maxsize=None)
def _hash(stamps: tuple[tuple[int, int], ...]) -> bytes:
    digest = hashlib.sha256()
    for path in COMPILED_SOURCES:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.digest()


def compiled_sources_hash() -> bytes:
    """Return the SHA-256 of every file in :data:`COMPILED_SOURCES` (re-read when one changes)."""
    stamps = tuple((os.stat(p).st_mtime_ns, os.stat(p).st_size) for p in COMPILED_SOURCES)
    return _hash(stamps)


#: Folders of other versions of the compiled sources that :func:`prune_shared_cache` keeps (the
#: last used; ~19 MB each when every loop is compiled).
SHARED_CACHE_KEEP = 8


def shared_cache_root() -> Path:
    """Return the folder of numba's caches of :data:`COMPILED_SOURCES`, one folder a version."""
    return user_cache_dir() / 'numba'


def shared_cache_folder(py_file: str | Path) -> Path:
    """
    Return the folder where numba keeps the compiled functions of ``py_file`` (of this clone).

    ``<shared_cache_root>/<first 16 hex digits of compiled_sources_hash>/<py_file's folder
    relative to core>``: every clone, worktree or install whose compiled sources are the same,
    byte for byte, loads what another compiled (numba's index also keys each entry by the
    function's bytecode, its argument types, numba's version and the CPU). An edit to any of
    them is another folder: everything compiles again, as in-tree.
    """
    return _version_folder() / _compiled_folder(str(py_file))


@functools.lru_cache(maxsize=None)
def _compiled_folder(py_file: str) -> Path:
    """Return the folder of ``py_file``, one of :data:`COMPILED_SOURCES`, relative to core."""
    return Path(py_file).resolve().parent.relative_to(_CORE)


@functools.lru_cache(maxsize=1)
def _version_folder() -> Path:
    """
    Return this process's folder of :func:`shared_cache_root` (the hash at its first call).

    Once a process: a source edited while it runs only changes the stamp numba checks
    (:func:`compiled_sources_hash`), and what it compiles then is kept in this folder.
    """
    return _version_of(shared_cache_root())


def _version_of(root: Path) -> Path:
    """Return the folder in ``root`` of the compiled sources as they are now."""
    return root / compiled_sources_hash().hex()[:16]


@functools.lru_cache(maxsize=None)
def _is_compiled_source(py_file: str) -> bool:
    """Whether ``py_file`` is one of :data:`COMPILED_SOURCES`."""
    try:
        return Path(py_file).resolve() in COMPILED_SOURCES
    except OSError:
        return False


def prune_shared_cache(keep: int = SHARED_CACHE_KEEP) -> list[Path]:
    """
    Mark this version's folder used now; delete the other versions' but the ``keep`` last used.

    The versions' folders are those of :func:`shared_cache_root` named by a hash; a folder is
    marked used by the warm-ups (``cli.warmup``), else dated by its making. Returns the
    folders deleted.
    """
    import shutil

    root = shared_cache_root()
    current = _version_of(root)
    if current.is_dir():
        os.utime(current)
    try:
        versions = [p for p in root.iterdir()
                    if p != current and p.is_dir() and re.fullmatch('[0-9a-f]{16}', p.name)]
    except OSError:
        return []
    versions.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    for folder in versions[keep:]:
        shutil.rmtree(folder, ignore_errors=True)
    return versions[keep:]


#: The compiled functions (numba's library names: qualified names, a copy's with its suffix)
#: whose vectorised loops run on 512-bit registers where the CPU has AVX-512
#: (:func:`jit` ``wide=True``; :func:`_wide_ir`).
WIDE_VECTOR_LOOPS: set[str] = set()
#: The LLVM function attribute given to them: it overrides the CPU's tuning (below).
PREFER_512_BIT = '"prefer-vector-width"="512"'


def _wide_ir(text: str) -> str:
    """
    Return LLVM IR ``text`` with :data:`PREFER_512_BIT` on every function it defines.

    LLVM's tuning for the CPUs with AVX-512 keeps vectorised loops to 256-bit registers
    (``prefer-256-bit``: 512-bit instructions lowered the clock of older Xeons), for numba's
    whole process. The lockstep loops over a block of bodies (``kernels.lockstep``) take
    11-15 % less CPU a body-step on 512-bit registers, 8 doubles a ``zmm`` (the ``dop853``
    lanes of ``kernels.lanes`` about as much as before), with the same bits (the same
    operations on more bodies at once; no reduction is reassociated). The single-body loops
    stay at 256 bits: there AVX-512 vectorises the loops over a state's 7 components with
    masked 8-wide moves, whose stores the next scalar loads cannot take from the store buffer
    (with 512 bits for the whole process, Fig 9's ``dop853`` run took 8-10 % more CPU). The
    attribute is per function: only the functions compiled with ``wide=True`` get it; on a
    CPU without AVX-512 it changes nothing.
    """
    # (llvmlite writes a definition's opening brace on the line after its signature)
    return re.sub(r'^(define [^\n]*)\n\{', r'\1 ' + PREFER_512_BIT + '\n{', text,
                  flags=re.MULTILINE)


def _prefer_wide_vectors(codegen: Any, cgutils: Any, llvm: Any) -> None:
    """
    Compile the functions of :data:`WIDE_VECTOR_LOOPS` with :func:`_wide_ir`'s attribute.

    numba turns a function's IR module to text before LLVM parses it
    (``CPUCodeLibrary.add_ir_module``, whose steps this repeats for those functions only;
    numba has no option for a function attribute). Checked by
    tests/test_core_jit_vectors.py: 512-bit registers in a block loop, none in a single-body
    loop, the same bits.
    """
    library = codegen.CPUCodeLibrary
    plain = library.add_ir_module
    if getattr(plain, 'wide_vectors', False):
        return

    def add_ir_module(self: Any, ir_module: Any) -> None:
        if self.name not in WIDE_VECTOR_LOOPS:
            plain(self, ir_module)
            return
        self._raise_if_finalized()
        parsed = llvm.parse_assembly(_wide_ir(cgutils.normalize_ir_text(str(ir_module))))
        parsed.name = ir_module.name
        parsed.verify()
        self.add_llvm_module(parsed)

    add_ir_module.wide_vectors = True    # type: ignore[attr-defined]
    library.add_ir_module = add_ir_module


if COMPILED:
    from numba.core import cgutils as _cgutils, codegen as _codegen
    _prefer_wide_vectors(_codegen, _cgutils, _codegen.ll)     # (ll: numba's llvmlite.binding)
    from numba.core import untyped_passes as _untyped_passes
    from tumble_ros.core.compiling.numba_inlining import copy_callee_once_when_inlining
    copy_callee_once_when_inlining(_untyped_passes)
    from numba.core import cpu as _cpu
    from tumble_ros.core.compiling.numba_blas_check import check_blas_without_importing_it
    check_blas_without_importing_it(_cpu)
    from numba.core import caching
    _caching: Any = caching

    class _CompiledSourcesLocator(_caching.InTreeCacheLocator):  # type: ignore[misc]  # (numba)
        """
        numba's cache of :data:`COMPILED_SOURCES`, stamped with the hash of them all.

        Kept in :func:`shared_cache_folder` (every clone of the same sources shares it), else,
        where that cannot be written, in-tree (numba's ``__pycache__``); in
        ``NUMBA_CACHE_DIR`` where that is set, as numba does.
        """

        def __init__(self, py_func: Callable[..., Any], py_file: str,
                     folder: str | None = None) -> None:
            super().__init__(py_func, py_file)
            if folder is not None:
                self._cache_path = folder

        def get_source_stamp(self) -> bytes:
            return compiled_sources_hash()

        @classmethod
        def from_function(cls, py_func: Callable[..., Any],
                          py_file: str) -> _CompiledSourcesLocator | None:
            if not _is_compiled_source(py_file):
                return None
            if _numba.config.CACHE_DIR:  # NUMBA_CACHE_DIR is honoured, as numba does
                chosen = os.path.join(_numba.config.CACHE_DIR,
                                      cls.get_suitable_cache_subpath(py_file))
            else:
                chosen = str(shared_cache_folder(py_file))
            for folder in (chosen, None):          # None: in-tree
                located = cls(py_func, py_file, folder)
                try:
                    located.ensure_cache_path()
                except OSError:
                    continue
                return located
            return None

    _IMPL = getattr(_caching, 'CacheImpl', None) or getattr(_caching, '_CacheImpl')
    _LOCATORS = _IMPL._locator_classes
    if _CompiledSourcesLocator not in _LOCATORS:
        _LOCATORS.insert(0, _CompiledSourcesLocator)

    def jit(f: F, cache: bool = True, wide: bool = False) -> F:
        """
        Compile ``f`` (nogil: ensembles run blocks of bodies in several threads at once).

        ``wide``: a loop over a block of bodies, its vectorised loops on 512-bit registers
        where the CPU has them (:data:`WIDE_VECTOR_LOOPS`).
        """
        if wide:
            WIDE_VECTOR_LOOPS.add(f.__qualname__)
        return cast(F, _numba.njit(**{**JIT_OPTIONS, 'cache': cache})(f))

    def jit_inline(f: F, cache: bool = True) -> F:
        """
        Compile ``f`` to be inlined into its callers at numba's IR level.

        No call (its arguments passed, its registers saved: more than the arithmetic of a
        small step), and LLVM optimises across the inlined body. Only for the per-step hot
        path: inlining multiplies compile time.
        """
        return cast(F, _numba.njit(**{**JIT_OPTIONS, 'cache': cache}, inline='always')(f))

    def called(f: F) -> F:
        """Compile a :func:`jit_inline` function separately (not inlined), for cold paths."""
        return jit(python_source(f))

    def _inlined(f: Callable[..., Any]) -> bool:
        return bool(getattr(f, 'targetoptions', {}).get('inline') == 'always')
else:
    def jit(f: F, cache: bool = True, wide: bool = False) -> F:
        """Return ``f`` unchanged (numba absent or disabled)."""
        return f

    jit_inline = jit

    def called(f: F) -> F:
        """Return ``f`` unchanged (numba absent or disabled)."""
        return f

    def _inlined(f: Callable[..., Any]) -> bool:
        return False


def jit_wide(f: F, cache: bool = True) -> F:
    """:func:`jit` for a loop over a block of bodies (``wide=True``: 512-bit vectors)."""
    return jit(f, cache=cache, wide=True)


def python_source(f: F) -> F:
    """Return the Python function behind a compiled one (it runs on numpy arrays too)."""
    return cast(F, getattr(f, 'py_func', f))


def specialise(f: F, namespace: dict[str, Any], suffix: str, cache: bool = True) -> F:
    """
    Return a copy of compiled function ``f`` that sees the globals ``namespace``, compiled as f.

    Its global names (the functions it calls) are looked up in ``namespace``, which numba
    treats as compile-time constants, as it does a module's globals: ``kernels.methods``
    binds a method's functions this way. The copy is named ``<name>__<suffix>`` (its own
    entry in numba's cache); ``cache=False`` keeps it out of the cache.
    """
    source = python_source(f)
    copy = types.FunctionType(source.__code__, namespace, source.__name__,
                              source.__defaults__, source.__closure__)
    copy.__qualname__ = f'{source.__qualname__}__{suffix}'
    copy.__doc__ = source.__doc__
    copy.__annotations__ = dict(source.__annotations__)
    if _inlined(f):
        return cast(F, jit_inline(copy, cache=cache))
    return cast(F, jit(copy, cache=cache, wide=source.__qualname__ in WIDE_VECTOR_LOOPS))


#: A first call of a compiled loop that takes longer than this [s] says so on stderr (it is
#: compiling: tens of seconds; loading it from the cache takes well under this).
COMPILE_NOTICE_SECONDS = 1.5
#: Environment variable that silences :func:`first_use`'s notices when set to ``0`` (a quiet
#: command sets it, so that the worker processes it starts, which inherit it, say nothing).
COMPILE_NOTICE_VARIABLE = 'TUMBLE_ROS_COMPILE_NOTICE'


@contextlib.contextmanager
def compile_notices(on: bool) -> Iterator[None]:
    """Within: :func:`first_use`'s notices on or off, here and in processes started here."""
    before = os.environ.get(COMPILE_NOTICE_VARIABLE)
    if not on:
        os.environ[COMPILE_NOTICE_VARIABLE] = '0'
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(COMPILE_NOTICE_VARIABLE, None)
        else:
            os.environ[COMPILE_NOTICE_VARIABLE] = before


def needs_compiling(function: Callable[..., Any]) -> bool:
    """
    Tell whether a call of ``function`` may compile (numba on, no compiled signature yet).

    A caller that calls a loop many times wraps in :func:`first_use` only the calls for which
    this holds (the context manager costs ~2 us a call: a segment per impact).
    """
    return COMPILED and _uncompiled(function)


def _uncompiled(function: Callable[..., Any]) -> bool:
    """
    Tell whether ``function`` is a numba dispatcher without any compiled signature yet.

    Its ``overloads`` mapping when it has one (``signatures`` builds a list of type tuples on
    each call: 2 us, on every step of a run with 10,000 impacts).
    """
    overloads = getattr(function, 'overloads', None)
    if overloads is not None:
        return len(overloads) == 0
    return getattr(function, 'signatures', None) == []


def load_for(function: Callable[..., Any], *args: Any) -> None:
    """
    Load compiled ``function`` for the types of ``args`` (compile it if not cached), no call.

    numba loads a cached loop (or compiles it) on its first call for its argument types: ~0.7 s
    for an ensemble's loops. Loading them before a timed call keeps that out of the timing
    (``EnsembleResult.wall_time``). The types are numba's of each argument, as a call's
    dispatch takes them. Nothing for a plain Python function.
    """
    if COMPILED and hasattr(function, 'compile'):
        function.compile(tuple(_numba.typeof(a) for a in args))


@contextlib.contextmanager
def first_use(function: Callable[..., Any], label: str,
              after: float = COMPILE_NOTICE_SECONDS,
              out: TextIO | None = None) -> Iterator[None]:
    """
    Around a call of compiled ``function``: say so when its first call in this process is slow.

    numba compiles a loop on its first call for its argument types (then keeps it in its
    cache, :func:`shared_cache_folder`), so a run waits only for the loops it uses; a later
    process loads it from the cache (well under a second, but seconds on a busy machine). When
    ``function`` has no compiled signature yet in this process and still none after ``after``
    seconds, a line goes to ``out`` (stderr: a node's log): ``compiling the <label> (first use,
    cached afterwards)...``, or ``loading the <label> from the numba cache...`` when the cache
    holds it for the current source (:func:`_in_cache`); then ``... the <label> compiled in
    <n> s`` or ``loaded in <n> s``, as numba's cache counters say once it is ready. Nothing
    otherwise (ready in time, a plain Python function, the environment variable
    :data:`COMPILE_NOTICE_VARIABLE` set to ``0``).
    """
    if (not COMPILED or not _uncompiled(function)
            or os.environ.get(COMPILE_NOTICE_VARIABLE) == '0'):
        yield
        return
    stream = out if out is not None else sys.stderr
    started = time.monotonic()
    said: list[bool] = []    # [whether the notice said loading], once said

    def notice() -> None:
        # numba adds the signature once the loop is compiled (or loaded), before it runs it: a
        # long first call that is already running says nothing (an ensemble of many bodies)
        if getattr(function, 'signatures', None):
            return
        loading = _in_cache(function)
        said.append(loading)
        print(f'loading the {label} from the numba cache...' if loading else
              f'compiling the {label} (first use, cached afterwards)...', file=stream,
              flush=True)

    timer = threading.Timer(after, notice)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        if said:
            misses = getattr(function, '_cache_misses', None)
            loaded = said[0] if misses is None else not misses
            print(f"... the {label} {'loaded' if loaded else 'compiled'} in "
                  f'{time.monotonic() - started:.0f} s', file=stream, flush=True)


def _in_cache(function: Callable[..., Any]) -> bool:
    """
    Tell whether numba's cache holds compiled code of ``function`` for its current source.

    Its index file lists entries and matches the source file's stamp (numba's own check, which
    gives no entries otherwise): the first call then loads them (unless its argument types are
    new). False for anything else (no cache, a stand-in, an unreadable index).
    """
    cache_file = getattr(getattr(function, '_cache', None), '_cache_file', None)
    try:
        return bool(cache_file is not None and cache_file._load_index())
    except Exception:   # (numba's private API: any failure means "cannot tell")
        return False

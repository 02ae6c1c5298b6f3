"""numba's inlining with one copy of the callee (core.compiling.numba_inlining): less work."""
from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import types
from typing import Any, Callable, Iterator

import pytest

from tumble_ros.core.compiling.jit import COMPILED, jit, jit_inline
from tumble_ros.core.compiling.numba_inlining import (copy_callee_once, one_copy_source,
                                                      PER_BLOCK_COPY)

needs_numba = pytest.mark.skipif(not COMPILED, reason='numba not available')


def _branchy(x: float, n: int) -> float:
    """Several blocks (a loop, branches) and a dozen variables: what the kernels inline."""
    total = 0.0
    for k in range(n):
        a = x * k
        b = a * a - 1.0
        if b > 0.0:
            total += a / b
        elif b < -0.5:
            total -= b
        else:
            total += 1.0
        if total > 1e6:
            break
    c = total * 0.5
    d = c + x
    return d if d > 0.0 else -d


#: What :func:`_caller` calls: in Python this; compiled, its inlined copy (``_compiled_caller``).
branchy = _branchy


def _caller(x: float, n: int) -> float:
    """Inline ``_branchy`` three times (each call site gets its own copy)."""
    return branchy(x, n) + branchy(x + 1.0, n) * branchy(x - 1.0, n)


def _compiled_caller(name: str) -> Callable[..., Any]:
    """Return a new dispatcher of :func:`_caller` named ``name`` (not cached: it compiles)."""
    inlined = jit_inline(types.FunctionType(_branchy.__code__, {}, '_branchy'), cache=False)
    function = types.FunctionType(_caller.__code__, {'branchy': inlined}, name)
    function.__qualname__ = name
    return jit(function, cache=False)


@contextlib.contextmanager
def _numbas_own_inline_ir() -> Iterator[None]:
    """Within: numba's ``inline_ir`` as numba ships it (the copy a block)."""
    from numba.core.inline_closurecall import InlineWorker
    edited = InlineWorker.inline_ir
    InlineWorker.inline_ir = edited.numba_inline_ir
    try:
        yield
    finally:
        InlineWorker.inline_ir = edited


@contextlib.contextmanager
def _counting_variable_copies() -> Iterator[list[int]]:
    """Within: count the copies of numba IR variables (``ir.Var.__deepcopy__`` calls)."""
    from numba.core import ir
    plain = ir.Var.__deepcopy__
    count = [0]

    def counted(self: Any, memo: dict[int, Any]) -> Any:
        count[0] += 1
        return plain(self, memo)

    ir.Var.__deepcopy__ = counted
    try:
        yield count
    finally:
        ir.Var.__deepcopy__ = plain


def _machine_code(function: Callable[..., Any], name: str) -> tuple[str, str]:
    """
    Return the LLVM IR and the assembly of compiled ``function``, its own names masked.

    In the IR also the numbers numba's counters give each compilation: the blocks' labels
    (``B40``) and the inlined variables' versions (``_branchy_v2_total``); in both, the sizes of
    the string constants that hold a mangled name (``[125 x i8]``, ``.size ..., 125``: its
    counters have more digits when the process compiled more before; seen in full runs, 126
    against 125).
    """
    def mask(text: str) -> str:
        text = re.sub(rf'\w*{name}\w*', 'F', text)
        return re.sub(r'(?<=\[)\d+(?= x i8\])|(?<=\.size\t"\.const\.missing Environment: F", )\d+',
                      'N', text)

    ir_text = next(iter(function.inspect_llvm().values()))
    asm = next(iter(function.inspect_asm().values()))
    ir_text = re.sub(r'\bB\d+|_v\d+_', 'N', mask(ir_text))
    return re.sub(' +', ' ', ir_text), mask(asm)       # (the comments aligned to the labels)


@needs_numba
def test_the_pinned_numba_gets_the_edit_when_it_first_inlines():
    """
    The requirements' numba holds the lines edited: a numba that does not is noticed here.

    Not at import: a process that imports the package (a node, loading its loops from the
    cache) does not import numba's inliner; it does once something compiles.
    """
    check = ('import sys, tumble_ros.core, tumble_ros.nodes.sim; '
             'print("numba.core.inline_closurecall" in sys.modules)')
    imported = subprocess.run([sys.executable, '-c', check], capture_output=True, text=True,
                              check=True)
    assert imported.stdout.strip() == 'False', imported
    jit(lambda x: x + 1.0, cache=False)(1.0)     # compiles: the pipeline's inlining pass runs
    from numba.core.inline_closurecall import InlineWorker
    assert getattr(InlineWorker.inline_ir, 'copies_callee_once', False)
    assert one_copy_source(InlineWorker.inline_ir.numba_inline_ir) is not None
    assert copy_callee_once(InlineWorker)          # already edited: left as it is
    assert InlineWorker.inline_ir.copies_callee_once


def test_a_source_without_the_lines_is_left_alone():
    class Worker:
        def inline_ir(self) -> None:
            """Not numba's."""

    plain = Worker.inline_ir
    assert one_copy_source(plain) is None
    assert not copy_callee_once(Worker)
    assert Worker.inline_ir is plain
    assert PER_BLOCK_COPY.count('copy.deepcopy') == 1


@needs_numba
def test_the_same_machine_code_with_fewer_copies():
    """One inlined function compiled both ways: the same code byte for byte, and the result."""
    with _counting_variable_copies() as copies_once:
        edited = _compiled_caller('caller_once')
        edited_result = edited(0.3, 50)
    with _numbas_own_inline_ir(), _counting_variable_copies() as copies_a_block:
        plain = _compiled_caller('caller_each')
        plain_result = plain(0.3, 50)
    assert edited_result == plain_result == _caller(0.3, 50)
    # (names of one length: numba keeps the name in a constant of that size)
    assert _machine_code(edited, 'caller_once') == _machine_code(plain, 'caller_each')
    # numba's copy copies the scope's variables once a block; the edit once a call site
    assert copies_once[0] > 0
    assert copies_a_block[0] > 3 * copies_once[0], (copies_a_block, copies_once)

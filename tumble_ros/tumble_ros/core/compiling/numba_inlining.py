"""
numba's IR inlining with one copy of the callee, not one a block: the loops compile in less CPU.

The kernels inline their per-step functions at numba's IR level (``jit.jit_inline``, numba's
``inline='always'``). For every call it inlines, numba deep-copies the callee's IR
(``numba.core.inline_closurecall.InlineWorker.inline_ir``, its nested ``copy_ir``) one block at
a time, each block with a memo of its own. Every variable refers to the function's scope, which
holds every variable, so each block's copy copies the whole scope again: the copy costs the
blocks times the variables. Compiling the ``splitting`` loops spent a quarter of its time
there (py-spy, 2026-12-06: 25 % of 34 s).

:func:`copy_callee_once` makes that copy one ``copy.deepcopy`` of the blocks together (one memo:
the scope and each variable copied once, as the blocks share them in the callee). numba has no
option for it: the method is numba's own source with that one edit, compiled in numba's module
(the edit is the one numba-cuda's pull request 689 proposes, numba issue 8989 the discussion).
Nothing else changes: the inlined IR is the same, and the machine code the same byte for byte
(tests/test_core_numba_inlining.py). Alternated, the ``splitting`` loops without extra
torques compiled in 34.6-35.6 s of CPU before, 25.8-27.8 s after; the ``dop853`` loops in
20.1-20.6 s, then 15.9-18.2 s; the whole warm-up in 140-143 s, then 109-116 s
(benchmarks/HISTORY.md, "The inliner's copies").

Where numba's source is not the one this edits (another numba version), nothing is changed and
numba compiles as it always did, only slower; the test says so.

The edit is made when numba first inlines (:func:`copy_callee_once_when_inlining`), not at
import: a process that only loads its loops from the cache (a node) does not import numba's
inliner (26 ms).
"""
from __future__ import annotations

import functools
import inspect
import textwrap
from typing import Any

__all__ = ['PER_BLOCK_COPY', 'ONE_COPY', 'copy_callee_once', 'copy_callee_once_when_inlining',
           'one_copy_source']

#: numba's copy of the callee's blocks, one deep copy (and one memo) a block: the lines edited.
PER_BLOCK_COPY = """\
        for block_label, block in the_ir.blocks.items():
            new_block = copy.deepcopy(the_ir.blocks[block_label])
            kernel_copy.blocks[block_label] = new_block
"""
#: What replaces them: the blocks copied together, the scope and its variables once.
ONE_COPY = """\
        kernel_copy.blocks = copy.deepcopy(the_ir.blocks)
"""


def one_copy_source(method: Any) -> str | None:
    """
    Return the source of numba's ``inline_ir`` ``method`` with :data:`ONE_COPY`, dedented.

    None when the source does not hold :data:`PER_BLOCK_COPY` exactly once (another numba).
    """
    source = textwrap.dedent(inspect.getsource(method))
    if source.count(PER_BLOCK_COPY) != 1:
        return None
    return source.replace(PER_BLOCK_COPY, ONE_COPY)


def copy_callee_once(worker: Any) -> bool:
    """
    Give numba's ``InlineWorker`` class ``worker`` an ``inline_ir`` that copies a callee once.

    Returns whether ``worker.inline_ir`` is now the edited method (True also when it already
    was). The edited source is compiled with the line numbers of numba's file and its module's
    globals, so a traceback through it reads as one through numba's.
    """
    plain = worker.inline_ir
    if getattr(plain, 'copies_callee_once', False):
        return True
    source = one_copy_source(plain)
    if source is None:
        return False
    module = inspect.getmodule(plain)
    first_line = inspect.getsourcelines(plain)[1]
    namespace: dict[str, Any] = {}
    code = compile('\n' * (first_line - 1) + source, inspect.getfile(plain), 'exec')
    exec(code, vars(module), namespace)          # (numba's own source, one edit)
    edited: Any = functools.wraps(plain)(namespace[plain.__name__])
    edited.copies_callee_once = True
    edited.numba_inline_ir = plain
    worker.inline_ir = edited
    return True


def copy_callee_once_when_inlining(untyped_passes: Any) -> None:
    """
    Make :func:`copy_callee_once`'s edit when numba's inlining pass first runs, not now.

    ``untyped_passes``: numba's module of that pass (``InlineInlinables``, which every compiled
    function's pipeline runs before any inlining, and which imports the inliner's module as it
    runs). Its ``run_pass`` makes the edit, then gives the class numba's own ``run_pass`` back.
    """
    pass_class = untyped_passes.InlineInlinables
    plain = pass_class.run_pass
    if getattr(plain, 'edits_numba', False):
        return

    def run_pass(self: Any, state: Any) -> Any:
        from numba.core import inline_closurecall
        copy_callee_once(inline_closurecall.InlineWorker)
        pass_class.run_pass = plain
        return plain(self, state)

    run_pass.edits_numba = True          # type: ignore[attr-defined]
    pass_class.run_pass = run_pass

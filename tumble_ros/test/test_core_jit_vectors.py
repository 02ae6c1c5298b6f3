"""The block loops' 512-bit vectors on AVX-512 (core.compiling.jit ``wide=True``)."""
from __future__ import annotations

import re

import numpy as np
import pytest

from tumble_ros.core import kernels
from tumble_ros.core.compiling.jit import (_wide_ir, COMPILED, jit, PREFER_512_BIT,
                                           WIDE_VECTOR_LOOPS)

needs_numba = pytest.mark.skipif(not COMPILED, reason='numba not available')

IR = """declare i32 @"g"(i8* %".1")

define i32 @"f"(i8* %".1") noinline
{
entry:
  %"x" = call i32 @"g"(i8* %".1")
  ret i32 %"x"
}

define i8* @"cpython.f"(i8* %"py_args")
{
entry:
  ret i8* %"py_args"
}
"""


def test_every_function_defined_gets_the_attribute_and_nothing_else_changes():
    wide = _wide_ir(IR)
    assert PREFER_512_BIT == '"prefer-vector-width"="512"'
    assert wide.count(PREFER_512_BIT) == 2
    assert 'define i32 @"f"(i8* %".1") noinline ' + PREFER_512_BIT + '\n{' in wide
    assert 'define i8* @"cpython.f"(i8* %"py_args") ' + PREFER_512_BIT + '\n{' in wide
    assert 'declare i32 @"g"(i8* %".1")\n' in wide           # a declaration: no body, left
    assert wide.replace(' ' + PREFER_512_BIT, '') == IR


def _avx512() -> bool:
    """Tell whether this CPU has AVX-512 (LLVM's features of the host, as numba reads them)."""
    from numba.core.codegen import get_host_cpu_features
    return '+avx512f' in str(get_host_cpu_features()).split(',')


@needs_numba
def test_a_wide_loop_runs_on_512_bit_registers_exactly_where_the_cpu_has_them():
    """The same loop, compiled wide and not: zmm only wide, on AVX-512; the same bits."""
    def scaled_sum_wide(a, x, y, out):
        for i in range(x.shape[0]):
            out[i] = y[i] + a * x[i]

    def scaled_sum_narrow(a, x, y, out):
        for i in range(x.shape[0]):
            out[i] = y[i] + a * x[i]

    wide = jit(scaled_sum_wide, cache=False, wide=True)
    narrow = jit(scaled_sum_narrow, cache=False)
    assert 'scaled_sum_wide' in {name.rsplit('.', 1)[-1] for name in WIDE_VECTOR_LOOPS}
    x = np.random.default_rng(1).normal(size=1001)
    y = np.random.default_rng(2).normal(size=1001)
    out_wide, out_narrow = np.empty_like(x), np.empty_like(x)
    wide(np.pi, x, y, out_wide)
    narrow(np.pi, x, y, out_narrow)
    assert out_wide.tobytes() == out_narrow.tobytes() == (y + np.pi * x).tobytes()
    wide_asm = next(iter(wide.inspect_asm().values()))
    narrow_asm = next(iter(narrow.inspect_asm().values()))
    assert 'zmm' not in narrow_asm
    if _avx512():
        assert re.search(r'v(mul|add)pd\s+[^\n]*%zmm', wide_asm), wide_asm[:3000]
    else:                     # the attribute asks for what the CPU does not have: nothing
        assert 'zmm' not in wide_asm


@needs_numba
def test_the_block_loops_are_wide_and_the_single_body_loops_are_not():
    """Which compiled functions get 512-bit vectors: the lockstep and lanes loops only."""
    for name in ('splitting', 'rk4', 'dop853'):
        loops = kernels.loops(name)
        block = loops.block_advance if name != 'dop853' else loops.lanes_advance
        assert block.py_func.__qualname__ in WIDE_VECTOR_LOOPS, name
        for single in (loops.advance, loops.step, loops.dense, loops.emit,
                       loops.ensemble_advance):
            assert single.py_func.__qualname__ not in WIDE_VECTOR_LOOPS, (name, single)
    from tumble_ros.core.kernels import dop853, lanes, lockstep, rk4, splitting
    for function in (rk4.block_rhs, rk4.block_step, splitting.block_flow, splitting.block_step,
                     dop853.lanes_stages, lanes.lanes_rhs, lanes.lanes_block,
                     lockstep.block_step, lockstep.block_track, lockstep.block_euler):
        assert function.py_func.__qualname__ in WIDE_VECTOR_LOOPS, function
    for function in (lanes.lane_load, lockstep.load_body, rk4.block_load, dop853.step):
        assert function.py_func.__qualname__ not in WIDE_VECTOR_LOOPS, function

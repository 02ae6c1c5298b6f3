"""
The compiled methods: one table (:data:`KERNELS`), and the loops built from it per method.

Each method is a module with three functions on one body's state ``st`` (layout :data:`ST`):

* ``start(p, extra, cfg, st)``: set up a segment whose span is st[ST.TAU_BOUND] (its step
  count and step, or its first adaptive step); called for every segment, also an empty one
  (st[ST.STATUS] then already FINISHED);
* ``step(p, extra, cfg, st) -> FAIL code``: one step from st[ST.Y] at local time st[ST.TAU],
  setting st[ST.TAU_OLD], st[ST.TAU] (exactly st[ST.TAU_BOUND] at the end) and st[ST.NFEV];
* ``dense(p, extra, cfg, st, tau)``: the state at local time tau of the last step, to
  st[ST.SCRATCH].

:func:`loops` builds the method's copy of the :mod:`.stepping` and :mod:`.ensemble` loops
with those three functions bound in (numba inlines them: no dispatch at run time). A copy,
not a closure: numba's cache key of a closure pickles the compiled functions it closes over,
and a compiled function pickles with a new random id in every process, so a closure would be
compiled again by every process. A new compiled integrator is one module and one line in
:data:`KERNELS` (benchmarks/HISTORY.md, "Adding a compiled integrator").
"""
from __future__ import annotations

import inspect
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, NamedTuple

from tumble_ros.core.compiling.jit import COMPILED_SOURCES, specialise
from tumble_ros.core.kernels import dop853, ensemble, lanes, lockstep, rk4, splitting, stepping
from tumble_ros.core.kernels.layout import Array, CF, Extra

__all__ = ['KERNELS', 'Loops', 'loops', 'kernel_id', 'kernel_name', 'loops_for', 'cached',
           'ensemble_init', 'ensemble_advance', 'has_lockstep', 'has_lockstep_module',
           'has_lanes', 'has_lanes_module', 'BLOCK_FUNCTIONS', 'LANE_FUNCTIONS']

#: The functions a method's module defines to be stepped in lockstep (:mod:`.lockstep`):
#: ``block_start``, ``block_step``, ``block_load``, ``block_store`` (see :mod:`.splitting`,
#: :mod:`.rk4`); optional. A module may also define ``block_dense`` (the block's dense output:
#: :mod:`.splitting`; without it a sample inside a step is written body by body).
BLOCK_FUNCTIONS = ('block_start', 'block_step', 'block_load', 'block_store')

#: The functions a method's module defines to be stepped as lanes with their own clocks
#: (:mod:`.lanes`): an adaptive method's step split (see :mod:`.dop853`); optional.
LANE_FUNCTIONS = ('lanes_start', 'lanes_attempt', 'lanes_stages', 'lanes_control',
                  'lanes_accept')

#: The compiled methods: registry key (``Stepper.kernel``) -> module with start, step, dense.
KERNELS: dict[str, ModuleType] = {
    'rk4': rk4,
    'dop853': dop853,
    'splitting': splitting,
}


class Loops(NamedTuple):
    """One method's compiled loops (signatures: :mod:`.stepping`, :mod:`.ensemble`)."""

    seg_init: Callable[..., None]
    step: Callable[..., bool]
    dense: Callable[..., None]
    emit: Callable[..., int]
    advance: Callable[..., tuple[int, int, int]]
    ensemble_init: Callable[..., None]
    ensemble_advance: Callable[..., None]
    block_init: Callable[..., None] | None = None
    block_advance: Callable[..., None] | None = None
    lanes_advance: Callable[..., None] | None = None


_BUILT: dict[str, tuple[ModuleType, Loops]] = {}


def kernel_id(name: str) -> int:
    """Return the number of method ``name`` in :data:`KERNELS` (1, 2, ...: cfg[CF.METHOD])."""
    if name not in KERNELS:
        raise KeyError(f'no compiled method {name!r}; registered: {", ".join(KERNELS)}')
    return list(KERNELS).index(name) + 1


def kernel_name(cfg: Array) -> str:
    """Return the registry key of the method of a config array (layout :data:`CF`)."""
    return list(KERNELS)[int(cfg[CF.METHOD]) - 1]


def cached(module: ModuleType) -> bool:
    """
    Return whether the loops of ``module``'s method are kept in numba's cache.

    Only for a module among :data:`~tumble_ros.core.compiling.jit.COMPILED_SOURCES` (its edits
    invalidate the cache); any other (a test's) is compiled in every process.
    """
    try:
        return Path(inspect.getfile(module)).resolve() in COMPILED_SOURCES
    except (OSError, TypeError):
        return False


def _copies(template: ModuleType, names: tuple[str, ...], bound: dict[str, Any], suffix: str,
            cache: bool) -> dict[str, Any]:
    """Copy functions ``names`` of ``template`` into one namespace where ``bound`` is bound."""
    namespace = dict(vars(template))
    namespace.update(bound)
    for name in names:
        namespace[name] = specialise(getattr(template, name), namespace, suffix, cache)
    return namespace


def loops(name: str) -> Loops:
    """Return the compiled loops of method ``name`` of :data:`KERNELS` (built on first use)."""
    module = KERNELS[name]
    built = _BUILT.get(name)
    if built is None or built[0] is not module:
        built = module, loops_for(module, name)
        _BUILT[name] = built
    return built[1]


def loops_for(module: ModuleType, suffix: str) -> Loops:
    """Build the loops of the method of ``module`` (compiled function names end __suffix)."""
    cache = cached(module)
    bound = {'method_start': module.start, 'method_step': module.step,
             'method_dense': module.dense}
    single = _copies(stepping, stepping.LOOP_FUNCTIONS, bound, suffix, cache)
    many = _copies(ensemble, ensemble.LOOP_FUNCTIONS,
                   {name: single[name] for name in ('seg_init', 'emit', 'advance')}, suffix,
                   cache)
    blocks: dict[str, Any] = {}
    shared = {name: single[name] for name in ('seg_init', 'emit', 'track_update')}
    if has_lockstep_module(module):
        block = _copies(lockstep, lockstep.LOOP_FUNCTIONS,
                        {**{f'method_{name}': getattr(module, name) for name in BLOCK_FUNCTIONS},
                         'method_block_dense': getattr(module, 'block_dense',
                                                       lockstep.no_block_dense),
                         **shared}, suffix, cache)
        blocks.update(block_init=block['block_init'], block_advance=block['block_advance'])
    if has_lanes_module(module):
        lane = _copies(lanes, lanes.LOOP_FUNCTIONS,
                       {**{f'method_{name}': getattr(module, name) for name in LANE_FUNCTIONS},
                        **shared}, suffix, cache)
        blocks.update(lanes_advance=lane['lanes_advance'])
    return Loops(single['seg_init'], single['step'], single['dense'], single['emit'],
                 single['advance'], many['ensemble_init'], many['ensemble_advance'], **blocks)


def has_lockstep_module(module: ModuleType) -> bool:
    """Return whether a method's module can step a block of bodies in lockstep."""
    return all(callable(getattr(module, name, None)) for name in BLOCK_FUNCTIONS)


def has_lanes_module(module: ModuleType) -> bool:
    """Return whether a method's module can step a block of bodies as lanes (:mod:`.lanes`)."""
    return all(callable(getattr(module, name, None)) for name in LANE_FUNCTIONS)


def has_lanes(name: str) -> bool:
    """Return whether method ``name`` of :data:`KERNELS` can be stepped in :mod:`.lanes`."""
    return name in KERNELS and has_lanes_module(KERNELS[name])


def has_lockstep(name: str) -> bool:
    """Return whether method ``name`` of :data:`KERNELS` can be stepped in :mod:`.lockstep`."""
    return name in KERNELS and has_lockstep_module(KERNELS[name])


def ensemble_init(extra: Extra, cfg: Array, *args: Any) -> None:
    """Run the ``ensemble_init`` loop of the method of ``cfg`` (:mod:`.ensemble`)."""
    loops(kernel_name(cfg)).ensemble_init(extra, cfg, *args)


def ensemble_advance(extra: Extra, cfg: Array, *args: Any) -> None:
    """Run the ``ensemble_advance`` loop of the method of ``cfg`` (:mod:`.ensemble`)."""
    loops(kernel_name(cfg)).ensemble_advance(extra, cfg, *args)

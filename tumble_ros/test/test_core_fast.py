"""
The fast path (compiled loops, core/kernels/) against the reference step-by-step path.

Same method and step, same trajectory to <= 1e-12; the same Propagator API and failures;
the kernels' own source run as plain Python (numba disabled) gives the same numbers.
"""
import importlib
import json
import os
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from tumble_ros.core import (Impact, IntegrationError, IntegratorSettings, kernels, load_scenario,
                             Propagator, Scenario, simulate)

CONFIG = Path(__file__).resolve().parents[1] / 'config'
FAST_METHODS = {'rk4': {'step': 1e-3}, 'dop853': {'rtol': 1e-10, 'atol': 1e-12},
                'splitting': {'step': 1e-3},
                'splitting4': {'step': 2e-3}, 'splitting6': {'step': 5e-3}}
needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')
IMPACTS = (Impact(0.5, 3e-7, (3e6, -1e6, 2e5)),
           Impact(1.2, 1e-3, (0.0, 1e3, 2e3), frame='orbital'),
           Impact(1.2005, 2e-3, (5e2, 0.0, 0.0)))


def fig9(**changes):
    return load_scenario(CONFIG / 'fig9.yaml').replace(**changes)


def assert_same(a, b, tol=1e-12):
    assert a.success and b.success, (a.message, b.message)
    np.testing.assert_array_equal(a.t, b.t)
    scale = np.max(np.abs(b.omega))
    assert np.max(np.abs(a.omega - b.omega)) <= tol * scale
    assert np.max(np.abs(a.quaternion - b.quaternion)) <= tol
    assert np.max(np.abs(a.euler - b.euler)) <= tol * max(1.0, np.max(np.abs(b.euler)))
    assert np.max(np.abs(a.jacobi - b.jacobi)) <= tol * np.max(np.abs(b.jacobi))


@needs_numba
@pytest.mark.parametrize('method', sorted(FAST_METHODS))
def test_fast_and_reference_paths_give_the_same_trajectory(method):
    sc = fig9(duration=2.0, output_interval=0.01, impacts=IMPACTS,
              integrator=IntegratorSettings(method=method, **FAST_METHODS[method]))
    fast, ref = simulate(sc, fast=True), simulate(sc, fast=False)
    assert_same(fast, ref)
    assert (fast.n_steps, fast.nfev) == (ref.n_steps, ref.nfev)


@needs_numba
@pytest.mark.parametrize('method', ['rk4', 'dop853', 'splitting4'])
def test_euler_tracking_through_long_steps_matches(method):
    """
    Check the Euler angles when phi and psi turn by several radians per step.

    The tracking subdivides the step with dense output on both paths, and the continuous
    angles agree.
    """
    sc = Scenario(inertia=(1.0, 1.3, 1.9), omega0=(20.0, 5.0, 300.0), euler0=(0.5, 0.2, 0.6),
                  duration=0.5, output_interval=0.05,
                  integrator=IntegratorSettings(method=method, step=5e-3, rtol=1e-7, atol=1e-7))
    fast, ref = simulate(sc, fast=True), simulate(sc, fast=False)
    assert_same(fast, ref)
    assert np.ptp(ref.euler[:, 1]) > 20 * np.pi  # psi really winds up (~300 rad/yr)


@needs_numba
@pytest.mark.parametrize('method', ['dop853', 'splitting'])
def test_incremental_api_is_the_same_on_both_paths(method):
    """
    Drive both paths through the incremental API the way the sim node does.

    advance_to/sample at irregular times, an impact scheduled while running,
    pop_completed_impacts.
    """
    sc = fig9(duration=3.0, output_interval=0.1, impacts=IMPACTS[:1],
              integrator=IntegratorSettings(method=method, **FAST_METHODS[method]))
    props = [Propagator(sc, fast=True), Propagator(sc, fast=False)]
    assert [p.fast for p in props] == [True, False]
    late = Impact(2.0, 1e-3, (0.0, 0.0, 4e3), frame='orbital')
    samples = [[], []]
    completed = [[], []]
    for t in (0.0, 0.25, 0.5, 0.5 + 3e-7, 0.9, 1.7, 1.75, 2.0005, 2.5, 3.0):
        for k, prop in enumerate(props):
            if t == 0.9:
                prop.schedule(late)
            samples[k].append(prop.sample(t))
            completed[k] += prop.pop_completed_impacts()
    for a, b in zip(*samples):
        assert a.t == b.t
        np.testing.assert_allclose(a.omega, b.omega, rtol=0, atol=1e-12 * 30)
        np.testing.assert_allclose(a.quaternion, b.quaternion, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.euler, b.euler, rtol=0, atol=1e-11)
        assert a.jacobi == pytest.approx(b.jacobi, rel=1e-12)
    assert len(completed[0]) == len(completed[1]) == 2
    for (i0, s0, e0), (i1, s1, e1) in zip(*completed):
        assert i0 == i1
        np.testing.assert_allclose(e0 - s0, e1 - s1, atol=1e-12 * 30)
    assert props[0].n_steps == props[1].n_steps


@needs_numba
def test_failures_are_reported_the_same_way():
    # (|omega0| is bounded: a torque pulse of 1e300, which only needs to be finite, makes the
    # state overflow within the first step)
    sc = Scenario(inertia=(1.0, 1.6, 2.2), impacts=(Impact(0.0, 0.5, (1e300, 1e300, 1e300)),),
                  duration=1.0,
                  integrator=IntegratorSettings(method='rk4', step=0.1))
    with np.errstate(all='ignore'):
        fast, ref = (simulate(sc, t_eval=[0.0, 0.5, 1.0], fast=True),
                     simulate(sc, t_eval=[0.0, 0.5, 1.0], fast=False))
    assert not fast.success and fast.message == ref.message and 'non-finite' in fast.message
    np.testing.assert_array_equal(fast.omega, ref.omega)
    with np.errstate(all='ignore'):
        sc = sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-13, atol=1e-300))
        fast, ref = (simulate(sc, t_eval=[0.0, 1.0], fast=True),
                     simulate(sc, t_eval=[0.0, 1.0], fast=False))
    assert not fast.success and fast.message == ref.message, (fast.message, ref.message)
    prop = Propagator(sc.replace(integrator=IntegratorSettings(method='splitting', step=0.1)),
                      fast=True)
    with pytest.raises(IntegrationError, match='non-finite'):
        prop.advance_to(1.0)
    assert prop.status == 'failed'


def test_fast_path_capability_and_fallback():
    sc = fig9(duration=0.1, output_interval=0.01)
    with pytest.raises(ValueError, match='no compiled loop'):
        Propagator(sc.replace(integrator=IntegratorSettings(method='rk45')), fast=True)
    euler = sc.replace(attitude='euler', integrator=IntegratorSettings(method='rk4', step=1e-3))
    with pytest.raises(ValueError, match='quaternion'):
        Propagator(euler, fast=True)
    assert Propagator(euler).fast is False  # default: silently the reference path
    assert Propagator(sc.replace(integrator=IntegratorSettings(method='rk45'))).fast is False
    assert Propagator(sc).fast is kernels.COMPILED
    assert Propagator(sc, split_impacts=False).fast is False


@needs_numba
def test_warm_up_compiles_the_single_body_and_ensemble_loops():
    from tumble_ros.cli.warmup import warm_up

    assert warm_up() > 0.0
    for name in kernels.KERNELS:  # every registered method's own loops
        loops = kernels.loops(name)
        for loop in (loops.advance, loops.ensemble_advance, loops.ensemble_init):
            # compiled (or loaded from the cache) for the real argument types
            assert loop.signatures, (name, loop)


@needs_numba
def test_the_warm_up_of_a_scenario_compiles_what_its_run_uses_and_nothing_else():
    """What make run warms beside the set-up: the default scenario's dop853 loop, no other."""
    probe = (
        'from tumble_ros.cli.warmup import warm_up_scenario\n'
        'from tumble_ros.core import kernels\n'
        'assert warm_up_scenario("") > 0.0\n'
        'print(sorted(name for name in kernels.KERNELS\n'
        '             if kernels.loops(name).advance.signatures))\n'
    )
    done = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split('\n')[-2] == "['dop853']", done.stdout


def test_a_scenario_the_warm_up_cannot_read_is_left_to_the_run(tmp_path, capsys):
    from tumble_ros.cli.warmup import main, warm_up_scenario
    from tumble_ros.core import ScenarioError

    missing = tmp_path / 'missing.yaml'
    with pytest.raises(ScenarioError, match='missing.yaml'):
        warm_up_scenario(str(missing))
    with pytest.raises(ScenarioError, match='no_such_scenario.yaml'):
        warm_up_scenario('no_such_scenario')       # a name: the shipped config/ folder's file
    assert main(['--scenario', str(missing)]) == 0   # make run goes on: the run says why
    if kernels.COMPILED:
        assert 'not compiled ahead (ScenarioError' in capsys.readouterr().out


@needs_numba
def test_a_first_use_that_compiles_says_so_and_a_compiled_loop_says_nothing():
    """The notice of jit.first_use (make run compiles only the loops it uses, on first use)."""
    import io
    import threading
    import time

    from tumble_ros.core.compiling.jit import first_use, jit

    def polynomial(x):
        return 3.0 * x * x + 1.0

    compiled = jit(polynomial, cache=False)   # compiled in this process, at its first call
    out = io.StringIO()
    with first_use(compiled, 'test loop', after=0.0, out=out):
        deadline = time.monotonic() + 30.0   # (the notice comes from a timer thread)
        while not out.getvalue() and time.monotonic() < deadline:
            threading.Event().wait(0.01)
        assert compiled(2.0) == 13.0
    lines = out.getvalue().splitlines()
    assert lines[0] == 'compiling the test loop (first use, cached afterwards)...'
    assert lines[1].startswith('... the test loop compiled in ') and len(lines) == 2
    # compiled now: nothing to say, whatever the wait
    quiet = io.StringIO()
    with first_use(compiled, 'test loop', after=0.0, out=quiet):
        threading.Event().wait(0.2)
    assert quiet.getvalue() == ''
    # a plain Python function (the reference path) neither
    with first_use(polynomial, 'plain', after=0.0, out=quiet):
        threading.Event().wait(0.2)
    assert quiet.getvalue() == ''


def test_a_long_first_call_that_is_already_running_is_not_called_compiling():
    """
    The notice looks at the loop when it would speak: compiled by then, it is running: silence.

    (A first ensemble call over many bodies compiles or loads its loop in a moment, then runs
    for seconds; in a Dask run its workers' "compiling" lines broke the one-line Ctrl-C output.)
    A stand-in dispatcher gets its signature (what numba adds once compiled) before the notice.
    """
    import io
    import threading

    from tumble_ros.core.compiling import jit as jit_module

    class Dispatcher:
        signatures: list = []

    loop = Dispatcher()
    out = io.StringIO()
    with jit_module.first_use(loop, 'running loop', after=0.3, out=out):
        loop.signatures = ['(float64,)']       # compiled at once; the call now runs
        threading.Event().wait(0.8)
    assert out.getvalue() == ''
    still = Dispatcher()
    with jit_module.first_use(still, 'slow loop', after=0.1, out=out):
        threading.Event().wait(0.5)            # still compiling when the notice comes
    assert out.getvalue().startswith('compiling the slow loop (first use')
    # a quiet command turns them off (for the processes it starts too), and back on after
    silent = io.StringIO()
    with jit_module.compile_notices(False):
        with jit_module.first_use(Dispatcher(), 'quiet loop', after=0.0, out=silent):
            threading.Event().wait(0.3)
    assert silent.getvalue() == ''
    assert jit_module.COMPILE_NOTICE_VARIABLE not in os.environ


@needs_numba
def test_a_first_use_that_loads_from_the_cache_says_loading_not_compiling(tmp_path):
    """Issue 47: every ensemble run said 'compiling ... (first use)' when it loaded the cache."""
    import io
    import threading
    import time

    from tumble_ros.core.compiling.jit import first_use

    (tmp_path / 'cached_loop.py').write_text(
        'from numba import njit\n\n\n@njit(cache=True)\ndef cube(x):\n    return x * x * x\n')
    env = {**os.environ, 'PYTHONPATH': str(tmp_path)}
    subprocess.run([sys.executable, '-c', 'import cached_loop; cached_loop.cube(2.0)'],
                   env=env, check=True, timeout=120)          # compiled and cached there
    sys.path.insert(0, str(tmp_path))
    try:   # (by name: a module the test writes, not a dependency)
        cached_loop = importlib.import_module('cached_loop')
    finally:
        sys.path.remove(str(tmp_path))
    out = io.StringIO()
    with first_use(cached_loop.cube, 'cached loop', after=0.0, out=out):
        deadline = time.monotonic() + 30.0   # (the notice comes from a timer thread)
        while not out.getvalue() and time.monotonic() < deadline:
            threading.Event().wait(0.01)
        assert cached_loop.cube(3.0) == 27.0
    lines = out.getvalue().splitlines()
    assert lines[0] == 'loading the cached loop from the numba cache...'
    assert lines[1].startswith('... the cached loop loaded in ') and len(lines) == 2


_SUBPROCESS = r"""
import json, sys
import numpy as np
from tumble_ros.core import (IntegratorSettings, Propagator, Impact, load_scenario, kernels,
                             simulate)
from tumble_ros.core.integrators import INTEGRATORS, SegmentProblem
from tumble_ros.core.integrators.compiled import CompiledStepper
sc = load_scenario(sys.argv[1])
out = {"compiled": kernels.COMPILED}
problem = SegmentProblem(sc.inertia, sc.orbit_rate, (1e3, 0.0, 0.0), (0.0, 2e3, 0.0))
y0 = np.concatenate([sc.omega0, [0.9, 0.1, 0.2, 0.3]])
for name, kw in json.loads(sys.argv[2]).items():
    st = CompiledStepper(INTEGRATORS[name], None, 0.0, y0, 0.2,
                         IntegratorSettings(method=name, **kw), problem=problem)
    track = np.array(sc.euler0, dtype=float)
    t_out = np.array([0.05, 0.1234, 0.2])
    y_out, e_out = np.zeros((3, 7)), np.zeros((3, 3))
    k, steps = st.advance(0.2, track, t_out, y_out, e_out, 0)
    out[name] = [y_out.tolist(), e_out.tolist(), steps, st.nfev]
r = simulate(sc.replace(duration=0.3, output_interval=0.1,
                        integrator=IntegratorSettings(method="splitting", step=1e-3)))
out["simulate"] = r.omega.tolist()
print(json.dumps(out))
"""


@needs_numba
def test_kernels_run_as_plain_python_give_the_same_results():
    """
    Check the pure-Python fallback against the compiled loops.

    With numba disabled the kernels' source runs in the interpreter and the Propagator takes
    the reference path; both agree with the compiled loops to <= 1e-12.
    """
    methods = {'rk4': {'step': 5e-3}, 'dop853': {'rtol': 1e-9, 'atol': 1e-12},
               'splitting6': {'step': 2e-2}}
    args = [sys.executable, '-c', _SUBPROCESS, str(CONFIG / 'fig9.yaml'), json.dumps(methods)]
    results = {}
    for disabled in ('0', '1'):
        env = dict(os.environ, NUMBA_DISABLE_JIT=disabled)
        done = subprocess.run(args, capture_output=True, text=True, timeout=300, env=env)
        assert done.returncode == 0, done.stderr[-3000:]
        results[disabled] = json.loads(done.stdout.strip().splitlines()[-1])
    jit, plain = results['0'], results['1']
    assert jit['compiled'] is True and plain['compiled'] is False
    for name in methods:
        y_j, e_j, steps_j, nfev_j = jit[name]
        y_p, e_p, steps_p, nfev_p = plain[name]
        assert (steps_j, nfev_j) == (steps_p, nfev_p)
        np.testing.assert_allclose(y_p, y_j, rtol=0, atol=1e-12 * 30)
        np.testing.assert_allclose(e_p, e_j, rtol=0, atol=1e-12)
    np.testing.assert_allclose(plain['simulate'], jit['simulate'], rtol=0, atol=1e-12 * 30)


@needs_numba
def test_an_edit_to_any_kernel_file_invalidates_the_cache(tmp_path, monkeypatch):
    """
    The kernels inline each other across files: one cache stamp covers all of them.

    numba alone checks a function's own file only (an edit to rk4.py would leave stepping.py's
    cached machine code, which inlined the old rk4, in use).
    """
    from tumble_ros.core.compiling import jit
    from tumble_ros.core.kernels import rk4

    for function in (kernels.loops('rk4').advance, rk4.start):
        locator = function._cache._impl._locator  # numba's cache internals (checked here)
        assert isinstance(locator, jit._CompiledSourcesLocator)
        assert locator.get_source_stamp() == jit.compiled_sources_hash()
    names = {p.name for p in jit.COMPILED_SOURCES}
    assert {'jit.py', 'stepping.py', 'rk4.py', 'physics.py', 'gravity_gradient.py'} <= names
    copies = []
    for k, path in enumerate(jit.COMPILED_SOURCES):
        copy = tmp_path / f'{k}_{path.name}'
        copy.write_bytes(path.read_bytes())
        copies.append(copy)
    monkeypatch.setattr(jit, 'COMPILED_SOURCES', tuple(copies))
    before = jit.compiled_sources_hash()
    rk4_copy = next(c for c in copies if c.name.endswith('_rk4.py'))
    rk4_copy.write_text(rk4_copy.read_text() + '\n# an edit\n')
    assert jit.compiled_sources_hash() != before


def test_every_core_module_a_compiled_source_imports_is_under_the_cache_stamp():
    """
    The core modules the kernels import: trig's sin/cos inlined, units' constants frozen.

    A core module a compiled source imports, left out of COMPILED_SOURCES, would leave stale
    machine code in use after an edit to it (trig.py was, until this test).
    """
    import ast

    from tumble_ros.core.compiling import jit

    core = Path(jit.__file__).resolve().parents[1]
    imported = set()
    for path in jit.COMPILED_SOURCES:
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([node.module or ''] if isinstance(node, ast.ImportFrom)
                     else [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            for name in names:
                if name.startswith('tumble_ros.core.'):
                    parts = name.split('.')[2:]
                    module = core.joinpath(*parts).with_suffix('.py')
                    imported.add(module if module.exists()
                                 else core.joinpath(*parts, '__init__.py'))
    assert {core / 'trig.py', core / 'units.py'} <= imported   # (the check's reach)
    missing = {p.relative_to(core) for p in imported if p.name != '__init__.py'} - {
        p.relative_to(core) for p in jit.COMPILED_SOURCES}
    assert not missing


def _kernel_shaped_loop(options):
    """Compile a loop shaped like a kernel's: an inlined step hands a slice to a called check."""
    import numba

    @numba.njit(**options)
    def squared_norm(y):
        acc = 0.0
        for i in range(y.shape[0]):
            acc += y[i] * y[i]
        return acc

    @numba.njit(inline='always', **options)
    def step(st, i):
        st[i] += 1.0
        return squared_norm(st[i:i + 3]) < 10.0

    @numba.njit(**options)
    def loop(st, n):
        k = 0
        while k < n:
            if not step(st, k % 4):
                break
            k += 1
        return k

    st = np.zeros(8)
    steps = loop(st, 5)
    (ir,) = loop.inspect_llvm().values()
    return (steps, st.tolist()), ir


@needs_numba
def test_kernels_are_compiled_without_reference_counting():
    """
    The kernels run without numba's atomic reference counts (jit.JIT_OPTIONS, _nrt=False).

    Those counts took two thirds of an ensemble's splitting step (benchmarks/HISTORY.md). A
    kernel-shaped loop compiled with the kernels' options holds no NRT_incref; compiled with
    numba's defaults it does (so this test would see them come back). The same value either way.
    """
    from tumble_ros.core.compiling import jit
    from tumble_ros.core.kernels import splitting

    loops = kernels.loops('splitting')
    for function in (loops.advance, loops.ensemble_advance, splitting.flow):
        assert function.targetoptions['_nrt'] is False
        assert function.targetoptions['nogil'] is True
    uncached = {k: v for k, v in jit.JIT_OPTIONS.items() if k != 'cache'}  # (cached IR: none)
    value_plain, ir_plain = _kernel_shaped_loop(uncached)
    value_counted, ir_counted = _kernel_shaped_loop({'nogil': True})
    assert 'NRT_incref' not in ir_plain and 'NRT_decref' not in ir_plain
    assert 'NRT_incref' in ir_counted
    assert value_plain == value_counted

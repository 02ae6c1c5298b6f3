"""
dop853 ensembles stepped as lanes with their own clocks (core/kernels/lanes.py).

Bodies sharing their segments (no per-body impact) are stepped by blocks, each body its own
adaptive steps, the stages vectorised across bodies. Each body must give exactly the samples,
step and evaluation counts of its single-body run (``simulate``) and of the per-body ensemble
loop, whatever the blocks, threads and checkpoints: with rejected attempts, samples inside steps
(dense output), several segments, very different spins in one block, and a body that fails
while the others go on.
"""
from pathlib import Path

import numpy as np
import pytest
from test_core_lockstep import _Spy, assert_identical, spread  # (the lockstep loop's checks)

from tumble_ros.core import (ensemble_scenarios, Impact, IntegratorSettings, kernels,
                             load_scenario, simulate, simulate_ensemble)
from tumble_ros.core.integrators import INTEGRATORS
from tumble_ros.core.propagation import ensemble as E

pytestmark = pytest.mark.skipif(not kernels.COMPILED,
                                reason='numba not available: only the reference path runs')
CONFIG = Path(__file__).resolve().parents[1] / 'config'
DOP853 = INTEGRATORS['dop853']


def fig9(duration=0.3, rtol=1e-9, atol=1e-11, **changes):
    settings = IntegratorSettings(method='dop853', rtol=rtol, atol=atol)
    return load_scenario(CONFIG / 'fig9.yaml').replace(
        **{'duration': duration, 'output_interval': duration / 6, 'integrator': settings,
           **changes})


def assert_single_runs(ens, sc, t_eval, omega0, euler0):
    """Every body of ``ens`` is its own ``simulate`` run, bit for bit."""
    for b, body in enumerate(ensemble_scenarios(sc, omega0=omega0, euler0=euler0)):
        one = simulate(body, t_eval)
        for name in ('omega', 'euler', 'quaternion', 'jacobi'):
            assert np.array_equal(getattr(ens, name)[b], getattr(one, name)), (b, name)
        assert ens.n_steps[b] == one.n_steps and ens.nfev[b] == one.nfev, b


def per_body(monkeypatch):
    """Take the lanes loop out of the registry: the per-body ensemble loop runs."""
    monkeypatch.setattr(E, 'ENSEMBLE_LOOPS',
                        {k: v for k, v in E.ENSEMBLE_LOOPS.items() if k != 'lanes'})


def lanes(sc, n, omega0, euler0, block, threads, checkpoints, times=None):
    times = sc.output_times if times is None else times
    return E._ensemble_compiled(sc, times, n, None, omega0, euler0, DOP853, None, checkpoints,
                                threads, lanes=block)


def test_which_ensembles_are_stepped_as_lanes():
    sc = fig9()
    hit = Impact(0.2, 3e-7, (1e6, 0.0, 0.0))
    assert E._lanes_refusal(sc, None, DOP853) == ''
    assert E._lanes_refusal(sc, [(), ()], DOP853) == ''
    # the scenario's own impacts are every body's: shared segments, own steps
    assert E._lanes_refusal(sc.replace(impacts=(hit,)), None, DOP853) == ''
    assert 'impacts per body' in E._lanes_refusal(sc, [(), (hit,)], DOP853)
    for fixed in ('rk4', 'splitting'):      # one time grid: lockstep's
        assert 'no lanes loop' in E._lanes_refusal(sc, None, INTEGRATORS[fixed])
        assert E._lockstep_refusal(sc, None, INTEGRATORS[fixed]) == ''
    assert list(E.ENSEMBLE_LOOPS) == ['lockstep', 'lanes', 'per-body']
    assert kernels.has_lanes('dop853') and not kernels.has_lanes('rk4')


@pytest.mark.parametrize('inertia', [None, (1.0, 1.5, 2.2)])
def test_each_body_is_bit_for_bit_its_single_run(inertia, monkeypatch):
    sc = fig9()
    if inertia is not None:
        sc = sc.replace(inertia=inertia)
    n = 9
    omega0, euler0 = spread(sc, n, size=3.0)
    omega0[2] *= 4.0           # very different spins in one block: ~4x the steps
    # off the step grid (dense output), on it, and the end
    t_eval = np.array([0.0, 0.0123, 0.1, 0.13333, 0.3])
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0, threads=2)
    assert ens.compiled and ens.success.all()
    assert_single_runs(ens, sc, t_eval, omega0, euler0)
    # the bodies really differ, in their states and their steps
    assert np.ptp(ens.omega[:, -1, 2]) > 1e-1
    assert ens.n_steps[2] > 2 * np.median(ens.n_steps)
    assert len(set(ens.n_steps.tolist())) > 2
    per_body(monkeypatch)
    assert_identical(ens, simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0))


def test_rejected_attempts_keep_each_body_on_its_own_steps(monkeypatch):
    """Without dense output, nfev = 2 + 12 (steps + rejected attempts): rejections differ."""
    sc = fig9(duration=0.5, rtol=1e-6, atol=1e-6)
    n = 12
    omega0, euler0 = spread(sc, n, seed=7, size=5.0)
    t_eval = np.array([0.0, sc.duration])
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0, euler_angles=False)
    rejected = (ens.nfev - 2) / 12 - ens.n_steps
    assert np.array_equal(rejected, np.round(rejected)) and rejected.min() >= 0
    assert rejected.max() > 0 and len(set(rejected.tolist())) > 1, rejected
    for b, body in enumerate(ensemble_scenarios(sc, omega0=omega0, euler0=euler0)):
        one = simulate(body, t_eval)      # (its Euler track's dense outputs count in its nfev)
        assert np.array_equal(ens.omega[b], one.omega) and ens.n_steps[b] == one.n_steps
    per_body(monkeypatch)
    assert_identical(ens, simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0,
                                            euler_angles=False))


def test_steps_followed_in_pieces_and_in_one_keep_each_bodys_euler_angles(monkeypatch):
    """
    Steps followed in pieces and in one: each body's angles and counts are its own.

    Loose tolerances give steps that turn phi or psi by more than the track's step (followed
    in pieces, by dense outputs) beside steps followed in one. A lane loads only the step's
    start for a step followed in one piece, all of its state for one in pieces
    (``lanes.after_step``): steps in pieces must occur here (steps in one piece are most of
    every run at the default tolerance, the tests above).
    """
    sc = fig9(duration=0.5, rtol=1e-6, atol=1e-6)
    n = 12
    omega0, euler0 = spread(sc, n, seed=7, size=5.0)
    t_eval = np.linspace(0.0, sc.duration, 8)
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0)
    bare = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0, euler_angles=False)
    pieces = ens.nfev - bare.nfev     # the track's dense outputs (its extra stages, evaluations)
    assert pieces.max() > 0, pieces
    assert np.array_equal(ens.n_steps, bare.n_steps)
    for b, body in enumerate(ensemble_scenarios(sc, omega0=omega0, euler0=euler0)):
        one = simulate(body, t_eval)
        assert np.array_equal(ens.euler[b], one.euler) and ens.nfev[b] == one.nfev, b
    per_body(monkeypatch)
    assert_identical(ens, simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0))


def test_results_do_not_depend_on_blocks_threads_or_checkpoints():
    sc = fig9()
    n = 23
    omega0, euler0 = spread(sc, n, seed=2, size=2.0)
    runs = [lanes(sc, n, omega0, euler0, block, threads, checkpoints)
            for block, threads, checkpoints in [(128, 1, 1), (1, 1, 1), (7, 2, 3), (16, 2, 5)]]
    for other in runs[1:]:
        assert_identical(runs[0], other)
    # a chunk of the ensemble gives the rows of the whole
    part = lanes(sc, 10, omega0[5:15], euler0[5:15], 4, 1, 1)
    assert np.array_equal(part.euler, runs[0].euler[5:15])
    assert np.array_equal(part.omega, runs[0].omega[5:15])
    assert np.array_equal(part.nfev, runs[0].nfev[5:15])


def test_a_failing_body_fails_alone_as_in_the_per_body_loop(monkeypatch):
    """A body failing at its start, bodies failing mid-run (work budget), the others go on."""
    sc = fig9(duration=0.2)
    omega0, euler0 = spread(sc, 7, seed=3)
    omega0[1] = np.nan         # f is NaN at the segment's start: no usable step size
    omega0[[3, 5]] *= 4.0      # ~4x the steps of the others: past the budget below
    # a work budget of 25 steps per 1/30 yr (limits.step_budget): the fast bodies stop at it
    monkeypatch.setattr(E, 'step_budget', lambda interval, rate, max_step: (interval, 25.0))
    times = sc.output_times
    lane = lanes(sc, 7, omega0, euler0, 4, 2, 2)
    ref = E._ensemble_compiled(sc, times, 7, None, omega0, euler0, DOP853, None, 2, 2)
    assert lane.success.tolist() == [True, False, True, False, True, False, True]
    assert 'not a number' in lane.messages[1]
    assert 'budget' in lane.messages[3] and 'budget' in lane.messages[5]
    assert_identical(lane, ref)
    assert np.isnan(lane.omega[1]).all()
    assert np.isfinite(lane.omega[3, 0]).all() and np.isnan(lane.omega[3, -1]).all()
    assert 0 < lane.n_steps[3] < lane.n_steps[0] * 4


def test_segments_extra_torques_and_shared_pulses():
    # Apophis 2029: three segments (the encounter window), a Kepler perturber (extra torque),
    # a triaxial body
    sc = load_scenario(CONFIG / 'apophis_2029.yaml')
    sc = sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-9, atol=1e-12))
    assert len(sc.segment_cuts) == 2 and sc.extra_torques
    n = 5
    omega0, euler0 = spread(sc, n, seed=4, size=10.0)
    t_eval = np.linspace(0.0, sc.duration, 13)
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0)
    assert_single_runs(ens, sc, t_eval, omega0, euler0)
    assert np.max(np.abs(ens.omega[:, -1] - omega0)) > 1.0    # the flyby turned the bodies
    # the scenario's impacts: pulse segments shared by every body, stepped as lanes
    hit = fig9().replace(impacts=(Impact(0.1, 3e-3, (3e3, 0.0, 500.0)),))
    omega0, euler0 = spread(hit, n, seed=5)
    t_eval = np.array([0.0, 0.1, 0.1015, 0.2, 0.3])
    ens = simulate_ensemble(hit, t_eval, omega0=omega0, euler0=euler0, threads=2)
    assert_single_runs(ens, hit, t_eval, omega0, euler0)
    assert np.max(np.abs(ens.omega[:, -1] - ens.omega[:, 1])) > 1.0   # the pulse did act


@pytest.mark.parametrize('threads', [1, 2])
def test_the_lanes_loop_is_loaded_before_the_timing_for_its_call_types(monkeypatch, threads):
    """``wall_time`` leaves out numba's first load of the lanes loop (its scratch argument too)."""
    real = kernels.loops('dop853')
    spies = {name: _Spy(getattr(real, name)) for name in ('ensemble_init', 'lanes_advance')}
    monkeypatch.setattr(kernels, 'loops', lambda name: real._replace(**spies))
    sc = fig9(duration=0.1)
    omega0, euler0 = spread(sc, 7, seed=5)
    simulate_ensemble(sc, omega0=omega0, euler0=euler0, threads=threads)
    for name, spy in spies.items():
        assert spy.called and spy.called == spy.loaded, (name, spy.called, spy.loaded)

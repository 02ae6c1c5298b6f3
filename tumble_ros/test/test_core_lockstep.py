"""
Ensembles stepped in lockstep (core/kernels/lockstep.py): the bits of each body's own run.

Bodies sharing one time grid (no impacts, a fixed-step method with a lockstep loop) are stepped
by blocks, structure of arrays, vectorised across bodies. Each body must give exactly the
samples, step and evaluation counts of its single-body run (``simulate``) and of the per-body
ensemble loop, whatever the blocks, threads and checkpoints; a failing body fails alone with
the per-body loop's message.
"""
from pathlib import Path

import numpy as np
import pytest

from tumble_ros.core import (ensemble_scenarios, Impact, IntegratorSettings, kernels,
                             load_scenario, simulate, simulate_ensemble)
from tumble_ros.core.integrators import INTEGRATORS
from tumble_ros.core.propagation import ensemble as E

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')
CONFIG = Path(__file__).resolve().parents[1] / 'config'
FIELDS = ('omega', 'euler', 'quaternion', 'jacobi', 'success', 'n_steps', 'nfev')


def fig9(method='splitting', step=2e-3, **changes):
    base = {'duration': 0.6, 'output_interval': 0.1,
            'integrator': IntegratorSettings(method=method, step=step)}
    return load_scenario(CONFIG / 'fig9.yaml').replace(**{**base, **changes})


def spread(sc, n, seed=1, size=0.5):
    rng = np.random.default_rng(seed)
    return (np.array(sc.omega0) + size * rng.normal(size=(n, 3)),
            np.array(sc.euler0) + 0.3 * rng.normal(size=(n, 3)))


def assert_identical(a, b):
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), name
    assert a.messages == b.messages


def per_body(monkeypatch):
    """Take the lockstep and lanes loops out of the registry: the per-body loop runs."""
    monkeypatch.setattr(E, 'ENSEMBLE_LOOPS',
                        {k: v for k, v in E.ENSEMBLE_LOOPS.items() if k == 'per-body'})


def test_which_ensembles_are_stepped_in_lockstep():
    sc = fig9()
    splitting, dop853 = INTEGRATORS['splitting'], INTEGRATORS['dop853']
    assert E._lockstep_refusal(sc, None, splitting) == ''
    assert E._lockstep_refusal(sc, [(), ()], splitting) == ''
    assert E._lockstep_refusal(fig9('splitting6'), None, INTEGRATORS['splitting6']) == ''
    hit = Impact(0.2, 3e-7, (1e6, 0.0, 0.0))
    assert 'impacts' in E._lockstep_refusal(sc, [(), (hit,)], splitting)
    assert 'impacts' in E._lockstep_refusal(sc.replace(impacts=(hit,)), None, splitting)
    assert E._lockstep_refusal(fig9('rk4'), None, INTEGRATORS['rk4']) == ''
    # adaptive: every body its own steps (the lanes loop: test_core_lanes.py)
    assert "'dop853'" in E._lockstep_refusal(fig9('dop853'), None, dop853)
    assert list(E.ENSEMBLE_LOOPS) == ['lockstep', 'lanes', 'per-body']


def test_the_plain_torque_is_the_torque_bit_for_bit():
    """rk4.block_rhs's torque without branches: torque_given_sun's bits where it is used."""
    from tumble_ros.core.kernels.physics import plain_torque_given_sun, torque_given_sun
    from tumble_ros.core.torques.gravity_gradient import sun_in_orbit_plane

    rng = np.random.default_rng(3)
    # signed zeros: dropping the zero terms (the Sun has no Z' component) would change a sign
    q = np.vstack([[1.0, 0.0, 0.0, 0.0], [-0.0, -0.0, 1.0, 0.0], rng.normal(size=(60, 4))])
    times = np.concatenate([[0.25, 0.0], rng.uniform(-3.0, 3.0, size=60)])
    inertia = (1.0, 1.5, 2.2)
    for body_pulse in ((0.0, 0.0, 0.0), (3.0, -0.0, -2.5e6)):
        p = kernels.problem_arrays(inertia, 2 * np.pi, [body_pulse + (0.0, 0.0, 0.0)])[0]
        assert p[kernels.PR.HAS_ORBITAL] == 0.0
        for t, (q0, q1, q2, q3) in zip(times, q):
            sx, sy = sun_in_orbit_plane(2 * np.pi, t)
            want = torque_given_sun(p, None, t, sx, sy, q0, q1, q2, q3)
            got = plain_torque_given_sun(p, sx, sy, q0, q1, q2, q3)
            assert np.array(got).tobytes() == np.array(want).tobytes(), (t, q0, q1, q2, q3)
    # an orbital-frame pulse is not the plain torque's: block_rhs takes torque_given_sun then
    p = kernels.problem_arrays(inertia, 2 * np.pi, [(0.0, 0.0, 0.0, 1e6, 0.0, 0.0)])[0]
    sx, sy = sun_in_orbit_plane(2 * np.pi, 0.3)
    assert (plain_torque_given_sun(p, sx, sy, *q[5])
            != torque_given_sun(p, None, 0.3, sx, sy, *q[5]))


@needs_numba
@pytest.mark.parametrize('method, step, inertia', [
    ('splitting', 2e-3, None),              # fig9: symmetric, one axis piece
    ('splitting6', 1e-2, None),             # 9 stages
    ('splitting', 2e-3, (1.0, 1.5, 2.2)),   # triaxial: two axis pieces (B_1 B_2 B_1)
    ('splitting', 5e-2, None),              # ~1.5 rad a step: the Euler track in pieces
    ('rk4', 2e-3, None),
    ('rk4', 2e-3, (1.0, 1.5, 2.2)),
    ('rk4', 3e-2, None),                    # ~1.2 rad a step: f evaluated per body (dense)
])
def test_each_body_is_bit_for_bit_its_single_run(method, step, inertia, monkeypatch):
    sc = fig9(method, step)
    if inertia is not None:
        sc = sc.replace(inertia=inertia)
    n = 9
    omega0, euler0 = spread(sc, n)
    # off the step grid (dense output), on it, and the end
    t_eval = np.array([0.0, 0.0123, 0.1, 0.33333, 0.6])
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0, threads=2)
    assert ens.compiled and ens.success.all()
    for b, body in enumerate(ensemble_scenarios(sc, omega0=omega0, euler0=euler0)):
        one = simulate(body, t_eval)
        assert np.array_equal(ens.omega[b], one.omega)
        assert np.array_equal(ens.euler[b], one.euler)
        assert np.array_equal(ens.quaternion[b], one.quaternion)
        assert np.array_equal(ens.jacobi[b], one.jacobi)
        assert ens.n_steps[b] == one.n_steps and ens.nfev[b] == one.nfev
    # the bodies really differ, and the per-body ensemble loop gives the same bits
    assert np.ptp(ens.omega[:, -1, 2]) > 1e-3
    per_body(monkeypatch)
    assert_identical(ens, simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0))


@needs_numba
@pytest.mark.parametrize('method', ['splitting', 'rk4'])
def test_segments_and_extra_torques_of_a_flyby_are_stepped_in_lockstep(method):
    # Apophis 2029: three segments (the encounter window), a Kepler perturber (extra torque),
    # a triaxial body
    sc = load_scenario(CONFIG / 'apophis_2029.yaml')
    sc = sc.replace(integrator=IntegratorSettings(method=method, step=4e-5))
    assert len(sc.segment_cuts) == 2 and sc.extra_torques
    n = 5
    omega0, euler0 = spread(sc, n, seed=4, size=10.0)
    t_eval = np.linspace(0.0, sc.duration, 13)
    ens = simulate_ensemble(sc, t_eval, omega0=omega0, euler0=euler0)
    for b, body in enumerate(ensemble_scenarios(sc, omega0=omega0, euler0=euler0)):
        one = simulate(body, t_eval)
        assert np.array_equal(ens.omega[b], one.omega)
        assert np.array_equal(ens.euler[b], one.euler)
        assert ens.n_steps[b] == one.n_steps and ens.nfev[b] == one.nfev
    # the flyby turned the bodies
    assert np.max(np.abs(ens.omega[:, -1] - omega0)) > 1.0


@needs_numba
@pytest.mark.parametrize('method', ['splitting', 'rk4'])
def test_results_do_not_depend_on_blocks_threads_or_checkpoints(method):
    sc = fig9(method)
    n = 23
    omega0, euler0 = spread(sc, n, seed=2)
    times = sc.output_times
    method = INTEGRATORS[method]
    runs = [E._ensemble_lockstep(sc, times, n, None, omega0, euler0, method, None, checkpoints,
                                 threads, block=block)
            for block, threads, checkpoints in [(256, 1, 1), (1, 1, 1), (7, 2, 3), (16, 2, 1)]]
    for other in runs[1:]:
        assert_identical(runs[0], other)
    # a chunk of the ensemble gives the rows of the whole
    part = E._ensemble_lockstep(sc, times, 10, None, omega0[5:15], euler0[5:15], method, None,
                                1, 1, block=4)
    assert np.array_equal(part.euler, runs[0].euler[5:15])
    assert np.array_equal(part.omega, runs[0].omega[5:15])


@needs_numba
@pytest.mark.parametrize('method', ['splitting', 'rk4'])
def test_a_failing_body_fails_alone_as_in_the_per_body_loop(method):
    sc = fig9(method, duration=0.2)
    omega0, euler0 = spread(sc, 5, seed=3)
    omega0[1] = 1e200          # |omega|^2 overflows at the first step (past the inputs' check)
    omega0[3] = 1e154          # |pi|^2 finite at first, not after the torque's kick
    times = sc.output_times
    method = INTEGRATORS[method]
    lock = E._ensemble_lockstep(sc, times, 5, None, omega0, euler0, method, None, 1, 2, block=2)
    ref = E._ensemble_compiled(sc, times, 5, None, omega0, euler0, method, None, 1, 2)
    assert lock.success.tolist() == [True, False, True, False, True]
    assert 'non-finite' in lock.messages[1]
    assert_identical(lock, ref)
    assert np.isnan(lock.omega[1, -1]).all() and np.isfinite(lock.omega[1, 0]).all()


@needs_numba
@pytest.mark.parametrize('method', ['splitting', 'rk4', 'dop853'])
@pytest.mark.parametrize('loop', ['lockstep', 'per-body', 'impacts', 'reference'])
def test_without_euler_angles_every_other_output_keeps_its_bits(monkeypatch, method, loop):
    """euler_angles=False: the same samples, steps and states; euler NaN; the track skipped."""
    sc = fig9(method, step=5e-3, duration=0.3, output_interval=0.05,
              integrator=IntegratorSettings(method=method, step=5e-3, rtol=1e-8, atol=1e-8))
    omega0, euler0 = spread(sc, 5, seed=4)
    impacts = None
    if loop == 'per-body':
        per_body(monkeypatch)
    if loop == 'impacts':
        impacts = [(), (Impact(0.1, 3e-4, (3e3, 0.0, 0.0)),), (), (), ()]
    fast = loop != 'reference'
    runs = [simulate_ensemble(sc, omega0=omega0, euler0=euler0, impacts=impacts, fast=fast,
                              threads=2, euler_angles=euler) for euler in (True, False)]
    full, bare = runs
    assert full.compiled == bare.compiled == fast
    for name in ('omega', 'quaternion', 'jacobi', 'success', 'n_steps'):
        assert np.array_equal(getattr(full, name), getattr(bare, name), equal_nan=True), name
    assert np.isfinite(full.euler).all() and full.success.all()
    assert bare.euler.shape == full.euler.shape and np.isnan(bare.euler).all()
    # the track's dense outputs are evaluations too: rk4's and dop853's counts may only drop
    assert (bare.nfev <= full.nfev).all()


class _Spy:
    """A compiled loop whose loads (``compile``) and calls record numba's argument types."""

    def __init__(self, loop):
        self.loop, self.loaded, self.called = loop, set(), set()

    def compile(self, signature):  # noqa: A003 - the name numba's dispatchers have
        self.loaded.add(tuple(signature))
        return self.loop.compile(signature)

    def __call__(self, *args):
        import numba

        self.called.add(tuple(numba.typeof(a) for a in args))
        return self.loop(*args)

    def __getattr__(self, name):        # signatures, overloads: as the loop's
        return getattr(self.loop, name)


@needs_numba
@pytest.mark.parametrize('loop', ['lockstep', 'per-body'])
@pytest.mark.parametrize('threads', [1, 2])
def test_the_loops_are_loaded_before_the_timing_for_the_types_they_are_called_with(
        monkeypatch, loop, threads):
    """
    ``wall_time`` leaves out numba's first load of the loops.

    That load took ~0.7 s at N = 100, and the ensemble command printed ~2e3 body-steps/s for
    ~3e5. The loops are loaded (``jit.load_for``) for the argument types their calls then
    dispatch on; another type would load or compile them again inside the timing.
    """
    if loop == 'per-body':
        per_body(monkeypatch)
    names = ('block_init', 'block_advance') if loop == 'lockstep' else (
        'ensemble_init', 'ensemble_advance')
    real = kernels.loops('splitting')
    spies = {name: _Spy(getattr(real, name)) for name in names}
    monkeypatch.setattr(kernels, 'loops', lambda name: real._replace(**spies))
    sc = fig9('splitting', duration=0.1, output_interval=0.05)
    omega0, euler0 = spread(sc, 7, seed=5)
    simulate_ensemble(sc, omega0=omega0, euler0=euler0, threads=threads)
    for name, spy in spies.items():
        assert spy.called and spy.called == spy.loaded, (name, spy.called, spy.loaded)


@needs_numba
def test_the_lockstep_track_update_is_set_tracks_phi_and_psi_bit_for_bit():
    """
    ``tracking.follow`` (the lockstep loop's track update): ``set_track``'s phi and psi.

    Without theta's atan2 and mostly without hypot: on random attitudes, references many turns
    away, theta near 0 and pi across the band where |(c20, c21)| is decided by hypot
    (0.5e-300 to 1e-300, and just above with both entries below it), NaN and infinite
    quaternions (the track then kept); track[2] is never written.
    """
    from tumble_ros.core.kernels.tracking import follow, set_track

    rng = np.random.default_rng(11)
    tiny = np.geomspace(1e-302, 1e-299, 301)
    one, zero = np.ones_like(tiny), np.zeros_like(tiny)
    quaternions = np.vstack([
        rng.normal(size=(400, 4)),
        np.column_stack([one, zero, tiny, zero]),     # theta ~ 0: c20 = -2e, c21 = 0
        np.column_stack([one, tiny, tiny, zero]),     # c20 = -2e, c21 = 2e: hypot 2.8e
        np.column_stack([tiny, one, zero, zero]),     # theta ~ pi: c21 = 2e
        np.column_stack([tiny, one, tiny, zero]),
        [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-0.0, -0.0, 1.0, 0.0],
         [np.nan, 0.0, 0.0, 1.0], [1.0, np.nan, 0.0, 0.0], [np.inf, 0.0, 0.0, 0.0],
         [1.0, np.inf, 1.0, 0.0], [1e200, 1e200, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]],
    ])
    st = np.zeros(kernels.ST.SIZE)
    degenerate = 0
    for q in quaternions:
        reference = np.array([rng.uniform(-1e3, 1e3), rng.uniform(-1e3, 1e3), 7.0])
        want, got = reference.copy(), reference.copy()
        st[3:7] = q
        set_track(st, 0, want)
        follow(q[0], q[1], q[2], q[3], got)
        assert got[:2].tobytes() == want[:2].tobytes(), q
        assert got[2] == 7.0
        degenerate += want[1] == 2 * np.pi * np.round(reference[1] / (2 * np.pi))
    # the band's both sides were reached: psi = 0 (unwrapped) for some tiny quaternions only
    assert 0 < degenerate < len(quaternions) - 400


@needs_numba
@pytest.mark.parametrize('method, step', [
    ('splitting', 2e-3),   # samples inside a step: the block's dense output (block_dense)
    ('splitting', 5e-2),   # fast bodies' tracks in pieces (dense), slow ones' on the columns
    ('rk4', 2e-3),         # no block dense output: samples inside a step body by body
])
def test_a_mixed_block_gives_each_body_its_own_samples_and_euler_angles(method, step):
    """
    One block of very different bodies, samples on and off the step grid, several in a step.

    Spins from 1e-3 to ~300 rad/yr (phi or psi through ~30 turns), theta near 0 and near pi
    (phi and psi nearly degenerate), one body failing at its first step: each running body's
    samples (Euler angles included) are its single run's, the failed one's the per-body
    loop's, whatever the blocks, threads and checkpoints.
    """
    sc = fig9(method, step)
    omega0 = np.array([[0.1, 0.1, 30.0], [0.01, -0.02, 0.3], [3.0, -2.0, 300.0],
                       [20.0, 5.0, -30.0], [0.1, 0.1, 30.0], [1e-3, 0.0, 1e-3],
                       [1e154, 1e154, 1e154], [50.0, 50.0, 100.0], [0.0, 0.0, -200.0]])
    euler0 = np.array([[0.5, 0.0, 0.9], [1.0, 2.0, 1e-3], [0.3, -1.0, 1e-6],
                       [-2.0, 0.5, np.pi - 1e-3], [0.5, 0.0, np.pi - 1e-7], [0.0, 0.0, 0.1],
                       [0.1, 0.2, 0.3], [3.0, 3.0, 1.5], [-3.1, 3.1, 2e-2]])
    n = len(omega0)
    t_eval = np.unique(np.concatenate([np.linspace(0.0, 0.6, 41),
                                       [0.1001, 0.1002, 0.1003, 0.33333, 0.5999]]))
    method_type = INTEGRATORS[method]
    # (the overflowing body is past the inputs' check: the loops are called directly)
    ens = E._ensemble_lockstep(sc, t_eval, n, None, omega0, euler0, method_type, None, 1, 2)
    assert ens.success.tolist() == [b != 6 for b in range(n)]
    running = [b for b in range(n) if b != 6]
    bodies = ensemble_scenarios(sc, omega0=omega0[running], euler0=euler0[running])
    for b, body in zip(running, bodies):
        one = simulate(body, t_eval)
        for name in ('omega', 'euler', 'quaternion', 'jacobi'):
            assert np.array_equal(getattr(ens, name)[b], getattr(one, name)), (b, name)
        assert ens.n_steps[b] == one.n_steps and ens.nfev[b] == one.nfev
    # the angles wrapped many times, and theta went near 0 and near pi
    assert np.ptp(ens.euler[2, :, 0]) + np.ptp(ens.euler[2, :, 1]) > 40 * np.pi
    assert np.nanmin(ens.euler[:, :, 2]) < 1e-2 and np.nanmax(ens.euler[:, :, 2]) > np.pi - 1e-2
    for block, threads, checkpoints in [(1, 1, 1), (4, 2, 7), (256, 1, 3)]:
        assert_identical(ens, E._ensemble_lockstep(sc, t_eval, n, None, omega0, euler0,
                                                   method_type, None, checkpoints, threads,
                                                   block=block))
    assert_identical(ens, E._ensemble_compiled(sc, t_eval, n, None, omega0, euler0, method_type,
                                               None, 1, 2))

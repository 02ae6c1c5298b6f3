"""Ensembles: N bodies at once equal N single runs; random impact sequences; the command."""
import io
from pathlib import Path

import numpy as np
import pytest

from tumble_ros.cli.ensemble import main
from tumble_ros.cli.progress import ProgressBar
from tumble_ros.core import (
    ensemble_scenarios,
    Impact,
    IntegratorSettings,
    kernels,
    load_scenario,
    random_impacts,
    ScenarioError,
    simulate,
    simulate_ensemble,
)

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def fig9(method='splitting4', **changes):
    settings = {'rk4': {'step': 1e-3},
                'dop853': {'rtol': 1e-10, 'atol': 1e-12}}.get(method, {'step': 4e-3})
    base = {'duration': 3.0, 'output_interval': 0.25,
            'integrator': IntegratorSettings(method=method, **settings)}
    return load_scenario(CONFIG / 'fig9.yaml').replace(**{**base, **changes})


def assert_body_equals_run(ens, b, single, tol=1e-12):
    assert single.success and ens.success[b]
    assert np.max(np.abs(ens.omega[b] - single.omega)) <= tol * np.max(np.abs(single.omega))
    assert np.max(np.abs(ens.quaternion[b] - single.quaternion)) <= tol
    assert (np.max(np.abs(ens.euler[b] - single.euler))
            <= tol * max(1.0, np.max(np.abs(single.euler))))
    assert np.max(np.abs(ens.jacobi[b] - single.jacobi)) <= tol * np.max(np.abs(single.jacobi))
    assert ens.n_steps[b] == single.n_steps


@pytest.mark.parametrize('method', ['splitting4', 'rk4', 'dop853'])
def test_identical_bodies_equal_single_runs(method):
    sc = fig9(method, impacts=(Impact(1.0, 3e-7, (2e6, 0.0, 1e6)),))
    ens = simulate_ensemble(sc, n_bodies=5)
    assert ens.omega.shape == (5, sc.output_times.size, 3) and ens.compiled is kernels.COMPILED
    for fast in (None, False):
        single = simulate(sc, fast=fast)
        for b in range(5):
            assert_body_equals_run(ens, b, single)
    assert ens.nfev[0] == simulate(sc).nfev


@pytest.mark.parametrize('method', ['splitting', 'dop853'])
def test_bodies_with_their_own_impacts_and_initial_states_equal_their_single_runs(method):
    sc = fig9(method)
    n = 6
    hits = random_impacts(n, sc.duration, rate=1.0, torque=1e6, pulse=3e-7, seed=7)
    hits[2] = hits[2] + (Impact(1.5, 0.01, (0.0, 0.0, 300.0), frame='orbital'),)
    hits[4] = ()
    rng = np.random.default_rng(3)
    omega0 = np.array(sc.omega0) + 0.05 * rng.normal(size=(n, 3))
    euler0 = np.array(sc.euler0) + 0.1 * rng.normal(size=(n, 3))
    t_eval = np.array([0.0, 0.3, 1.5, 1.505, 2.999, 3.0])
    ens = simulate_ensemble(sc, t_eval, impacts=hits, omega0=omega0, euler0=euler0)
    bodies = ensemble_scenarios(sc, impacts=hits, omega0=omega0, euler0=euler0)
    assert (len(bodies) == n and bodies[4].impacts == ()
            and bodies[2].impacts[-1].frame == 'orbital')
    for b, body in enumerate(bodies):
        assert_body_equals_run(ens, b, simulate(body, t_eval, fast=False))
    # the impacts really differ between bodies
    assert np.ptp(ens.omega[:, -1, 2]) > 1e-3


def test_compiled_and_reference_ensembles_agree_and_failures_stay_per_body():
    sc = fig9('rk4', duration=1.0)
    # body 1's state overflows at once
    kicks = [(), (Impact(0.0, 0.5, (1e300, 1e300, 1e300)),), ()]
    ens = simulate_ensemble(sc, impacts=kicks, progress=None)
    ref = simulate_ensemble(sc, impacts=kicks, fast=False)
    assert ens.success.tolist() == ref.success.tolist() == [True, False, True]
    assert ('non-finite' in ens.messages[1] and ens.messages[1] == ref.messages[1]
            and ens.messages[0] == '')
    good = [0, 2]
    np.testing.assert_allclose(ens.omega[good], ref.omega[good], rtol=0, atol=1e-12 * 30)
    assert np.isnan(ens.omega[1, -1]).all() and np.isfinite(ens.omega[1, 0]).all()
    reached = int(np.isfinite(ens.omega[1, :, 0]).sum())
    for out in (ens.omega, ens.euler, ens.quaternion, ens.jacobi):
        assert np.isnan(out[1, reached:]).all() and np.isfinite(out[[0, 2]]).all()


def test_progress_is_reported_and_inputs_are_checked():
    sc = fig9('splitting', duration=1.0)
    calls = []
    simulate_ensemble(sc, n_bodies=3, progress=lambda f, t, steps: calls.append((f, t, steps)),
                      checkpoints=4)
    assert [c[0] for c in calls] == [0.25, 0.5, 0.75, 1.0] and calls[-1][1] == 1.0
    assert calls[-1][2] == 3 * 250 and all(a[2] <= b[2] for a, b in zip(calls, calls[1:]))
    stream = io.StringIO()
    bar = ProgressBar(2.0, 10, stream=stream)
    bar(0.5, 1.0, 1000)
    bar(1.0, 2.0, 2000)
    assert '50.0%' in stream.getvalue() and 'body-steps/s' in stream.getvalue()
    with pytest.raises(ScenarioError, match='inconsistent'):
        simulate_ensemble(sc, n_bodies=2, omega0=np.zeros((3, 3)))
    with pytest.raises(ScenarioError, match='end of the run'):
        simulate_ensemble(sc, impacts=[(Impact(0.99, 0.1, (1.0, 0.0, 0.0)),)])
    with pytest.raises(ValueError, match='compiled ensemble not available'):
        simulate_ensemble(sc.replace(integrator=IntegratorSettings(method='rk45')), n_bodies=1,
                          fast=True)


def test_random_impacts_are_reproducible_and_inside_the_run():
    a = random_impacts(20, 10.0, rate=2.0, torque=5e5, pulse=1e-3, seed=42)
    b = random_impacts(20, 10.0, rate=2.0, torque=5e5, pulse=1e-3, seed=42)
    assert a == b and len(a) == 20
    flat = [i for body in a for i in body]
    assert 200 < len(flat) < 600  # Poisson, mean 400
    assert all(0.0 <= i.start and i.end <= 10.0 and i.duration == 1e-3 for i in flat)
    assert all(np.linalg.norm(i.torque) == pytest.approx(5e5) for i in flat)


def test_command_line(tmp_path, capsys):
    out = tmp_path / 'ens.npz'
    code = main([str(CONFIG / 'fig9.yaml'), '--bodies', '4', '--duration', '0.5',
                 '--output-interval', '0.1',
                 '--method', 'splitting6', '--step', '0.01', '--impact-rate', '4',
                 '--omega-spread', '0.01',
                 '--seed', '1', '--out', str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert 'bodies: 4 (4 succeeded)' in captured.out and 'body-steps/s' in captured.out
    assert '100.0%' in captured.err  # progress display on stderr
    data = np.load(out)
    assert data['omega'].shape == (4, 6, 3) and data['success'].all()
    assert main(['--bodies', '0', '--quiet']) == 2


def test_a_simulators_params_file_with_its_node_parameters_is_read(tmp_path, capsys):
    """
    The params file given to ``ros2 run tumble_ros sim`` also runs as an ensemble.

    The simulator's own parameters (real_time_factor, seconds_per_year, ...) are not the
    scenario's: they are skipped; an unknown name is still refused, with its name.
    """
    from tumble_ros.topics import SIM_NODE_PARAMETERS

    params = tmp_path / 'sim.yaml'
    node = ''.join(f'    {name}: {default!r}\n'.replace("'", '') for name, (default, *_)
                   in SIM_NODE_PARAMETERS.items())
    params.write_text('sim:\n  ros__parameters:\n    duration: 0.2\n    output_interval: 0.1\n'
                      + node.replace('True', 'true').replace('False', 'false'))
    assert main([str(params), '--bodies', '2', '--quiet']) == 0, capsys.readouterr().err
    assert 'bodies: 2 (2 succeeded)' in capsys.readouterr().out
    params.write_text(params.read_text() + '    real_time_factr: 1.0\n')
    assert main([str(params), '--bodies', '2', '--quiet']) == 2
    assert 'real_time_factr: unknown scenario parameter' in capsys.readouterr().err


def test_small_pages_switch_numpys_huge_pages_off_and_restore_them():
    """Off inside (also nested and on two threads at once), numpy's own setting after."""
    import threading

    from tumble_ros.core.propagation.ensemble import small_pages

    multiarray = np._core.multiarray
    default = multiarray._get_madvise_hugepage()
    for setting in (True, False):
        multiarray._set_madvise_hugepage(setting)
        inside = []
        started, leave = threading.Barrier(2), threading.Event()

        def other():
            with small_pages():
                started.wait()
                leave.wait()
                inside.append(multiarray._get_madvise_hugepage())

        thread = threading.Thread(target=other)
        thread.start()
        with small_pages():
            started.wait()
            with small_pages():
                inside.append(multiarray._get_madvise_hugepage())
        inside.append(multiarray._get_madvise_hugepage())   # the other thread still inside
        leave.set()
        thread.join()
        assert inside == [False, False, False]
        assert multiarray._get_madvise_hugepage() is setting
    multiarray._set_madvise_hugepage(default)


def test_the_fastest_spin_is_numpys_norm_bit_for_bit_and_bounds_the_ensemble():
    """ensemble._fastest_spin (by columns) against np.linalg.norm's rows; the bound it checks."""
    from tumble_ros.core.model.limits import MAX_OMEGA
    from tumble_ros.core.propagation.ensemble import _fastest_spin

    rng = np.random.default_rng(30)
    for scale in (1e-170, 1e-3, 1.0, 30.0, 1e9, 1e160):
        omega = rng.normal(size=(1001, 3)) * scale * rng.uniform(0.5, 2.0, size=(1001, 1))
        expected = float(np.max(np.linalg.norm(omega, axis=1)))
        assert _fastest_spin(omega).hex() == expected.hex(), scale
    one = np.array([[3.0, 4.0, 12.0]])
    assert _fastest_spin(one) == 13.0
    too_fast = np.tile([0.0, 0.0, 1.0], (5, 1))
    too_fast[3, 1] = 2.0 * MAX_OMEGA
    with pytest.raises(ScenarioError, match=r'omega0: \|omega0\| = 2e\+10 rad/yr exceeds'):
        simulate_ensemble(fig9('splitting'), omega0=too_fast)

"""
Ensembles on Dask and in stores: the same answer everywhere, restarts, killed workers, failures.

One small LocalCluster (2 worker processes, 1 thread each) serves the module and is closed at
its end, with every process it started.
"""
import os
from pathlib import Path
import pickle
import signal

import numpy as np
import pytest

from tumble_ros.cli.ensemble import main
from tumble_ros.core import (ensemble_scenarios, GaussianSpread, Impact, IntegratorSettings,
                             iter_chunks, load_scenario, parse_scenario, RandomImpacts,
                             ScenarioError, simulate_ensemble)
from tumble_ros.core.propagation.simulate import sample_times
from tumble_ros.ensembles import (dask_client, ensemble_variable, EnsembleRunError,
                                  EnsembleStoreError, open_ensemble, run_ensemble,
                                  run_ensemble_to_store, run_fingerprint)
from tumble_ros.io.ensemble_store import EnsembleStore

CONFIG = Path(__file__).resolve().parents[1] / 'config'
FIELDS = ('omega', 'euler', 'quaternion', 'jacobi', 'success', 'n_steps', 'nfev')
#: What a run without Euler angles keeps bit for bit (nfev counts no tracking evaluations).
KEPT = ('omega', 'quaternion', 'jacobi', 'success', 'n_steps')


def fig9(**changes):
    base = {'duration': 2.0, 'output_interval': 0.25,
            'integrator': IntegratorSettings(method='splitting4', step=4e-3)}
    return load_scenario(CONFIG / 'fig9.yaml').replace(**{**base, **changes})


def random_inputs(sc, n=13, seed=5):
    return {'impacts': RandomImpacts(rate=1.5, torque=1e6, seed=seed),
            'omega0': GaussianSpread(sc.omega0, 0.05, seed=seed),
            'euler0': GaussianSpread(sc.euler0, 0.1, seed=seed), 'n_bodies': n}


def assert_same(a, b, fields=FIELDS):
    for name in fields:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.messages == b.messages


@pytest.fixture(scope='module')
def client():
    with dask_client(workers=2) as c:
        yield c


def test_per_body_draws_do_not_depend_on_the_number_of_bodies_or_the_chunking():
    hits = RandomImpacts(rate=2.0, torque=5e5, pulse=1e-3, seed=42)
    whole = hits.draw(0, 10, 10.0)
    assert whole == hits.draw(0, 4, 10.0) + hits.draw(4, 6, 10.0)
    assert whole[7] == hits.body(7, 10.0) and whole[7] != whole[8]
    assert whole != RandomImpacts(rate=2.0, torque=5e5, pulse=1e-3, seed=43).draw(0, 10, 10.0)
    flat = [i for body in hits.draw(0, 200, 10.0) for i in body]
    assert 3600 < len(flat) < 4400  # Poisson, mean 200 * 2 * (10 - 1e-3) = 4000, sd 63
    assert all(0.0 <= i.start and i.end <= 10.0 and i.duration == 1e-3 for i in flat)
    assert all(np.linalg.norm(i.torque) == pytest.approx(5e5) for i in flat)
    spread = GaussianSpread((0.0, 1.0, 30.0), 0.5, seed=1)
    w = spread.draw(0, 2000, stream=1)
    np.testing.assert_array_equal(w[5:9], spread.draw(5, 4, stream=1))
    assert np.all(np.abs(w.mean(axis=0) - [0.0, 1.0, 30.0]) < 5 * 0.5 / np.sqrt(2000))
    assert np.all(np.abs(w.std(axis=0) / 0.5 - 1.0) < 0.1)
    # omega0 and euler0 given the same seed are still independent draws
    assert not np.any(spread.draw(0, 5, stream=1) == spread.draw(0, 5, stream=2))
    # a body of an ensemble is the scenario with that body's draws
    sc = fig9()
    bodies = ensemble_scenarios(sc, **random_inputs(sc, n=6))
    assert bodies[4].impacts == RandomImpacts(rate=1.5, torque=1e6, seed=5).body(4, sc.duration)
    assert bodies[4].omega0 == tuple(GaussianSpread(sc.omega0, 0.05, seed=5).draw(4, 1, 1)[0])


def test_bad_inputs_are_refused_with_the_field_named():
    with pytest.raises(ScenarioError, match='^rate:'):
        RandomImpacts(rate=-1.0, torque=1.0)
    with pytest.raises(ScenarioError, match='^frame:'):
        RandomImpacts(rate=1.0, torque=1.0, frame='inertial')
    with pytest.raises(ScenarioError, match='^seed:'):
        RandomImpacts(rate=1.0, torque=1.0, seed=-3)
    with pytest.raises(ScenarioError, match='^sigma:'):
        GaussianSpread((0.0, 0.0, 1.0), -0.1)
    with pytest.raises(ScenarioError, match='^center:'):
        GaussianSpread((0.0, 1.0), 0.1)
    sc = fig9()
    with pytest.raises(ScenarioError, match='^n_bodies: needed'):
        simulate_ensemble(sc, impacts=RandomImpacts(rate=1.0, torque=1.0))
    with pytest.raises(ScenarioError, match='^chunk_size:'):
        list(iter_chunks(sc, n_bodies=3, chunk_size=0))
    with pytest.raises(ScenarioError, match='^workers:'):
        with dask_client(workers=0):
            pass


def test_same_answer_whatever_the_engine_and_the_chunking(client):
    sc = fig9()
    inputs = random_inputs(sc)
    reference = simulate_ensemble(sc, **inputs)
    assert np.ptp(reference.omega[:, -1, 2]) > 1e-3  # the bodies really differ
    assert reference.success.all()
    # one thread, the time span in 7 compiled calls with a progress display
    assert_same(simulate_ensemble(sc, **inputs, threads=1, checkpoints=7,
                                  progress=lambda *a: None), reference)
    # in-process chunks, joined in body order
    parts = sorted(iter_chunks(sc, **inputs, chunk_size=5), key=lambda c: c.start)
    assert [(c.start, c.stop) for c in parts] == [(0, 5), (5, 10), (10, 13)]
    for c in parts:
        np.testing.assert_array_equal(c.result.omega, reference.omega[c.start:c.stop])
    # a local cluster of 2 worker processes, with chunks of 1, 4 and all 13 bodies
    for size in (1, 4, 13):
        calls = []
        on_cluster = run_ensemble(sc, **inputs, client=client, chunk_size=size,
                                  progress=lambda f, t, s: calls.append(f))
        assert_same(on_cluster, reference)
        assert len(calls) == -(-13 // size) and calls[-1] == 1.0


def test_a_store_holds_the_run_labelled_and_a_failing_body_with_its_reason(client, tmp_path):
    sc = fig9(duration=1.0)
    kicks = [()] * 7
    kicks[3] = (Impact(0.1, 0.5, (1e300, 1e300, 1e300)),)   # body 3's state overflows
    kicks[5] = (Impact(0.5, 1e-3, (0.0, 3e3, 0.0)),)
    reference = simulate_ensemble(sc, impacts=kicks)
    summary = run_ensemble_to_store(sc, tmp_path / 'ens.zarr', impacts=kicks, chunk_size=3,
                                    client=client)
    assert (summary.n_chunks, summary.chunks_run, summary.chunks_skipped) == (3, 3, 0)
    assert (summary.succeeded, summary.failed, summary.pending) == (6, 1, 0)
    assert summary.failures[0][0] == 3 and 'non-finite' in summary.failures[0][1]
    ds = open_ensemble(tmp_path / 'ens.zarr')
    assert ds.omega.dims == ('body', 'time', 'component')
    assert ds.sizes['body'] == 7 and ds.sizes['time'] == sc.output_times.size
    assert ds.omega.attrs['units'] == 'rad/yr' and ds.time.attrs['units'] == 'yr'
    assert list(ds.component.values) == ['x', 'y', 'z']
    np.testing.assert_array_equal(ds.time.values, sc.output_times)
    assert parse_scenario(ds.attrs['scenario']) == sc
    for name in ('omega', 'euler', 'quaternion', 'jacobi'):
        np.testing.assert_array_equal(ds[name].values, getattr(reference, name), err_msg=name)
    assert ds.status.values.tolist() == [1, 1, 1, 2, 1, 1, 1]
    assert ds.reason.values[3] == reference.messages[3] and 'non-finite' in ds.reason.values[3]
    assert np.isnan(ds.omega.values[3, -1]).all() and np.isfinite(ds.omega.values[3, 0]).all()
    assert ds.n_impacts.values.tolist() == [0, 0, 0, 1, 0, 1, 0]
    np.testing.assert_array_equal(ds.n_steps.values, reference.n_steps)
    np.testing.assert_array_equal(ds.omega0.values, np.tile(sc.omega0, (7, 1)))
    assert ds.chunk_done.values.all()


def test_an_interrupted_run_restarts_where_it_stopped(tmp_path):
    sc = fig9()
    inputs = random_inputs(sc, n=10)
    reference = simulate_ensemble(sc, **inputs)
    path = tmp_path / 'ens.zarr'

    def interrupt_after_two(fraction, t, steps):
        if fraction >= 0.4:   # two chunks of 2 bodies (of 10) written
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_ensemble_to_store(sc, path, **inputs, chunk_size=2, progress=interrupt_after_two)
    partial = open_ensemble(path)
    assert partial.chunk_done.values.tolist() == [True, True, False, False, False]
    assert (partial.status.values[4:] == 0).all() and np.isnan(partial.omega.values[4:]).all()
    summary = run_ensemble_to_store(sc, path, **inputs)   # the same run: chunk size from the store
    assert (summary.chunks_skipped, summary.chunks_run, summary.succeeded) == (2, 3, 10)
    ds = open_ensemble(path)
    np.testing.assert_array_equal(ds.omega.values, reference.omega)
    np.testing.assert_array_equal(ds.quaternion.values, reference.quaternion)
    # another run into the same store is refused, or replaces it when asked to
    other = {**inputs, 'impacts': RandomImpacts(rate=1.5, torque=1e6, seed=6)}
    with pytest.raises(EnsembleStoreError, match='holds another run'):
        run_ensemble_to_store(sc, path, **other)
    with pytest.raises(EnsembleStoreError, match='holds another run'):
        run_ensemble_to_store(sc, path, **inputs, chunk_size=3)
    replaced = run_ensemble_to_store(sc, path, **other, overwrite=True, chunk_size=5)
    assert (replaced.chunks_skipped, replaced.chunks_run) == (0, 2)
    assert open_ensemble(path).attrs['chunk_size'] == 5
    with pytest.raises(EnsembleStoreError, match='no ensemble store'):
        open_ensemble(tmp_path / 'missing.zarr')


def test_a_killed_worker_loses_nothing_and_duplicates_nothing(client, tmp_path):
    # 8 chunks of ~0.3-1 s each: a worker is killed while it runs one, which Dask runs again
    sc = fig9(duration=1.0, output_interval=0.5,
              integrator=IntegratorSettings(method='splitting', step=1e-3))
    inputs = {'impacts': RandomImpacts(rate=1.0, torque=1e6, seed=9), 'n_bodies': 8 * 1500}
    reference = simulate_ensemble(sc, **inputs)
    pids = client.run(os.getpid)
    killed = []

    def kill_a_busy_worker(fraction, t, steps):
        if killed:
            return
        busy = [w for w, keys in client.processing().items() if keys]
        assert busy, 'no task running to interrupt'
        os.kill(pids[busy[0]], signal.SIGKILL)
        killed.append(busy[0])

    summary = run_ensemble_to_store(sc, tmp_path / 'ens.zarr', **inputs, chunk_size=1500,
                                    client=client, progress=kill_a_busy_worker)
    assert killed and (summary.chunks_run, summary.succeeded) == (8, 8 * 1500)
    ds = open_ensemble(tmp_path / 'ens.zarr')
    assert ds.chunk_done.values.all()
    np.testing.assert_array_equal(ds.omega.values, reference.omega)
    np.testing.assert_array_equal(ds.n_steps.values, reference.n_steps)
    client.wait_for_workers(2, timeout=60)   # the nanny restarted it, as a new process
    assert pids[killed[0]] not in client.run(os.getpid).values()


def test_a_task_that_raises_stops_the_run_with_its_reason(client):
    sc = fig9()
    # |omega0| above the core's limit: a ScenarioError raised in the task, re-raised here
    with pytest.raises(ScenarioError, match='omega0'):
        run_ensemble(sc, omega0=GaussianSpread((0.0, 0.0, 1e11), 1.0), n_bodies=4,
                     client=client, chunk_size=2)
    with pytest.raises(EnsembleRunError, match='cannot reach'):
        with dask_client(scheduler='tcp://127.0.0.1:9', timeout=1.0):
            pass


def test_command_line_on_a_local_cluster_and_on_a_running_scheduler(client, tmp_path, capsys):
    args = [str(CONFIG / 'fig9.yaml'), '--bodies', '9', '--duration', '0.5',
            '--output-interval', '0.1', '--method', 'splitting6', '--step', '0.01',
            '--impact-rate', '4', '--omega-spread', '0.01', '--seed', '1', '--chunk-size', '4']
    local, remote = tmp_path / 'local.zarr', tmp_path / 'remote.zarr'
    assert main(args + ['--workers', '2', '--out', str(local)]) == 0
    out = capsys.readouterr()
    assert '9 succeeded' in out.out and '3 run now' in out.out and '9/9 bodies' in out.err
    assert main(args + ['--out', str(local), '--quiet']) == 0    # again: nothing to do
    assert '0 run now, 3 already written' in capsys.readouterr().out
    assert main(args + ['--scheduler', client.scheduler.address, '--out', str(remote),
                        '--quiet']) == 0
    np.testing.assert_array_equal(open_ensemble(remote).omega.values,
                                  open_ensemble(local).omega.values)
    npz = tmp_path / 'threads.npz'
    assert main(args + ['--out', str(npz), '--quiet']) == 0
    np.testing.assert_array_equal(np.load(npz)['omega'], open_ensemble(local).omega.values)
    capsys.readouterr()
    assert main(args + ['--scheduler', 'tcp://127.0.0.1:9', '--scheduler-timeout', '1']) == 2
    assert 'cannot reach the Dask scheduler' in capsys.readouterr().err


def test_the_analysis_reads_the_store(tmp_path, capsys):
    from tumble_ros.analysis.ensemble import ensemble_statistics, final_spin, main as analyse
    from tumble_ros.core.model.spinstate import spin_state

    sc = fig9(duration=1.0)
    inputs = random_inputs(sc, n=12)
    reference = simulate_ensemble(sc, **inputs)
    run_ensemble_to_store(sc, tmp_path / 'ens.zarr', **inputs, chunk_size=5)
    ds = open_ensemble(tmp_path / 'ens.zarr')
    stats = ensemble_statistics(ds)
    w_end = reference.omega[:, -1]
    assert stats['succeeded'] == 12 and stats['time'] == sc.duration
    assert stats['omega_z']['mean'] == pytest.approx(w_end[:, 2].mean(), rel=1e-15)
    assert stats['omega_perp']['std'] == pytest.approx(np.hypot(w_end[:, 0], w_end[:, 1]).std())
    direct = spin_state(w_end[7], sc.inertia, reference.quaternion[7, -1])
    spin = final_spin(ds, max_spin_states=12)
    assert spin['rotation_period'][7] == direct.rotation_period
    assert spin['pole_latitude'][7] == direct.pole_latitude and spin['mode'][7] == direct.mode
    assert sum(stats['modes'].values()) == 12
    # a subset of the bodies for the spin states, spread over the ensemble
    assert final_spin(ds, max_spin_states=4)['spin_body'].tolist() == [0, 3, 7, 11]
    assert analyse([str(tmp_path / 'ens.zarr'), '--figures', str(tmp_path / 'figs')]) == 0
    assert 'omega_perp' in capsys.readouterr().out
    assert (tmp_path / 'figs' / 'ensemble.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert analyse([str(tmp_path / 'nothing.zarr')]) == 1
    assert 'no ensemble store' in capsys.readouterr().err


# ---------------------------------------------------------------------------------------
# Runs without Euler angles (euler_angles=False, the command's --no-euler-angles)
# ---------------------------------------------------------------------------------------
def assert_no_euler(result, n, m):
    assert result.euler_angles is False
    assert result.euler.shape == (n, m, 3) and np.isnan(result.euler).all()
    assert result.euler.strides == (0, 0, 0)     # one NaN seen N x m x 3 times: no memory


def test_without_euler_angles_the_same_bits_whatever_the_engine_and_the_chunking(client):
    sc = fig9()
    inputs = random_inputs(sc)
    m = sc.output_times.size
    full = simulate_ensemble(sc, **inputs)
    bare = simulate_ensemble(sc, **inputs, euler_angles=False)
    assert np.isfinite(full.euler).all() and full.success.all()
    assert_same(bare, full, KEPT)
    assert_no_euler(bare, 13, m)
    # pickled (a Dask task's result) without its NaN euler, and back
    assert len(pickle.dumps(full)) - len(pickle.dumps(bare)) >= full.euler.nbytes
    again = pickle.loads(pickle.dumps(bare))
    assert_same(again, bare)
    assert_no_euler(again, 13, m)
    # in-process chunks, each chunk's simulate_ensemble call without Euler angles
    parts = list(iter_chunks(sc, **inputs, chunk_size=5, euler_angles=False))
    assert [(c.start, c.stop) for c in parts] == [(0, 5), (5, 10), (10, 13)]
    for c in parts:
        np.testing.assert_array_equal(c.result.omega, full.omega[c.start:c.stop])
        assert_no_euler(c.result, c.stop - c.start, m)
    # the local cluster, chunks of 1, 4 and all 13 bodies: gathered without memory for euler
    for size in (1, 4, 13):
        on_cluster = run_ensemble(sc, **inputs, client=client, chunk_size=size,
                                  euler_angles=False)
        assert_same(on_cluster, bare)
        assert_no_euler(on_cluster, 13, m)
    # in process, gathered from chunks too (threads path: simulate_ensemble itself)
    assert_same(run_ensemble(sc, **inputs, euler_angles=False), bare)


def test_a_store_without_euler_angles_opens_and_says_why_it_has_none(client, tmp_path):
    sc = fig9(duration=1.0)
    inputs = random_inputs(sc, n=7)
    full = simulate_ensemble(sc, **inputs)
    path = tmp_path / 'bare.zarr'
    summary = run_ensemble_to_store(sc, path, **inputs, chunk_size=3, client=client,
                                    euler_angles=False)
    assert (summary.chunks_run, summary.succeeded) == (3, 7)
    ds = open_ensemble(path)
    assert 'euler' not in ds.variables and 'euler0' in ds.variables
    assert '--no-euler-angles' in ds.attrs['left_out']['euler']
    for name in ('omega', 'quaternion', 'jacobi', 'n_steps'):
        np.testing.assert_array_equal(ensemble_variable(ds, name).values,
                                      getattr(full, name), err_msg=name)
    # reading the Euler angles: one error naming the output and the option that left it out
    refusal = (r"bare\.zarr: no 'euler' in this ensemble store: the run left out the Euler "
               r"angles \(euler_angles=False, the ensemble command's --no-euler-angles\)")
    with pytest.raises(EnsembleStoreError, match=refusal):
        ensemble_variable(ds, 'euler')
    with pytest.raises(EnsembleStoreError, match=refusal):
        EnsembleStore(path).read('euler')
    with pytest.raises(EnsembleStoreError, match="no variable 'eular' in this ensemble store"):
        ensemble_variable(ds, 'eular')
    # resumed only by the same choice: the choice is part of the run's fingerprint
    assert run_ensemble_to_store(sc, path, **inputs, euler_angles=False).chunks_skipped == 3
    with pytest.raises(EnsembleStoreError, match='holds another run'):
        run_ensemble_to_store(sc, path, **inputs)
    # a store with the Euler angles (as every store before the choice): all there, no
    # left_out attribute, the same fingerprint as before the choice existed
    with_euler = tmp_path / 'full.zarr'
    run_ensemble_to_store(sc, with_euler, **inputs, chunk_size=3)
    old = open_ensemble(with_euler)
    assert 'left_out' not in old.attrs
    np.testing.assert_array_equal(ensemble_variable(old, 'euler').values, full.euler)
    n, prepared = 7, {'impacts': inputs['impacts'], 'omega0': inputs['omega0'],
                      'euler0': inputs['euler0']}
    times = sample_times(sc, None)
    assert old.attrs['fingerprint'] == run_fingerprint(sc, times, prepared, n, 3)
    assert ds.attrs['fingerprint'] == run_fingerprint(sc, times, prepared, n, 3,
                                                      euler_angles=False)
    assert ds.attrs['fingerprint'] != old.attrs['fingerprint']
    # only the optional variables may be left out; a store that claims others is damaged
    with pytest.raises(EnsembleStoreError, match=r"left_out: \['omega'\] cannot be left out"):
        EnsembleStore.create(tmp_path / 'x.zarr', n_bodies=2, times=[0.0, 1.0], chunk_size=1,
                             attrs={'scenario': ''}, left_out={'omega': 'no'})
    import zarr
    group = zarr.open_group(str(with_euler), mode='r+', zarr_format=2)
    group.attrs['left_out'] = {'status': 'gone'}
    zarr.consolidate_metadata(str(with_euler))
    with pytest.raises(EnsembleStoreError, match="damaged ensemble store: attribute 'left_out'"):
        open_ensemble(with_euler)


def test_command_line_without_euler_angles_keeps_every_other_output(client, tmp_path, capsys):
    from tumble_ros.analysis.ensemble import main as analyse
    from tumble_ros.cli.ensemble import _parser

    assert '--no-euler-angles' in _parser().format_help()
    base = [str(CONFIG / 'fig9.yaml'), '--bodies', '9', '--duration', '0.5',
            '--output-interval', '0.1', '--method', 'splitting', '--step', '0.005',
            '--omega-spread', '0.01', '--seed', '1', '--chunk-size', '4', '--quiet']
    # with impacts: the per-body loop; without: the lockstep loop
    for loop, args in (('per-body', base + ['--impact-rate', '4']), ('lockstep', base)):
        out = {}
        for name, flag in (('full', []), ('bare', ['--no-euler-angles'])):
            out[name] = tmp_path / f'{loop}-{name}.npz'
            assert main(args + flag + ['--out', str(out[name])]) == 0, loop
            assert main(args + flag + ['--scheduler', client.scheduler.address,
                                       '--out', str(tmp_path / f'{loop}-{name}.zarr')]) == 0
        full, bare = np.load(out['full']), np.load(out['bare'])
        assert 'euler' in full.files and 'euler' not in bare.files, loop
        assert sorted(full.files) == sorted(bare.files + ['euler'])
        for name in bare.files:
            np.testing.assert_array_equal(bare[name], full[name], err_msg=f'{loop} {name}')
        stored = open_ensemble(tmp_path / f'{loop}-bare.zarr')
        assert 'euler' not in stored.variables
        for name in ('omega', 'quaternion', 'jacobi', 'n_steps'):
            np.testing.assert_array_equal(stored[name].values, full[name], err_msg=name)
        np.testing.assert_array_equal(
            open_ensemble(tmp_path / f'{loop}-full.zarr').euler.values, full['euler'])
    capsys.readouterr()
    # the store's analysis needs no Euler angles: it runs on a store without them
    assert analyse([str(tmp_path / 'lockstep-bare.zarr')]) == 0
    assert 'omega_perp' in capsys.readouterr().out
    # the same store resumed with the other choice: refused, one line, exit 2
    assert main(base + ['--out', str(tmp_path / 'lockstep-bare.zarr')]) == 2
    assert 'holds another run' in capsys.readouterr().err

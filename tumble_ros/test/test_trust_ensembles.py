"""
The ensemble and encounter commands at their edges.

As processes: their params files, the listeners of an embedded cluster, Ctrl-C, one writer per
store, foreign and damaged stores.

Each process is started with the real entry point (``ensemble``, as ``ros2 run`` finds it) in
its own process group, killed with it after the test (conftest ``spawn``).
"""
import json
import os
from pathlib import Path
import signal
import socket
import subprocess
import sys
import time

import pytest

from tumble_ros.analysis.ensemble import main as analyse_main
from tumble_ros.cli.ensemble import main as ensemble_main
from tumble_ros.core import check_params_file, IntegratorSettings, load_scenario, ScenarioError
from tumble_ros.core.compiling.jit import COMPILE_NOTICE_VARIABLE
from tumble_ros.ensembles import EnsembleStoreError, open_ensemble, run_ensemble_to_store
from tumble_ros.io.ensemble_store import EnsembleStoreLocked, lock_path, store_lock

CONFIG = Path(__file__).resolve().parents[1] / 'config'
#: Generous bound [s] for a process (a Dask cluster starting on a loaded 2-core machine).
SLOW = 240.0


def small_scenario():
    return load_scenario(CONFIG / 'fig9.yaml').replace(
        duration=1.0, output_interval=0.5,
        integrator=IntegratorSettings(method='splitting4', step=4e-3))


# -- the params file: one check, every reader ---------------------------------------------------

def _bad_files(tmp_path):
    fifo = tmp_path / 'fifo.yaml'
    os.mkfifo(fifo)
    binary = tmp_path / 'binary.yaml'
    binary.write_bytes(bytes(range(256)) * 4)
    return {'fifo': (fifo, 'is a FIFO (named pipe), not a params file (only regular files '
                           'are read)'),
            'binary': (binary, 'cannot read it as text: it holds binary data'),
            'directory': (tmp_path, 'is a directory, not a params file'),
            'missing': (tmp_path / 'missing.yaml', 'no such file')}


@pytest.mark.parametrize('command', ['ensemble', 'encounter'])
def test_ensemble_and_encounter_refuse_a_fifo_and_a_binary_file_in_one_line(
        spawn, tmp_path, command):
    """`ensemble FIFO.yaml` blocked forever; a binary file's error did not name it."""
    for kind, (path, expected) in _bad_files(tmp_path).items():
        process = spawn(command, path, '--quiet')
        assert process.wait(SLOW) == 2, (kind, process.output)
        (line,) = process.output.strip().splitlines()
        assert line.startswith(f'error: params file {path}: {expected}'), kind


def test_every_reader_gives_the_same_refusal(tmp_path):
    """One check: sim and bringup (params_file_problem), ensemble and encounter (load_scenario)."""
    from tumble_ros.nodes.parameters import params_file_problem

    for kind, (path, expected) in _bad_files(tmp_path).items():
        with pytest.raises(ScenarioError) as direct:
            check_params_file(path)
        with pytest.raises(ScenarioError) as loaded:
            load_scenario(path)
        node = params_file_problem(['sim', '--ros-args', '--params-file', str(path)])
        assert str(direct.value).startswith(f'params file {path}: {expected}'), kind
        assert str(loaded.value) == str(direct.value) == node, kind


# -- the embedded cluster: loopback only, a clean Ctrl-C -----------------------------------------

def _group(pid: int):
    import psutil

    root = psutil.Process(pid)
    return [root] + root.children(recursive=True)


def _listeners(pid: int) -> dict:
    """Return {(pid, name): [(ip, port), ...]} of every listening socket of the process tree."""
    import psutil

    found = {}
    for process in _group(pid):
        try:
            sockets = [c.laddr for c in process.net_connections(kind='inet')
                       if c.status == psutil.CONN_LISTEN]
        except psutil.Error:
            continue
        if sockets:
            found[(process.pid, process.name())] = [(a.ip, a.port) for a in sockets]
    return found


def _ensemble_args(out, *more):
    return [CONFIG / 'fig9.yaml', '--bodies', '40000', '--duration', '20',
            '--output-interval', '1', '--method', 'splitting6', '--step', '0.01',
            '--impact-rate', '0.5', '--seed', '1', '--chunk-size', '1000', '--out', out,
            *more]


def test_an_embedded_cluster_listens_on_loopback_only_and_ctrl_c_ends_it_in_one_line(
        spawn, tmp_path):
    """
    The LocalCluster's HTTP server listened on 0.0.0.0 (dashboard_address=':0').

    Every listening socket of every process of the run (driver, nannies, workers) is read
    while the run is busy; then the whole process group gets SIGINT, as a terminal's Ctrl-C
    does: one line, exit code 130, the chunks written kept.
    """
    out = tmp_path / 'big.zarr'
    run = spawn('ensemble', *_ensemble_args(out, '--workers', '2', '--quiet'))
    deadline = time.monotonic() + SLOW
    seen = {}
    while time.monotonic() < deadline and run.popen.poll() is None:
        seen = _listeners(run.popen.pid)
        workers = [key for key in seen if key[0] != run.popen.pid]
        # .zmetadata is written last when the store is created: the run is then under way
        if len(workers) >= 2 and (out / '.zmetadata').exists():
            break
        time.sleep(0.2)
    assert run.popen.poll() is None, run.output
    assert len([key for key in seen if key[0] != run.popen.pid]) >= 2, seen
    everywhere = {ip for sockets in seen.values() for ip, _ in sockets}
    assert everywhere == {'127.0.0.1'}, seen
    os.killpg(run.popen.pid, signal.SIGINT)
    assert run.wait(SLOW) == 130, run.output
    assert run.output.strip().splitlines() == [
        f'ensemble: stopped by SIGINT; the chunks written to {out} are kept: run the same '
        'command to resume'], run.output
    assert not lock_path(out).exists()
    assert open_ensemble(out).sizes['body'] == 40000      # the store stays readable


def test_ctrl_c_while_the_cluster_starts_is_one_line(spawn, tmp_path):
    """A Ctrl-C as the workers start gave 'Nanny failed to start' or KeyboardInterrupt."""
    out = tmp_path / 'early.zarr'
    run = spawn('ensemble', *_ensemble_args(out, '--workers', '2', '--quiet'))
    deadline = time.monotonic() + SLOW
    while time.monotonic() < deadline and run.popen.poll() is None:
        if len(_group(run.popen.pid)) > 1:        # the first worker process exists
            break
        time.sleep(0.02)
    os.killpg(run.popen.pid, signal.SIGINT)
    assert run.wait(SLOW) == 130, run.output
    lines = run.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('ensemble: stopped by SIGINT'), run.output


def test_the_sigint_ignoring_python_outlives_the_cluster_start():
    """
    The wrapper the workers are spawned through stays after the cluster's start is left.

    A Ctrl-C as the cluster started ended the ``with`` while a nanny still spawned through the
    wrapper; removed then, it printed "/bin/sh: 0: cannot open .../python" and a resource
    tracker warning (1 run in 8 beside a CPU hog, CI of 2026-12-04).
    """
    import multiprocessing.spawn as mp_spawn

    from tumble_ros.runs.ensembles import dask_engine

    before = mp_spawn.get_executable()
    with dask_engine._workers_ignore_sigint():
        wrapper = Path(os.fsdecode(mp_spawn.get_executable()))   # (bytes on POSIX)
    assert mp_spawn.get_executable() == before and wrapper != Path(os.fsdecode(before))
    assert wrapper.is_file()
    probe = 'import signal; print(signal.getsignal(signal.SIGINT) is signal.SIG_IGN)'
    done = subprocess.run([str(wrapper), '-c', probe], capture_output=True, text=True,
                          timeout=60)
    assert done.stdout.strip() == 'True', done.stderr


def test_the_sigint_ignoring_python_outlives_the_process_that_made_it(tmp_path):
    """
    A Ctrl-C at the cluster's start ends the driver while a nanny still spawns through it.

    Removed at the driver's exit (atexit), the wrapper was gone under that spawn: "/bin/sh: 0:
    cannot open .../python" (CI of 2026-12-04, twice). Made in a process that then exits, it
    must still run this Python with SIGINT ignored; a second process finds the same file.
    """
    make = ('from tumble_ros.runs.ensembles import dask_engine; '
            'print(dask_engine._sigint_ignoring_python())')
    env = {**os.environ, 'XDG_CACHE_HOME': str(tmp_path / 'cache')}
    paths = [subprocess.run([sys.executable, '-c', make], capture_output=True, text=True,
                            timeout=120, env=env, check=True).stdout.strip() for _ in range(2)]
    assert paths[0] == paths[1] and Path(paths[0]).parent == tmp_path / 'cache' / 'tumble_ros'
    probe = 'import signal; print(signal.getsignal(signal.SIGINT) is signal.SIG_IGN)'
    done = subprocess.run([paths[0], '-c', probe], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == 'True', done.stderr
    assert sorted(p.name for p in (tmp_path / 'cache' / 'tumble_ros').iterdir()
                  if p.is_file()) == [Path(paths[0]).name]    # no scratch file left


def test_the_dashboard_is_served_on_loopback_only_when_asked(tmp_path):
    from tumble_ros.ensembles import dask_client

    with dask_client(workers=1, dashboard=True) as client:
        assert client.dashboard_link.startswith('http://127.0.0.1:')
        assert {ip for sockets in _listeners(os.getpid()).values()
                for ip, _ in sockets} == {'127.0.0.1'}


# -- one writer per store ------------------------------------------------------------------------

_HOLD = """
import sys, time
from pathlib import Path
from tumble_ros.core import IntegratorSettings, load_scenario, RandomImpacts
from tumble_ros.ensembles import run_ensemble_to_store
sc = load_scenario(sys.argv[1]).replace(duration=1.0, output_interval=0.5,
                                        integrator=IntegratorSettings(method='splitting4',
                                                                      step=4e-3))
def hold(fraction, t, steps):
    print('chunk written', flush=True)
    time.sleep(3600)
run_ensemble_to_store(sc, sys.argv[2], n_bodies=6, chunk_size=2, progress=hold,
                      impacts=RandomImpacts(rate=1.0, torque=1e6, seed=3))
"""


def test_a_second_run_into_a_store_is_refused_and_a_dead_owner_s_lock_is_taken_over(
        tmp_path, capsys):
    """
    Two identical runs into one store both resumed it and wrote the same chunks.

    The first run is killed (SIGKILL) after its first chunk is written: its lock file stays,
    stale; the next run takes it over and writes only the chunks not written.
    """
    out = tmp_path / 'shared.zarr'
    # (numba's notices off: with a cache made stale by an edit, 'compiling ...' came first)
    first = subprocess.Popen([sys.executable, '-c', _HOLD, str(CONFIG / 'fig9.yaml'), str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                             start_new_session=True,
                             env={**os.environ, COMPILE_NOTICE_VARIABLE: '0'})
    try:
        said = first.stdout.readline()
        assert said.strip() == 'chunk written', said
        owner = json.loads(lock_path(out).read_text())
        assert (owner['pid'], owner['host']) == (first.pid, socket.gethostname())
        sc = small_scenario()
        from tumble_ros.core import RandomImpacts
        inputs = {'n_bodies': 6, 'impacts': RandomImpacts(rate=1.0, torque=1e6, seed=3)}
        with pytest.raises(EnsembleStoreLocked) as refused:
            run_ensemble_to_store(sc, out, **inputs)
        assert str(refused.value) == (
            f'{out}: being written by pid {first.pid} on {socket.gethostname()} since '
            f"{owner['since']} (lock file {lock_path(out)}); one writer per store: wait for it "
            'to end, or write to another path')
        assert open_ensemble(out).chunk_done.values.tolist() == [True, False, False]
        os.killpg(first.pid, signal.SIGKILL)
        first.wait(30)
        assert lock_path(out).exists()                       # left behind, stale
        summary = run_ensemble_to_store(sc, out, **inputs)
        assert (summary.chunks_skipped, summary.chunks_run, summary.succeeded) == (1, 2, 6)
        assert not lock_path(out).exists()
        again = run_ensemble_to_store(sc, out, **inputs)
        assert (again.chunks_skipped, again.chunks_run) == (3, 0)
    finally:
        if first.poll() is None:
            os.killpg(first.pid, signal.SIGKILL)
            first.wait(30)
        first.stdout.close()


def test_the_lock_is_held_for_the_run_and_released_after(tmp_path):
    out = tmp_path / 's.zarr'
    with store_lock(out):
        with pytest.raises(EnsembleStoreLocked, match=f'pid {os.getpid()} on'):
            with store_lock(out):
                pass
    assert not lock_path(out).exists()
    with store_lock(out):          # free again
        pass


# -- foreign and damaged stores, as output and as input ------------------------------------------

def _store(tmp_path) -> Path:
    from tumble_ros.core import RandomImpacts

    tmp_path.mkdir(exist_ok=True)
    out = tmp_path / 'ok.zarr'
    run_ensemble_to_store(small_scenario(), out, n_bodies=4, chunk_size=2,
                          impacts=RandomImpacts(rate=1.0, torque=1e6, seed=3))
    return out


def _set_attr(store: Path, key: str, value) -> None:
    import zarr

    group = zarr.open_group(str(store), mode='r+', zarr_format=2)
    group.attrs[key] = value
    zarr.consolidate_metadata(str(store))


def _damaged(tmp_path) -> dict:
    import shutil

    import zarr

    ok = _store(tmp_path)
    stores = {}
    newer = tmp_path / 'newer.zarr'
    shutil.copytree(ok, newer)
    _set_attr(newer, 'format_version', 2)
    stores['newer'] = (newer, 'ensemble store format version 2; this tumble_ros reads and '
                              'resumes version 1 only')
    renamed = tmp_path / 'renamed.zarr'
    shutil.copytree(ok, renamed)
    (renamed / 'omega').rename(renamed / 'spin')
    zarr.consolidate_metadata(str(renamed))
    stores['renamed'] = (renamed, 'damaged ensemble store: no variable omega')
    foreign = tmp_path / 'foreign.zarr'
    zarr.open_group(str(foreign), mode='w', zarr_format=2).attrs['title'] = 'someone else'
    zarr.consolidate_metadata(str(foreign))
    stores['foreign'] = (foreign, 'not a tumble_ros ensemble store')
    garbage = tmp_path / 'garbage.zarr'
    shutil.copytree(ok, garbage)
    (garbage / '.zmetadata').write_bytes(b'\x00not json')
    (garbage / '.zattrs').write_bytes(b'\x00not json')
    stores['garbage'] = (garbage, '')
    return stores


def test_a_foreign_or_damaged_store_is_refused_in_one_line_as_output_and_as_input(
        tmp_path, capsys):
    """A renamed variable gave a traceback; format_version was never checked."""
    for kind, (store, expected) in _damaged(tmp_path).items():
        args = [str(CONFIG / 'fig9.yaml'), '--bodies', '4', '--duration', '1',
                '--output-interval', '0.5', '--method', 'splitting4', '--step', '4e-3',
                '--impact-rate', '1', '--seed', '3', '--chunk-size', '2', '--quiet',
                '--out', str(store)]
        assert ensemble_main(args) == 2, kind
        out, err = capsys.readouterr()
        (line,) = err.strip().splitlines()
        assert line.startswith(f'error: {store}: ') and expected in line, (kind, err)
        assert analyse_main([str(store)]) == 1, kind
        out, err = capsys.readouterr()
        (line,) = err.strip().splitlines()
        assert line.startswith(f'ERROR: {store}: ') and expected in line, (kind, err)
        with pytest.raises(EnsembleStoreError):
            open_ensemble(store)
    corrupt = _store(tmp_path / 'corrupt')
    for chunk in (corrupt / 'omega').glob('[0-9]*'):
        chunk.write_bytes(b'garbage' * 10)
    assert analyse_main([str(corrupt)]) == 1
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f'ERROR: {corrupt}: damaged ensemble store: cannot read its data')
    assert ensemble_main(args[:-1] + [str(corrupt)]) == 2     # resumed: nothing to run, then read
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f'error: {corrupt}: damaged ensemble store: cannot read its data')
    a_file = tmp_path / 'file.zarr'
    a_file.write_text('not a store')
    assert analyse_main([str(a_file)]) == 1
    assert capsys.readouterr().err.startswith(f'ERROR: {a_file}: no ensemble store there')


def test_a_dead_scheduler_is_one_line_after_a_bounded_wait(capsys):
    args = [str(CONFIG / 'fig9.yaml'), '--bodies', '2', '--duration', '0.5', '--quiet']
    assert ensemble_main(args + ['--scheduler', 'tcp://127.0.0.1:9',
                                 '--scheduler-timeout', '1']) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("error: cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'")
    for timeout in ('inf', 'nan', '0', '1e9'):
        assert ensemble_main(args + ['--scheduler', 'tcp://127.0.0.1:9',
                                     '--scheduler-timeout', timeout]) == 2
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert line.startswith('error: --scheduler-timeout: must be in (0, 3600] s'), timeout

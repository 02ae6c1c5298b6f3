"""``make bench BENCH_ARGS=--quick`` judges nothing against the full run's targets."""
import io
import os
from pathlib import Path
import sys

import pytest

BENCH = Path(__file__).resolve().parents[2] / 'benchmarks'


@pytest.fixture()
def bench(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))
    import common
    import targets
    yield common, targets
    for name in ('common', 'targets', 'fresh_clone'):
        sys.modules.pop(name, None)


def _far_from_the_targets(summary) -> dict:
    """Return section results of a small run: every figure far from its target."""
    node = {'visible_s': 4.0}
    return {summary.MAIN_JOB: {'wall_s': [40.0]}, summary.READING: {'columnar_per_s': 2e4},
            summary.STANDALONE: {'events': {'samples_per_s': 900.0, 'lost': {}},
                                 summary.UNDER_LOAD: {'lost': {'/attitude': 3}}},
            summary.BRINGUP: {summary.UNDER_LOAD: {'lost': {'/clock': 1}}},
            summary.FRESH_CLONE: {'run': {'wall_s': 300.0, 'ok': True},
                                  'test': {'wall_s': 100.0, 'ok': False}},
            summary.ENSEMBLE: {'splitting N=10000': {'body_steps_per_s': 1e6}},
            summary.LOCKSTEP: {'splitting N=10000': {'end_to_end_per_s': 1e6, 'loop_per_s': 1e6},
                               'splitting N=1000000': {'end_to_end_per_s': 1e6},
                               'rk4 N=10000': {'ratio': 1.1, 'loop_ratio': 1.1},
                               'splitting6 N=10000': {'ratio': 1.1, 'loop_ratio': 1.1},
                               'dop853 N=10000': {'ratio': 1.1, 'loop_ratio': 1.1}},
            summary.STARTUP: {'sim': node, 'comparator': node, 'recorder': node},
            summary.IMPACTS: {0: {'cpu_s': 1.0}, 10_000: {'cpu_s': 9.0},
                              'ensemble': {0: {'cpu_s': 1.0}, 10_000: {'cpu_s': 9.0}}},
            summary.IMPACTS_LIVE: {0: {'cpu_s': 1.0}, 10_000: {'cpu_s': 9.0}}}


@pytest.mark.parametrize('quick', [True, False])
def test_a_quick_run_gives_no_verdict_the_full_run_does(bench, quick):
    common, summary = bench
    out = io.StringIO()
    ctx = common.Context(quick=quick, out=out, results=_far_from_the_targets(summary))
    summary.targets_section(ctx)
    text = out.getvalue()
    if quick:
        assert 'MISSED' not in text and 'MET' not in text, text
        assert 'no verdict' in text
        assert ctx.verdict(False) == ctx.verdict(True) != 'MET'
    else:
        assert text.count('MISSED') == sum(len(targets) for _, targets in summary.ISSUES), text
        assert ctx.verdict(True) == 'MET' and ctx.verdict(False, 'MISSED by 2x') == 'MISSED by 2x'


def test_a_target_met_says_met_with_its_gain(bench):
    """Issue 30's main-job row: 6.0 s before, 2.5 s now: MET, gain 2.4x; a missing section."""
    common, summary = bench
    out = io.StringIO()
    ctx = common.Context(out=out, results={summary.MAIN_JOB: {'wall_s': [2.5, 2.7]}})
    results = summary.targets_section(ctx)
    entry = results['issue 30: Fig 9 main job, wall']
    assert entry['met'] is True and abs(entry['gain'] - 6.0 / 2.5) < 1e-12
    assert results['issue 12: Fig 9 main job, wall']['met'] is True
    assert 'issue 30: node on the ROS graph after its start (slowest)' not in results
    assert 'not measured' in out.getvalue()


def test_a_fresh_clone_runs_in_a_new_shells_environment(bench, monkeypatch):
    """The clone's make sees neither this checkout's venv and workspace nor make's variables."""
    import fresh_clone
    root = fresh_clone.ROOT
    monkeypatch.setenv('PATH', os.pathsep.join([str(root / '.venv' / 'bin'), '/usr/bin']))
    monkeypatch.setenv('LD_LIBRARY_PATH', f'{root}/install/tumble_ros_interfaces/lib:/opt/lib')
    monkeypatch.setenv('PYTHONPATH', str(root / 'build' / 'tumble_ros'))
    monkeypatch.setenv('MAKEFLAGS', 's -- BENCH_ARGS=--quick')
    monkeypatch.setenv('VIRTUAL_ENV', str(root / '.venv'))
    monkeypatch.setenv('_ROS_WHEELS_BOOTSTRAP_COMPLETE', '1')
    env = fresh_clone.new_shell_environment()
    assert env['PATH'] == '/usr/bin' and env['LD_LIBRARY_PATH'] == '/opt/lib'
    dropped = {'PYTHONPATH', 'MAKEFLAGS', 'VIRTUAL_ENV', '_ROS_WHEELS_BOOTSTRAP_COMPLETE'}
    assert not dropped & set(env), env
    monkeypatch.setenv('LD_LIBRARY_PATH', f'{root}/.venv/lib/python3.11/site-packages/rclpy')
    assert 'LD_LIBRARY_PATH' not in fresh_clone.new_shell_environment()
    assert env['HOME'] == os.environ['HOME']


def test_the_first_run_of_a_fresh_clone_finds_every_cache_empty_but_the_one_kept(bench,
                                                                                 tmp_path):
    """Issue 48: numba's, matplotlib's, mypy's caches in an empty folder; uv's as asked."""
    import fresh_clone
    base = {'HOME': '/home/u', 'XDG_CACHE_HOME': '/home/u/.cache', 'MPLCONFIGDIR': '/m',
            'NUMBA_CACHE_DIR': '/n', 'UV_CACHE_DIR': '/u', 'PATH': '/usr/bin'}
    env = fresh_clone.empty_cache_environment(base, tmp_path, '/home/u/.cache/uv')
    assert env == {'HOME': '/home/u', 'XDG_CACHE_HOME': str(tmp_path), 'PATH': '/usr/bin',
                   'UV_CACHE_DIR': '/home/u/.cache/uv'}
    cold = fresh_clone.empty_cache_environment(base, tmp_path, None)
    assert 'UV_CACHE_DIR' not in cold and cold['XDG_CACHE_HOME'] == str(tmp_path)
    assert base['MPLCONFIGDIR'] == '/m'     # the caller's environment is left as it was
    # where the package and numba look: under the empty folder
    from tumble_ros.core.user_cache import user_cache_dir
    import unittest.mock
    with unittest.mock.patch.dict(os.environ, env, clear=True):
        assert user_cache_dir() == tmp_path / 'tumble_ros'


def test_a_quick_run_makes_no_fresh_clone(bench, monkeypatch):
    import fresh_clone
    common, _ = bench
    monkeypatch.setattr(fresh_clone.subprocess, 'run', None)     # nothing may be started
    out = io.StringIO()
    assert fresh_clone.fresh_clone_section(common.Context(quick=True, out=out)) is None
    assert 'not measured' in out.getvalue()


def test_a_fresh_clones_log_gives_its_warm_up_and_test_counts(bench):
    """The warm-up's own lines (cli/warmup.py) and pytest's summary, the last of each."""
    import fresh_clone

    from tumble_ros.cli import warmup
    source = Path(warmup.__file__).read_text()
    assert '== the loops of {label} ready ({seconds:.1f} s)' in source
    assert '== compiled loops ready ({seconds:.1f} s)' in source
    log = ('== the loops of the default scenario ready (12.3 s)\n'
           '== compiled loops ready (8.0 s)\n1 failed, 1589 passed in 300.2s\n')
    assert fresh_clone._last(fresh_clone.WARM_UP_READY, log, float) == 8.0
    assert fresh_clone._last(r'(\d+) passed', log, int) == 1589
    assert fresh_clone._last(r'(\d+) skipped', log, int) is None

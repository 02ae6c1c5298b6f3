"""
Shared pytest setup for the tumble_ros tests.

DDS isolation, done at import time: pytest imports this file before any test module, so before
anything imports rclpy (the RMW reads these variables when a context is initialised).

- ROS_DOMAIN_ID: DDS participants only discover each other within one domain. Tests that start
  nodes, publishers or services must not talk to another test process running at the same time
  (a second `make test`, CI, a developer's running simulator), so every test process gets its own
  domain, derived from its pid, in 1..101 (0 is the default domain everybody else uses; with the
  default DDS port mapping, 101 is the highest id whose ports stay below Linux's ephemeral range).
  A caller who sets ROS_DOMAIN_ID (even to 0) keeps it. Under ``pytest -n N`` (pytest-xdist,
  as ``make test`` runs) each worker takes its own domain: derived from the controller's pid and
  the worker's number, so two workers of one run never share one.
- ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST: discovery never leaves this machine, so tests send no
  multicast traffic to the network and see no other host's nodes.
"""
import os
import signal
import time

import pytest

#: Set beside ROS_DOMAIN_ID by this file: an xdist worker inherits both from its controller,
#: and must not take the controller's domain for the caller's.
OURS = 'TUMBLE_ROS_TEST_DOMAIN_ID'


def _own_domain_id() -> int:
    """Return this test process's domain, in 1..101 (see the module docstring)."""
    worker = os.environ.get('PYTEST_XDIST_WORKER', '')     # 'gw0', 'gw1', ... under pytest -n
    if not worker.startswith('gw'):
        return 1 + os.getpid() % 101
    count = max(1, int(os.environ.get('PYTEST_XDIST_WORKER_COUNT', '1')))
    base = os.getppid() % max(1, 101 // count)               # the controller's pid
    return 1 + (base * count + int(worker[2:])) % 101


_given = os.environ.get('ROS_DOMAIN_ID', '').strip()
DOMAIN_ID_FROM_CALLER = bool(_given) and _given != os.environ.get(OURS)
if not DOMAIN_ID_FROM_CALLER:
    os.environ['ROS_DOMAIN_ID'] = os.environ[OURS] = str(_own_domain_id())
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'


@pytest.fixture
def domain_id_from_caller():
    """Tell whether ROS_DOMAIN_ID came from the caller's environment rather than this file."""
    return DOMAIN_ID_FROM_CALLER


@pytest.fixture
def ros():
    """Provide a RosHarness (ros_harness.py), shut down after the test whatever happens."""
    from ros_harness import RosHarness

    harness = RosHarness()
    try:
        yield harness
    finally:
        harness.close()


@pytest.fixture(scope='session', autouse=True)
def dead_dds_segments_removed():
    """
    After the session, remove the DDS shared memory of the processes it killed.

    A SIGKILLed node cannot close its Fast DDS participant, whose segment in /dev/shm would
    stay forever (processes.remove_dead_dds_segments: only those of dead processes, made
    during this session).
    """
    since = time.time()
    yield
    from processes import remove_dead_dds_segments

    remove_dead_dds_segments(since)


@pytest.fixture
def spawn(tmp_path):
    """
    Provide ``start(name, *args, **popen_kwargs) -> processes.Process``.

    Every process group started is killed after the test.
    """
    from processes import Process

    started = []

    def start(name, *args, **kwargs):
        process = Process(name, args, tmp_path / f'{name}_{len(started)}.log', **kwargs)
        started.append(process)
        return process

    try:
        yield start
    finally:
        for process in started:
            process.kill_group()


#: The test files that took longest (the sum of their tests' times, longest first; measured
#: 2026-12-04, benchmarks/HISTORY.md, "The first run"). They are collected first, each
#: file's tests in their own order: pytest-xdist hands the first quarter of the tests out one at
#: a time, alternately, and the rest as workers free up, so the long tests are spread over the
#: workers and the run ends on short ones, not on one worker finishing a long test alone. A file
#: missing here only runs later; a name that no longer exists changes nothing.
LONGEST_FIRST = (
    'test_trust_processes.py', 'test_analysis_robustness.py', 'test_core_perturbers.py',
    'test_figure_pool.py', 'test_readme_commands.py', 'test_mypy.py',
    'test_analysis_periods.py', 'test_apophis_depth.py', 'test_core_divergence.py',
    'test_analysis_cli.py', 'test_flake8.py', 'test_apophis.py', 'test_make_figures.py',
    'test_ensemble_dask.py', 'test_trust_ensembles.py', 'test_core_boundaries.py',
    'test_core_ensemble.py', 'test_node_recorder.py', 'test_node_sim.py',
    'test_process_sim.py', 'test_node_startup.py', 'test_animation.py',
    'test_trust_nodes.py', 'test_main_job.py',
)


@pytest.fixture
def alarm():
    """Fail instead of hanging: SIGALRM after 20 s raises in a blocked call."""
    def expire(signum, frame):
        raise TimeoutError('the reader blocked')
    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(20)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


def pytest_collection_modifyitems(config, items):
    """Collect the files of LONGEST_FIRST first (stable: every file keeps its tests' order)."""
    rank = {name: position for position, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))

"""
``bringup``: simulator + comparator + recorder in one process, for one scenario's duration.

    bringup [SCENARIO] [--output FILE.mcap] [--model NAME] [--quiet] [--visible]
            [--offline] [--ros-args ...]

Runs the three nodes in one executor, the simulator as fast as the comparator and the recorder
take it (``real_time_factor = 0``, ``min_consumers = 2``: nothing is lost), shows progress on
stderr, and ends with a finalised MCAP file and a printed summary. The scenario file is a ROS 2
params file (``config/*.yaml``, or a shipped one's name: ``fig10``); its ``sim`` section
configures the simulator, and ``comparator`` or ``recorder`` sections, if present, those
nodes; ``--ros-args -p name:=value`` overrides the file. Without a file, the default scenario runs.

``--offline`` writes the same recording straight from the simulation, without the ROS graph
(:mod:`tumble_ros.runs.offline`: what differs is said there): the main job uses it.

Isolation: the run is invisible to other ROS processes and sees none of them
(``ROS_AUTOMATIC_DISCOVERY_RANGE=OFF`` for its own context, whatever the environment says), so
two runs at once, or a foreign ``/clock``, never mix into its recording. ``--visible`` keeps the
environment's discovery settings instead (to watch the run with ``ros2 topic echo``); then give
each visible run its own ``ROS_DOMAIN_ID``. A second publisher on the tumble topics is reported
all the same (status, comparison/status, the summary), and the run then exits 1: its recording
holds another run's messages.

Exit codes: 0 finished; 1 diverged, refused input, a recording that failed or that holds a
second source (one ``ERROR:`` line); 130 / 143 / 129 stopped by SIGINT / SIGTERM / SIGHUP
(the file is finalised and the summary printed alike); 141 when stdout or stderr is a closed
pipe (the file is finalised).
"""
from __future__ import annotations

import argparse
from contextlib import contextmanager
from dataclasses import dataclass, field
import operator
import os
from pathlib import Path
import signal
import sys
import time
from typing import TextIO

import rclpy
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.parameter import Parameter

from tumble_ros import topics
from tumble_ros.core import Scenario, ScenarioError
from tumble_ros.core.units import from_years
from tumble_ros.errors import NodeError
from tumble_ros.io import WrittenMessages
from tumble_ros.nodes.comparator import ComparatorNode
from tumble_ros.nodes.parameters import params_file_problem, refuse_unknown_parameters
from tumble_ros.nodes.recorder import default_output, RecorderNode
from tumble_ros.nodes.runner import EXECUTORS, init_rclpy, tear_down
from tumble_ros.nodes.shutdown import StopDuringSetUp, StopSignals
from tumble_ros.nodes.sim import SimNode
from tumble_ros.runs.offline import record_offline
from tumble_ros_interfaces.msg import SimStatus  # type: ignore[attr-defined]  # ROS message

__all__ = ['run_bringup', 'BringupResult', 'main', 'scenario_file', 'shipped_scenarios']


#: Wall-clock seconds between progress lines.
PROGRESS_PERIOD = 1.0
#: Wall-clock seconds to wait for the consumers to drain after the simulator finished.
DRAIN_TIMEOUT = 30.0


@dataclass
class BringupResult:
    """What a bringup run produced."""

    output: Path
    state: int  # SimStatus.FINISHED or DIVERGED (RUNNING/PAUSED if stopped early)
    message: str
    samples: int  # published by the simulator
    counts: dict[str, int] = field(default_factory=dict)  # recorded per topic
    wall_seconds: float = 0.0
    signal: int | None = None  # the SIGINT/SIGTERM that stopped the run early
    error: str | None = None  # why the recording stopped early
    warnings: list[str] = field(default_factory=list)  # second sources seen
    undrained: bool = False  # the consumers had not taken everything after DRAIN_TIMEOUT

    @property
    def ok(self) -> bool:
        """Finished, recorded without failure and from a single source, not stopped."""
        return (self.state == SimStatus.FINISHED and self.error is None and self.signal is None
                and not self.warnings)

    @property
    def exit_code(self) -> int:
        """0 finished, 128 + signal when stopped by one, 1 otherwise (a second source too)."""
        if self.signal is not None:
            return 128 + self.signal
        return 0 if self.ok else 1


def _progress_line(label: str, scenario: Scenario, t: float, samples: int,
                   started: float) -> str:
    """Return a progress line: t [yr] of the duration in the scenario's time unit, the rate."""
    unit = scenario.time_unit
    done = t / scenario.duration
    rate = samples / max(time.monotonic() - started, 1e-9)
    return (f'\r{label}: t = {from_years(t, unit):.6g} / {from_years(scenario.duration, unit):g} '
            f'{unit} ({100 * done:5.1f} %), {samples} samples, {rate:,.0f} samples/s')


@contextmanager
def _isolated(visible: bool):
    """Discovery off for the contexts created inside (the nodes still talk within the process)."""
    key = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
    saved = os.environ.get(key)
    if not visible:
        os.environ[key] = 'OFF'
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = saved


def run_bringup(params_file: str | os.PathLike[str] | None = None, output: str | None = None,
                model: str | None = None, ros_args: list[str] | None = None,
                progress: TextIO | None = sys.stderr, executor_name: str = 'events',
                visible: bool = False, offline: bool = False,
                markers: bool = True, keep: WrittenMessages | None = None) -> BringupResult:
    """
    Run sim + comparator + recorder until the scenario ends; return what was recorded.

    ``executor_name`` is a key of :data:`EXECUTORS`; ``visible``: see the module docstring
    (isolation); ``offline``: write the recording straight from the simulation
    (:mod:`tumble_ros.runs.offline`), no ROS graph (the nodes are only built to read their
    parameters);
    ``markers``: the simulator's 3D scene on ``markers`` (on unless False; it sets the sim's
    ``markers`` parameter, whatever the params file says); ``keep``: with ``offline``, receives
    the messages as written (:func:`~tumble_ros.runs.offline.record_offline`).
    SIGINT and SIGTERM stop the run early with the file finalised (``BringupResult.signal``).
    Raises ScenarioError / ParameterException / ValueError for invalid parameters or params
    files, an unknown executor; OSError when the recording cannot be created (nothing is left
    running then).
    """
    if executor_name not in EXECUTORS:
        raise NodeError(f"executor: must be one of {', '.join(EXECUTORS)}, got {executor_name!r}")
    # The file first: what --ros-args says after it (-p duration:=...) overrides it.
    args = ['bringup', '--ros-args', *(['--params-file', str(params_file)] if params_file else []),
            *(ros_args or [])]
    problem = params_file_problem(args)
    if problem:
        raise NodeError(problem)
    with StopSignals('bringup') as stop, _isolated(visible and not offline):
        if offline:
            return _run_offline(args, output, model, progress, stop, markers, keep)
        return _run(args, output, model, progress, executor_name, stop, markers)


def _run_offline(args, output, model, progress, stop: StopSignals,
                 markers: bool, keep: WrittenMessages | None = None) -> BringupResult:
    """Build the simulator and comparator for their parameters only; record offline."""
    context = Context()
    init_rclpy(args, context)
    nodes: list[Node] = []
    try:
        with stop.interrupting():     # a signal stops a long set-up (a large shape file)
            sim = SimNode(context=context, parameter_overrides=[
                Parameter('real_time_factor', value=0.0), Parameter('markers', value=markers)])
        nodes.append(sim)
        comparator_overrides = [Parameter('model', value=model)] if model else []
        nodes.append(ComparatorNode(context=context, parameter_overrides=comparator_overrides))
        problem = params_file_problem(args, sim.get_fully_qualified_name())
        if problem:
            raise NodeError(problem)
        refuse_unknown_parameters(nodes)
        scenario, timebase = sim.scenario, sim.timebase
        model_name = nodes[1].get_parameter('model').value
        publish_clock = sim.get_parameter('publish_clock').value
        markers = sim.get_parameter('markers').value
        marker_decimation = sim.get_parameter('marker_decimation').value
    finally:
        for node in reversed(nodes):
            node.destroy_node()
        rclpy.try_shutdown(context=context)
    path = Path(output or default_output())
    started = last_line = time.monotonic()

    def show(t: float, samples: int, last: bool = False) -> None:
        nonlocal last_line
        if progress and (last or time.monotonic() - last_line > PROGRESS_PERIOD):
            progress.write(_progress_line('bringup (offline)', scenario, t, samples, started))
            progress.flush()
            last_line = time.monotonic()

    result = record_offline(scenario, path, timebase=timebase, model_name=model_name,
                            publish_clock=publish_clock, markers=markers,
                            marker_decimation=marker_decimation, stop=lambda: stop.requested,
                            progress=show, keep=keep)
    show(result.t, result.samples, last=True)
    if progress:
        progress.write('\n')
    return BringupResult(output=result.output, state=result.state, message=result.message,
                         samples=result.samples, counts=result.counts,
                         wall_seconds=result.wall_seconds, signal=stop.signum)


def _run(args, output, model, progress, executor_name, stop: StopSignals,
         markers: bool) -> BringupResult:
    context = Context()
    init_rclpy(args, context)
    executor = EXECUTORS[executor_name](context=context)
    nodes: list[Node] = []
    try:
        with stop.interrupting():     # a signal stops a long set-up (a large shape file)
            sim = SimNode(context=context, parameter_overrides=[
                Parameter('real_time_factor', value=0.0), Parameter('min_consumers', value=2),
                Parameter('markers', value=markers)])
        nodes.append(sim)
        comparator_overrides = [Parameter('run_id', value=sim.run_id),
                                *([Parameter('model', value=model)] if model else [])]
        comparator = ComparatorNode(context=context, parameter_overrides=comparator_overrides)
        nodes.append(comparator)
        recorder_overrides = [Parameter('output', value=str(output))] if output else []
        recorder = RecorderNode(context=context, parameter_overrides=recorder_overrides,
                                message_info=executor_name != 'events')
        nodes.append(recorder)
        problem = params_file_problem(args, sim.get_fully_qualified_name())
        if problem:
            raise NodeError(problem)
        refuse_unknown_parameters(nodes)
        for node in nodes:
            executor.add_node(node)
        started = last_line = time.monotonic()

        def stopped() -> bool:
            return stop.requested or recorder.error is not None

        while sim.state not in (SimStatus.FINISHED, SimStatus.DIVERGED) and not stopped():
            executor.spin_once(timeout_sec=0.05)
            if progress and time.monotonic() - last_line > PROGRESS_PERIOD:
                progress.write(_progress_line('bringup', sim.scenario, sim.t,
                                              sim.published_samples, started))
                progress.flush()
                last_line = time.monotonic()
        # Let the consumers take what is in flight, until every sample and every comparison
        # has been recorded (latched status/scenario: the last one is always delivered).

        def drained() -> bool:
            counts = recorder.counts
            expected = {**{t: sim.published_samples for t in sim.per_sample_topics},
                        **{t: comparator.compared for t in topics.COMPARATOR_PER_SAMPLE}}
            # a second source (another run on these topics) adds its own messages to the
            # counts, which then never equal ours: all of ours are in once they reach them
            # (that recording is refused anyway); without, waiting here lasted DRAIN_TIMEOUT
            reached = operator.ge if recorder.warnings else operator.eq
            return (reached(comparator.consumed, sim.published_samples)
                    and all(reached(counts.get(sim.resolve_topic_name(t), 0), n)
                            for t, n in expected.items()))

        deadline = time.monotonic() + DRAIN_TIMEOUT
        while not drained() and not stopped() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        undrained = not drained() and not stopped()
        if progress:
            progress.write(_progress_line('bringup', sim.scenario, sim.t,
                                          sim.published_samples, started) + '\n')
        comparator.close()
        recorder.close()
        return BringupResult(output=recorder.path, state=sim.state, message=sim.status_message,
                             samples=sim.published_samples, counts=dict(recorder.counts),
                             wall_seconds=time.monotonic() - started, signal=stop.signum,
                             error=recorder.error, warnings=list(recorder.warnings),
                             undrained=undrained)
    finally:
        tear_down(executor, list(reversed(nodes)), context)


def shipped_scenarios() -> dict[str, Path]:
    """Return the scenario files installed with the package: {name: share/tumble_ros/config/..}."""
    from ament_index_python.packages import get_package_share_directory, PackageNotFoundError

    try:
        config = Path(get_package_share_directory('tumble_ros')) / 'config'
    except PackageNotFoundError:
        return {}
    return {path.stem: path for path in sorted(config.glob('*.yaml'))}


def scenario_file(name: str) -> Path:
    """
    Return the params file ``name`` names: a file, or a shipped scenario's name (``fig10``).

    Raises NodeError naming the shipped scenarios when it is neither.
    """
    path = Path(name)
    if path.is_file():
        return path
    shipped = shipped_scenarios()
    if path.suffix in ('', '.yaml') and path.parent == Path('.') and path.stem in shipped:
        return shipped[path.stem]
    raise NodeError(f"no scenario file {name} (shipped scenarios: {', '.join(shipped)})")


def format_result(result: BringupResult) -> str:
    """Return the printed summary of a run."""
    size = result.output.stat().st_size if result.output.exists() else 0
    if result.signal is not None:
        head = (f'stopped by {signal.Signals(result.signal).name} after {result.samples} samples; '
                'the recording was finalised')
    elif result.error:
        head = f'ERROR: {result.error}'
    else:
        state = 'finished' if result.state == SimStatus.FINISHED else 'DIVERGED'
        head = f'{state}: {result.message}'
    mixed = (['bringup: ERROR: the recording holds a second source (another run on the same '
              'topics): analyze refuses it unless --run chooses one run'] if result.warnings
             else [])
    late = ([f'bringup: WARNING: the comparator and recorder had not taken every sample '
             f'{DRAIN_TIMEOUT:g} s after the simulator finished: the recording may miss the '
             'last ones'] if result.undrained else [])
    lines = [f'bringup: {head}', *(f'bringup: WARNING: {w}' for w in result.warnings), *mixed,
             *late,
             f'  {result.samples} samples in {result.wall_seconds:.1f} s wall; '
             f'recorded {result.output} ({size / 1e6:.2f} MB)']
    lines += [f'  {topic:40s} {count:8d}' for topic, count in sorted(result.counts.items())]
    return '\n'.join(lines)


def main(args: list[str] | None = None, keep: WrittenMessages | None = None) -> int:
    """
    Entry point of ``ros2 run tumble_ros bringup``; ``args``: sys.argv, program name first.

    ``keep``: for the main job (``python -m tumble_ros``), receives an offline run's messages.
    """
    argv = list(sys.argv if args is None else args)[1:]
    ros_args = []
    if '--ros-args' in argv:
        k = argv.index('--ros-args')
        argv, ros_args = argv[:k], argv[k + 1:]
    parser = argparse.ArgumentParser(
        prog='bringup', description=__doc__.split('\n\n')[0],
        usage='%(prog)s [SCENARIO] [options] [--ros-args -p NAME:=VALUE ...]',
        epilog='--ros-args ends the options: what follows goes to the three nodes, e.g. '
               '--ros-args -p duration:=5.0 -p integrator.method:=rk4 (overrides the scenario '
               'file). Exit codes: 0 finished; 1 diverged, refused input or a failed recording; '
               '130 / 143 / 129 after SIGINT / SIGTERM / SIGHUP; 141 on a closed pipe.')
    parser.add_argument('scenario', nargs='?',
                        help='ROS 2 params file, or the name of a shipped one (fig10: '
                             'config/fig10.yaml); default scenario if omitted')
    parser.add_argument('--output',
                        help='MCAP file to write (default recordings/tumble_<time>.mcap)')
    parser.add_argument('--model', help="the comparator's analytic model")
    parser.add_argument('--executor', choices=sorted(EXECUTORS), default='events',
                        help='rclpy executor running the three nodes '
                             '(default: events, the faster)')
    parser.add_argument('--offline', action='store_true',
                        help='write the recording straight from the simulation, without the '
                             'ROS graph (the same file, see tumble_ros.runs.offline)')
    parser.add_argument('--quiet', action='store_true', help='no progress display')
    parser.add_argument('--no-markers', action='store_true',
                        help="do not publish and record the 3D scene ('markers')")
    parser.add_argument('--visible', action='store_true',
                        help='let other ROS processes see the run (default: isolated, '
                             'ROS_AUTOMATIC_DISCOVERY_RANGE=OFF for its own context); give each '
                             'visible run its own ROS_DOMAIN_ID')
    options = parser.parse_args(argv)
    try:
        scenario = scenario_file(options.scenario) if options.scenario else None
        result = run_bringup(scenario, options.output, options.model, ros_args,
                             progress=None if options.quiet else sys.stderr,
                             executor_name=options.executor,
                             visible=options.visible, offline=options.offline,
                             markers=not options.no_markers, keep=keep)
    except StopDuringSetUp as stopped:      # while the simulator was built: nothing recorded
        signum = int(stopped.args[0])
        print(f'bringup: stopped by {signal.Signals(signum).name} while starting: nothing '
              'recorded', file=sys.stderr)
        return 128 + signum
    except (ScenarioError, ValueError, ParameterException) as err:
        print(f"ERROR: {' '.join(str(err).split())}", file=sys.stderr)
        return 1
    except OSError as err:  # the recording cannot be created (read-only directory, exists, ...)
        print(f'ERROR: cannot record: {err}', file=sys.stderr)
        return 1
    print(format_result(result))
    return result.exit_code


if __name__ == '__main__':
    raise SystemExit(main())

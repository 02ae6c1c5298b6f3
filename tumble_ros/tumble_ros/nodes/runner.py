"""The one ``main()`` of every node executable (the demo_nodes_py pattern, written once)."""
from __future__ import annotations

import faulthandler
import os
import re
import sys
from typing import Callable

import rclpy
from rclpy._rclpy_pybind11 import RCLError, UnknownROSArgsError
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.logging import LoggingSeverity, set_logger_level
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from tumble_ros.errors import NodeError
from tumble_ros.nodes.parameters import params_file_problem, refuse_unknown_parameters
from tumble_ros.nodes.shutdown import spin_until_stopped, StopDuringSetUp, StopSignals

__all__ = ['run_node', 'close_node', 'tear_down', 'init_rclpy', 'wants_help', 'EXECUTORS',
           'EXECUTOR_ENV', 'chosen_executor', 'TEARDOWN_TIMEOUT']

#: Seconds the ROS side of a node process's teardown (executor shutdown, node destruction,
#: context shutdown) may take once every node's ``close()`` has run (files finalised, goodbyes
#: sent). Past it the process prints every thread's stack and exits with status 1: a hang
#: there is a deadlock inside rclpy/rmw (seen once in ~1300 node stops, main thread blocked
#: in an event's destruction inside the EventsExecutor's shutdown), and nothing is left to lose.
TEARDOWN_TIMEOUT = 15.0


def _events_executor(context: Context | None = None):
    # rclpy's EventsExecutor() calls faulthandler.enable(), which needs sys.stderr to be a real
    # file; pytest's capture (and some IDE consoles) replace it by one without a descriptor.
    saved = sys.stderr
    sys.stderr = sys.__stderr__ or saved
    try:
        return EventsExecutor(context=context)
    finally:
        sys.stderr = saved


def _single_executor(context: Context | None = None):
    return SingleThreadedExecutor(context=context)


#: The executors nodes run in. ``events`` (rclpy's C++ EventsExecutor, experimental in Jazzy)
#: runs the pipeline about 4x faster than ``single`` (the Python SingleThreadedExecutor, which
#: rebuilds its wait set over every entity at every wake-up); it cannot hand MessageInfo to
#: callbacks, so the recorder stamps publish times on receipt there.
EXECUTORS = {'events': _events_executor, 'single': _single_executor}
#: Environment variable choosing the executor of a standalone node (``ros2 run``): ``events``
#: (default) or ``single``.
EXECUTOR_ENV = 'TUMBLE_ROS_EXECUTOR'


def chosen_executor() -> str:
    """Return the executor a standalone node runs in (``$TUMBLE_ROS_EXECUTOR``, default events)."""
    name = os.environ.get(EXECUTOR_ENV, '') or 'events'
    if name not in EXECUTORS:
        raise NodeError(f'{EXECUTOR_ENV}={name!r}: must be one of {sorted(EXECUTORS)}')
    return name


def wants_help(args: list[str]) -> bool:
    """Tell whether ``args`` (program name first) ask for help before any ``--ros-args``."""
    own = list(args[1:])
    if '--ros-args' in own:
        own = own[:own.index('--ros-args')]
    return '-h' in own or '--help' in own


def init_rclpy(args: list[str], context: Context | None = None) -> None:
    """
    ``rclpy.init`` without rclpy's signal handlers; rcl's refusals as one-line NodeErrors.

    rcl refuses with a traceback a params file its parser cannot read although it is valid YAML
    (anchors and aliases, a sequence as a key: :func:`params_file_problem` lets them through)
    and an option it does not know after ``--ros-args``: the NodeError says which and why.
    """
    # rcl logs its own "Failed to parse global arguments" before raising: the NodeError says it
    # better, in one line (rcl's level is set back at once: its later messages are shown).
    set_logger_level('rcl', LoggingSeverity.FATAL)
    try:
        rclpy.init(args=args, context=context, signal_handler_options=SignalHandlerOptions.NO)
    except UnknownROSArgsError as err:
        unknown = ' '.join(re.findall(r"'([^']*)'", str(err))) or str(err)
        raise NodeError(f'unknown option after --ros-args: {unknown} (ROS arguments only there: '
                        '-p name:=value, --params-file FILE, -r from:=to, --log-level ...; '
                        "the program's own options go before --ros-args)") from None
    except RCLError as err:
        text = ' '.join(str(err).split())
        found = re.search(r"params file: '--params-file (.*?)'\. Error: (.*?)(?:, at \S+)*$",
                          text)
        if found:
            reason = found[2].strip()
            raise NodeError(f'params file {found[1]}: rcl cannot parse it: {reason}') from None
        raise NodeError('cannot start ROS: ' + re.sub(r', at \S+', '', text)) from None
    finally:
        set_logger_level('rcl', LoggingSeverity.UNSET)


def _close(node: Node) -> None:
    """Run the node's ``close()`` if it has one (finalise a file, say goodbye)."""
    close = getattr(node, 'close', None)
    if close is not None:
        close()


def close_node(node: Node) -> None:
    """Close a node no executor holds (:func:`_close`), then destroy it."""
    _close(node)
    node.destroy_node()


def tear_down(executor, nodes: list[Node], context: Context | None = None,
              watchdog: bool = False) -> None:
    """
    Close every node, shut the executor down, then destroy the nodes and the context.

    The order matters: ``close()`` (finalise a file, say goodbye) needs only a valid context;
    the executor must let go of the nodes' entities *before* they are destroyed. Destroyed
    first, their last reference was the executor's, and the rcl/rmw destruction then ran
    inside rclpy's EventsExecutor shutdown, where it once blocked for good (CI, a sim stopped
    by SIGINT right after a consumer left). ``watchdog`` (a node process's own teardown only):
    if the ROS part takes over :data:`TEARDOWN_TIMEOUT`, print every thread's stack and exit
    with status 1 from a C thread (the blocked main thread may hold the GIL).
    """
    for node in nodes:
        _close(node)
    if watchdog:
        faulthandler.dump_traceback_later(TEARDOWN_TIMEOUT, exit=True)
    try:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
    finally:
        if watchdog:
            faulthandler.cancel_dump_traceback_later()


def run_node(make_node: Callable[[], Node], args: list[str] | None, name: str,
             needs_params_section: bool = False) -> int:
    """
    Init rclpy, build the node, spin until SIGINT/SIGTERM/SIGHUP, close, clean up.

    ``--help`` (before any ``--ros-args``) prints the usage and the node's module docstring.
    Returns 0 on a stop by SIGINT, SIGTERM or SIGHUP (all finalise alike: the node's ``close()``
    runs while its context is still valid; a second signal during the clean-up is absorbed; one
    while the node is being built stops the building at once), 1 when
    the node refused its parameters, a params file or a ROS argument (one line saying why, no
    traceback).
    ``needs_params_section``: every ``--params-file`` must have a section for this node (the
    simulator's scenario files).
    """
    args = sys.argv if args is None else args
    if wants_help(args):
        print(f'usage: {name} [--ros-args [-p NAME:=VALUE ...] [--params-file FILE]]\n\n'
              f"{(sys.modules[make_node.__module__].__doc__ or '').strip()}")
        return 0
    problem = params_file_problem(args)
    try:
        executor_name = chosen_executor()
    except NodeError as err:
        problem = str(err)
    if problem:
        print(f'{name}: {problem}', file=sys.stderr, flush=True)
        return 1
    with StopSignals(name) as stop:
        # Our handlers, not rclpy's: rclpy's would shut the context down before close().
        try:
            init_rclpy(args)
        except NodeError as err:
            print(f'{name}: {err}', file=sys.stderr, flush=True)
            return 1
        executor = EXECUTORS[executor_name]()
        node = None
        try:
            with stop.interrupting():       # a signal stops a long set-up (a large shape file)
                node = make_node()
            problem = (params_file_problem(args, node.get_fully_qualified_name())
                       if needs_params_section else None)
            if problem:
                raise NodeError(problem)
            refuse_unknown_parameters([node])
            executor.add_node(node)
            spin_until_stopped(executor, lambda: stop.requested)
        except StopDuringSetUp:
            return 0                        # stopped before it ran: nothing to finalise
        except (ParameterException, ValueError) as err:   # ScenarioError is a ValueError
            print(f'{name}: invalid parameters: {err}', file=sys.stderr, flush=True)
            return 1
        except OSError as err:  # e.g. the recorder cannot create its file
            print(f'{name}: cannot start: {err}', file=sys.stderr, flush=True)
            return 1
        finally:
            tear_down(executor, [node] if node is not None else [], watchdog=True)
    return 0

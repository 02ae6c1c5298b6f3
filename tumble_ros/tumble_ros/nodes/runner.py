"""The one ``main()`` of every node executable (the demo_nodes_py pattern, written once)."""
from __future__ import annotations

import os
import sys
from typing import Callable

import rclpy
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from tumble_ros.core import ScenarioError
from tumble_ros.errors import NodeError
from tumble_ros.nodes.parameters import params_file_problem, refuse_unknown_parameters
from tumble_ros.nodes.shutdown import spin_until_stopped, StopSignals

__all__ = ['run_node', 'close_node', 'EXECUTORS', 'EXECUTOR_ENV', 'chosen_executor']


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


def close_node(node: Node) -> None:
    """Run the node's ``close()`` if it has one (finalise a file, say goodbye), then destroy it."""
    close = getattr(node, 'close', None)
    if close is not None:
        close()
    node.destroy_node()


def run_node(make_node: Callable[[], Node], args: list[str] | None, name: str,
             needs_params_section: bool = False) -> int:
    """
    Init rclpy, build the node, spin until SIGINT/SIGTERM, close, clean up.

    Returns 0 on a stop by SIGINT or SIGTERM (both finalise alike: the node's ``close()`` runs
    while its context is still valid; a second signal during the clean-up is absorbed), 1 when
    the node refused its parameters or a params file (one line saying why, no traceback).
    ``needs_params_section``: every ``--params-file`` must have a section for this node (the
    simulator's scenario files).
    """
    args = sys.argv if args is None else args
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
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        executor = EXECUTORS[executor_name]()
        node = None
        try:
            node = make_node()
            problem = (params_file_problem(args, node.get_fully_qualified_name())
                       if needs_params_section else None)
            if problem:
                raise NodeError(problem)
            refuse_unknown_parameters([node])
            executor.add_node(node)
            spin_until_stopped(executor, lambda: stop.requested)
        except (ParameterException, ScenarioError, ValueError) as err:
            print(f'{name}: invalid parameters: {err}', file=sys.stderr, flush=True)
            return 1
        except OSError as err:  # e.g. the recorder cannot create its file
            print(f'{name}: cannot start: {err}', file=sys.stderr, flush=True)
            return 1
        finally:
            if node is not None:
                close_node(node)
            executor.shutdown()
            rclpy.try_shutdown()
    return 0

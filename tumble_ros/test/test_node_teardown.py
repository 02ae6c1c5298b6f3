"""The teardown order of a node process (nodes.runner.tear_down) and its last-resort watchdog."""
from __future__ import annotations

import subprocess
import sys
import textwrap

from tumble_ros.nodes import runner


class _Recorded:
    """A stand-in executor and nodes that write what is done to them into one list."""

    def __init__(self, calls: list[str], name: str) -> None:
        self.calls, self.name = calls, name

    def close(self) -> None:
        self.calls.append(f'close {self.name}')

    def destroy_node(self) -> None:
        self.calls.append(f'destroy {self.name}')

    def shutdown(self) -> None:
        self.calls.append('executor shutdown')


def test_nodes_are_closed_then_let_go_by_the_executor_then_destroyed(monkeypatch):
    """
    close() of every node, then the executor's shutdown, then the destruction.

    Destroyed before the executor let go of them, the nodes' rcl entities were finalised inside
    the EventsExecutor's shutdown, where a sim stopped by SIGINT once blocked for good.
    """
    calls: list[str] = []
    monkeypatch.setattr(runner.rclpy, 'try_shutdown',
                        lambda context=None: calls.append('context shutdown'))
    nodes = [_Recorded(calls, 'recorder'), _Recorded(calls, 'comparator')]
    runner.tear_down(_Recorded(calls, 'executor'), nodes)  # type: ignore[arg-type]
    assert calls == ['close recorder', 'close comparator', 'executor shutdown',
                     'destroy recorder', 'destroy comparator', 'context shutdown']


def test_a_teardown_blocked_past_the_timeout_exits_1_with_the_stacks_after_closing():
    """A hang in the ROS part of the teardown ends the process, the node's close() done first."""
    script = textwrap.dedent("""
        import threading
        from tumble_ros.nodes import runner

        class Node:
            def close(self):
                print('closed', flush=True)

        class Executor:
            def shutdown(self):
                threading.Event().wait()      # never returns, as the deadlock did

        runner.TEARDOWN_TIMEOUT = 0.5
        runner.tear_down(Executor(), [Node()], watchdog=True)
        print('not reached', flush=True)
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert done.stdout.strip() == 'closed'
    assert 'Timeout' in done.stderr and 'in shutdown' in done.stderr, done.stderr


def test_a_teardown_in_time_leaves_no_watchdog_behind():
    """The watchdog is disarmed once the teardown ends: the process lives on past the timeout."""
    script = textwrap.dedent("""
        import time
        from tumble_ros.nodes import runner

        class Executor:
            def shutdown(self):
                pass

        runner.rclpy.try_shutdown = lambda context=None: None
        runner.TEARDOWN_TIMEOUT = 0.3
        runner.tear_down(Executor(), [], watchdog=True)
        time.sleep(1.0)
        print('alive', flush=True)
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=60)
    assert (done.returncode, done.stdout.strip()) == (0, 'alive'), done.stderr

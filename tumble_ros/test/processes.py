"""
Executables as their own processes, for the tests that need real signals and real concurrency.

Each process is started in its own session (process group), with its output in a file (a pipe
that nobody reads can block a chatty node), and the ``spawn`` fixture (conftest.py) kills every
group it started when the test ends. The processes inherit the test process's DDS isolation
(ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST from conftest.py).
"""
from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import time


def executable(name: str) -> str:
    """Where `ros2 run tumble_ros <name>` finds it: <prefix>/lib/tumble_ros/<name>."""
    from ament_index_python.packages import get_package_prefix

    path = Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / name
    assert path.is_file() and os.access(path, os.X_OK), f'{path} is not installed (make setup)'
    return str(path)


class Process:
    """One started executable: its Popen, its output file."""

    def __init__(self, name: str, args, log: Path, **kwargs) -> None:
        self.name, self.log = name, log
        self._out = open(log, 'w')
        self.popen = subprocess.Popen([executable(name), *map(str, args)], stdout=self._out,
                                      stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                      text=True,
                                      start_new_session=True, **kwargs)

    @property
    def output(self) -> str:
        return self.log.read_text(errors='replace')

    def wait_for(self, text: str, timeout: float = 30.0) -> bool:
        """Wait until ``text`` is in the output (False: timeout, or the process ended first)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.output:
                return True
            if self.popen.poll() is not None:
                return text in self.output
            time.sleep(0.05)
        return False

    def signal(self, signum: int) -> None:
        self.popen.send_signal(signum)

    def wait(self, timeout: float = 30.0) -> int:
        """
        Exit code (as Popen reports it: -N for a signal N).

        A process still running after ``timeout`` is a hang: it gets SIGABRT, on which Python's
        faulthandler (enabled by rclpy's EventsExecutor, the nodes' default) prints every
        thread's stack to its output, and the AssertionError carries that output.
        """
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.popen.send_signal(signal.SIGABRT)
            try:
                self.popen.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
            raise AssertionError(f'{self.name} still running {timeout} s after being asked to '
                                 f'stop; its output (with the stacks at SIGABRT):\n'
                                 f'{self.output[-6000:]}') from None

    def kill_group(self) -> None:
        if self.popen.poll() is None:
            try:
                os.killpg(self.popen.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        self.popen.wait(timeout=10)
        self._out.close()

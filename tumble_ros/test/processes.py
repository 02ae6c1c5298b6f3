"""
Executables as their own processes, for the tests that need real signals and real concurrency.

Each process is started in its own session (process group), with its output in a file (a pipe
that nobody reads can block a chatty node), and the ``spawn`` fixture (conftest.py) kills every
group it started when the test ends. The processes inherit the test process's DDS isolation
(ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST from conftest.py).
"""
from __future__ import annotations

import fcntl
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

#: Where Fast DDS keeps its shared-memory transport's segments.
SHM = Path('/dev/shm')
#: A segment younger than this [s] is never removed (its process may be taking its lock now).
SHM_MIN_AGE = 2.0


def executable(name: str) -> str:
    """Where `ros2 run tumble_ros <name>` finds it: <prefix>/lib/tumble_ros/<name>."""
    from ament_index_python.packages import get_package_prefix

    path = Path(get_package_prefix('tumble_ros')) / 'lib' / 'tumble_ros' / name
    assert path.is_file() and os.access(path, os.X_OK), f'{path} is not installed (make setup)'
    return str(path)


class Process:
    """One started executable: its Popen, its output file."""

    def __init__(self, name: str, args, log: Path, module: bool | str = False,
                 **kwargs) -> None:
        """
        Start ``name`` with ``args``: the installed executable (what `ros2 run` runs).

        ``module``: through the project's own entry point instead, ``python -m tumble_ros
        <name>`` (``name`` '' for the main job); a module name: ``python -m <module>`` (a
        command's module entry, ``tumble_ros.analysis``), ``name`` only naming the log.
        """
        self.name, self.log = name, log
        self._out = open(log, 'w')
        if isinstance(module, str):
            command = [sys.executable, '-m', module]
        elif module:
            command = [sys.executable, '-m', 'tumble_ros', *([name] if name else [])]
        else:
            command = [executable(name)]
        self.popen = subprocess.Popen([*command, *map(str, args)], stdout=self._out,
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


def remove_dead_dds_segments(since: float) -> int:
    """
    Remove the shared-memory segments of DDS participants whose process died; return how many.

    A process killed with SIGKILL (the tests kill some on purpose, and the ``spawn`` fixture
    kills what is left) cannot close its Fast DDS participant, whose segment
    ``/dev/shm/fastrtps_<id>`` and lock file ``<id>_el`` then stay forever (Fast DDS removes
    them on a clean exit; its ``fastdds shm clean`` tool is what removes such leftovers). A
    live participant holds an flock on its ``_el`` file: only segments whose lock can be taken,
    modified since ``since`` (time.time()) and older than :data:`SHM_MIN_AGE` are removed. The
    port segments (``fastrtps_port*``), shared by the participants of a domain, are left to
    Fast DDS.
    """
    removed = 0
    now = time.time()
    for lock in SHM.glob('fastrtps_*_el'):
        segment = lock.with_name(lock.name[:-len('_el')])
        if segment.name.startswith('fastrtps_port'):
            continue
        try:
            modified = lock.stat().st_mtime
            if not since <= modified <= now - SHM_MIN_AGE:
                continue
            fd = os.open(lock, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:   # its participant is alive
            os.close(fd)
            continue
        try:
            segment.unlink(missing_ok=True)
            lock.unlink(missing_ok=True)
            removed += 1
        finally:
            os.close(fd)
    return removed

"""
In-process ROS test harness: a private context, one executor, automatic cleanup.

Follows the rclpy tests' pattern: a private ``Context``, nodes built with
``parameter_overrides``, a ``SingleThreadedExecutor`` bound to the context; no launch files.
DDS isolation comes from conftest.py (ROS_DOMAIN_ID per test process, LOCALHOST discovery).
"""
from __future__ import annotations

import time
from typing import Any, Callable

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

from tumble_ros.runs.messages.qos import LATCHED_QOS, STATE_QOS


class RosHarness:
    """Owns a context, an executor, the nodes under test and a probe node."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes: list = []
        self.probe = self.add(rclpy.create_node('probe', context=self.context))

    def add(self, node):
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def start(self, node_class, **overrides):
        """Build ``node_class`` in this context with parameter overrides (name=value)."""
        params = [Parameter(name.replace('__', '.'), value=value)
                  for name, value in overrides.items()]
        return self.add(node_class(context=self.context, parameter_overrides=params))

    def collect(self, msg_type, topic: str, latched: bool = False, qos=None) -> list:
        """Subscribe the probe to ``topic``; returns the list that fills with messages."""
        box: list = []
        self.probe.create_subscription(msg_type, topic, box.append,
                                       qos or (LATCHED_QOS if latched else STATE_QOS))
        return box

    def spin_until(self, predicate: Callable[[], bool], timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            self.executor.spin_once(timeout_sec=0.01)
        return predicate()

    def spin_ticks(self, timer, n: int, timeout: float = 10.0) -> bool:
        """
        Spin until ``timer`` (a node's rclpy Timer) has fired ``n`` more times.

        For checks that something does NOT happen: after the node's own timer ran n times the
        node had every chance to act, however slow the machine (no wall-clock guess).
        """
        fired = [0]
        callback = timer.callback

        def counting():
            fired[0] += 1
            callback()

        timer.callback = counting
        try:
            return self.spin_until(lambda: fired[0] >= n, timeout)
        finally:
            timer.callback = callback

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)

    def call(self, srv_type, name: str, request, timeout: float = 10.0) -> Any:
        client = self.probe.create_client(srv_type, name)
        assert client.wait_for_service(timeout_sec=timeout), f'service {name} not available'
        future = client.call_async(request)
        assert self.spin_until(future.done, timeout), f'no answer from {name}'
        self.probe.destroy_client(client)
        return future.result()

    def close(self) -> None:
        for node in self.nodes:
            self.executor.remove_node(node)
            node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)

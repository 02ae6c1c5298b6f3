"""
Timers on the steady clock, for the nodes' own machinery.

A node's default timer runs on ROS time, which with ``use_sim_time:=true`` only advances when
``/clock`` does. The simulator *is* the clock source, and the consumers' progress reports, the
recorder's discovery and chunk flushing are wall-clock duties: on ROS time they would wait for a
``/clock`` that waits for them (the simulator froze with ``use_sim_time:=true``). Every internal
timer is therefore created here, on the steady clock, whatever ``use_sim_time`` says.
"""
from __future__ import annotations

from typing import Callable

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.timer import Timer

__all__ = ['steady_timer']


def steady_timer(node: Node, period: float, callback: Callable[[], None]) -> Timer:
    """Create a timer of ``node`` calling ``callback`` every ``period`` s of steady (wall) time."""
    return node.create_timer(period, callback, clock=Clock(clock_type=ClockType.STEADY_TIME))

"""Declaring and reading ROS 2 parameters with descriptors (description, unit, range).

The scenario's parameters come from :data:`tumble_ros.core.scenario.PARAMETER_DOCS` and are
validated by :class:`tumble_ros.core.Scenario` itself: the node adds no rules of its own.
They are read-only: a scenario is fixed for the life of a run.
"""
from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter

from tumble_ros.core import PARAMETER_DOCS, Scenario

__all__ = ["declare_node_parameters", "declare_scenario_parameters", "node_parameter", "read_parameters", "read_scenario_parameters", "describe"]

#: Array parameters whose default is empty need an explicit type.
_EMPTY_ARRAY_TYPES = {"impacts.frame": Parameter.Type.STRING_ARRAY}


def describe(description: str, unit: str) -> str:
    """Parameter description with its unit in brackets."""
    return f"{description} [{unit}]" if unit else description


def declare_scenario_parameters(node: Node) -> None:
    """Declare every Scenario field as a read-only parameter, defaults from ``Scenario()``."""
    for name, default in Scenario().to_parameters().items():
        unit, description = PARAMETER_DOCS[name]
        descriptor = ParameterDescriptor(
            description=describe(description, unit),
            additional_constraints="validated by tumble_ros.core.Scenario (docs/physics.md)",
            read_only=True,
            # Integers in YAML (duration: 2) are accepted; Scenario converts and checks.
            dynamic_typing=True,
        )
        if isinstance(default, list) and not default:
            descriptor.dynamic_typing = False  # rclpy: a declared type excludes dynamic typing
            node.declare_parameter(name, _EMPTY_ARRAY_TYPES.get(name, Parameter.Type.DOUBLE_ARRAY), descriptor)
        else:
            node.declare_parameter(name, default, descriptor)


def node_parameter(node: Node, name: str, default: Any, unit: str, description: str,
                   value_range: tuple[float, float] | None, read_only: bool) -> None:
    """Declare one of a node's own parameters, with its range enforced by rclpy."""
    descriptor = ParameterDescriptor(description=describe(description, unit), read_only=read_only)
    if isinstance(default, int) and not isinstance(default, bool):
        low, high = value_range if value_range is not None else (0, 2**31 - 1)
        descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high), step=1)]
    elif value_range is not None:
        descriptor.floating_point_range = [
            FloatingPointRange(from_value=float(value_range[0]), to_value=float(value_range[1]), step=0.0)]
    node.declare_parameter(name, default, descriptor)


def declare_node_parameters(node: Node, table: dict[str, tuple]) -> dict[str, Any]:
    """Declare a node's own parameters from ``{name: (default, unit, description, range, read_only)}``
    and return their values (overrides and params files applied, ranges enforced)."""
    for name, spec in table.items():
        node_parameter(node, name, *spec)
    return read_parameters(node, table)


def _value(node: Node, name: str) -> Any:
    try:
        value = node.get_parameter(name).value
    except ParameterUninitializedException:
        return []
    return list(value) if isinstance(value, (list, tuple)) or hasattr(value, "tolist") else value


def read_parameters(node: Node, names) -> dict[str, Any]:
    """Current values of the named parameters."""
    return {name: _value(node, name) for name in names}


def read_scenario_parameters(node: Node) -> dict[str, Any]:
    """Current values of the scenario parameters (see :func:`declare_scenario_parameters`)."""
    return read_parameters(node, PARAMETER_DOCS)

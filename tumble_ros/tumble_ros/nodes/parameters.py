"""
Declaring and reading ROS 2 parameters with descriptors (description, unit, range).

The scenario's parameters come from :data:`tumble_ros.core.model.scenario.PARAMETER_DOCS` and are
validated by :class:`tumble_ros.core.Scenario` itself: the node adds no rules of its own.
They are read-only: a scenario is fixed for the life of a run.

``tumble_ros.core`` (numba, the kernels: ~0.3 s) is imported by the functions that need it, not
with this module: the recorder, which declares no scenario, never imports it
(benchmarks/HISTORY.md, "Node start-up"; tests/test_node_startup.py).
"""
from __future__ import annotations

import difflib
from typing import Any, Iterable

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter
from tumble_ros.errors import NodeError

__all__ = ['EMPTY_ARRAY_TYPES', 'declare_node_parameters', 'declare_scenario_parameters',
           'node_parameter',
           'read_parameters', 'read_scenario_parameters', 'describe', 'params_file_problem',
           'refuse_unknown_parameters', 'section_applies']


def describe(description: str, unit: str) -> str:
    """Parameter description with its unit in brackets."""
    return f'{description} [{unit}]' if unit else description


#: The type of each scenario parameter whose default is an empty array. rclpy types ``[]`` as a
#: byte array, and rcl reads ``[]`` in a params file as "not set": both made ``ros2 param dump``
#: write ``null`` on the next generation (then the string ``'null'``), so these are declared with
#: their element type whatever the file says, and dump -> load -> dump is a fixed point.
EMPTY_ARRAY_TYPES = {
    'impacts.start': Parameter.Type.DOUBLE_ARRAY,
    'impacts.duration': Parameter.Type.DOUBLE_ARRAY,
    'impacts.torque': Parameter.Type.DOUBLE_ARRAY,
    'impacts.frame': Parameter.Type.STRING_ARRAY,
    'perturbers.names': Parameter.Type.STRING_ARRAY,
    'body.stokes': Parameter.Type.DOUBLE_ARRAY,
}


def declare_scenario_parameters(node: Node) -> None:
    """
    Declare every Scenario field as a read-only parameter, defaults from ``Scenario()``.

    Every parameter gets a value, empty arrays included (``impacts.*: []``): a parameter declared
    without a value makes GetParameters answer nothing for the whole request, so ``ros2 param
    dump`` printed ``ros__parameters: {}``. Dynamic typing lets an override of any type through
    (integers in YAML, ``duration: 2``); Scenario converts and checks every value. An empty
    array, from the default or from a file (where rcl reads ``[]`` as not set), is given its
    element type (:data:`EMPTY_ARRAY_TYPES`).
    """
    from tumble_ros.core import PARAMETER_DOCS, Scenario
    defaults = Scenario().to_parameters()     # in years, values_in_years False
    for name in ('time_unit', 'values_in_years'):
        _declare_scenario_parameter(node, name, defaults.pop(name), PARAMETER_DOCS[name])
    for name, default in _defaults_in_unit(node, defaults).items():
        _declare_scenario_parameter(node, name, default, PARAMETER_DOCS[name])
    _declare_perturbers(node)


def _defaults_in_unit(node: Node, defaults: dict[str, Any]) -> dict[str, Any]:
    """
    Return the defaults [yr] in the unit of the node's values (``time_unit``, or years).

    A node given ``time_unit: h`` lists (``ros2 param get``) the defaults it runs: the default
    step 1e-4 yr as 0.8766 h, not 1e-4 (which it would have read as 1e-4 h). An unknown unit
    leaves them in years (the Scenario refuses it, naming time_unit).
    """
    from tumble_ros.core.units import in_unit, TIME_UNITS
    unit = node.get_parameter('time_unit').value
    in_years = node.get_parameter('values_in_years').value
    if in_years is not False or unit not in TIME_UNITS:
        return defaults
    return in_unit(defaults, unit)


def _declare_scenario_parameter(node: Node, name: str, default: Any,
                                doc: tuple[str, str]) -> None:
    """Declare one scenario parameter (:func:`declare_scenario_parameters`)."""
    unit, description = doc
    descriptor = ParameterDescriptor(
        description=describe(description, unit),
        additional_constraints='validated by tumble_ros.core.Scenario (docs/physics.md)',
        read_only=True,
        dynamic_typing=True,
    )
    if name not in EMPTY_ARRAY_TYPES:
        node.declare_parameter(name, default, descriptor)
        return
    override = node._parameter_overrides.get(name)   # (no public getter)
    unset = override is not None and override.type_ == Parameter.Type.NOT_SET
    writable = ParameterDescriptor()
    writable.dynamic_typing = True
    node.declare_parameter(name, default, writable, ignore_override=unset)
    value = node.get_parameter(name).value
    if not len(value):
        # Typed empty: through set_parameters, the one way rclpy keeps a given type for [].
        node.set_parameters([Parameter(name, EMPTY_ARRAY_TYPES[name], [])])
    node.set_descriptor(name, descriptor)


def _declare_perturbers(node: Node) -> None:
    """
    Declare ``perturbers.<name>.<field>`` for every name of ``perturbers.names``.

    Their names depend on that list, so they are declared once it is read; the Scenario checks
    the names and every value.
    """
    from tumble_ros.core import ScenarioError
    from tumble_ros.core.model.scenario import (PERTURBER_DEFAULTS, PERTURBER_DOCS,
                                                perturber_parameter_names)
    try:
        names = perturber_parameter_names(
            {'perturbers.names': list(node.get_parameter('perturbers.names').value)})
    except ScenarioError:
        return       # (the Scenario refuses the list, naming it, when it is read)
    for name in names:
        field = name.rsplit('.', 1)[1]
        unit, description = PERTURBER_DOCS[field]
        descriptor = ParameterDescriptor(
            description=describe(description, unit),
            additional_constraints='validated by tumble_ros.core.Scenario (docs/physics.md)',
            read_only=True, dynamic_typing=True)
        node.declare_parameter(name, PERTURBER_DEFAULTS[field], descriptor)


def node_parameter(node: Node, name: str, default: Any, unit: str, description: str,
                   value_range: tuple[float, float] | None, read_only: bool) -> None:
    """Declare one of a node's own parameters, with its range enforced by rclpy."""
    descriptor = ParameterDescriptor(description=describe(description, unit), read_only=read_only)
    if isinstance(default, int) and not isinstance(default, bool):
        low, high = value_range if value_range is not None else (0, 2**31 - 1)
        descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high), step=1)]
    elif value_range is not None:
        descriptor.floating_point_range = [
            FloatingPointRange(from_value=float(value_range[0]), to_value=float(value_range[1]),
                               step=0.0)]
    node.declare_parameter(name, default, descriptor)


def declare_node_parameters(node: Node, table: dict[str, tuple]) -> dict[str, Any]:
    """
    Declare a node's own parameters and return their values.

    ``table`` is ``{name: (default, unit, description, range, read_only)}``; the values returned
    have the overrides and params files applied and their ranges enforced.
    """
    for name, spec in table.items():
        node_parameter(node, name, *spec)
    return read_parameters(node, table)


def _value(node: Node, name: str) -> Any:
    try:
        value = node.get_parameter(name).value
    except ParameterUninitializedException:
        return []
    return list(value) if isinstance(value, (list, tuple)) or hasattr(value, 'tolist') else value


def read_parameters(node: Node, names: Iterable[str]) -> dict[str, Any]:
    """Return the current values of the named parameters."""
    return {name: _value(node, name) for name in names}


def read_scenario_parameters(node: Node) -> dict[str, Any]:
    """
    Return the scenario parameters the node was given (see :func:`declare_scenario_parameters`).

    Only those given (a params file, ``-p``, a launch file's overrides): the Scenario takes its
    own defaults for the others, in years whatever ``time_unit`` says. Every parameter declared
    is read back, a default included, and a default was once read in the scenario's unit: a
    node given ``time_unit: h`` ran the default step 1e-4 yr as 1e-4 h.
    """
    from tumble_ros.core import PARAMETER_DOCS, ScenarioError
    from tumble_ros.core.model.scenario import perturber_parameter_names
    given = node._parameter_overrides                # (no public getter)
    values = read_parameters(node, [n for n in PARAMETER_DOCS if n in given])
    try:
        perturbers = perturber_parameter_names(values)
    except ScenarioError:
        return values   # (refused, naming perturbers.names, by Scenario.from_parameters)
    return {**values, **read_parameters(node, [n for n in perturbers if n in given])}


def section_applies(key: str, node_fqn: str) -> bool:
    """
    Tell whether a params-file node key applies to the node ``node_fqn``, by rcl's rules.

    :func:`tumble_ros.core.model.params_file.section_applies` (imported when called).
    """
    from tumble_ros.core.model.params_file import section_applies as applies
    return applies(key, node_fqn)


def refuse_unknown_parameters(nodes: Iterable[Node]) -> None:
    """
    Raise ValueError naming every override that no node of ``nodes`` declares.

    rclpy silently drops an override (``-p``, a params-file entry) for a parameter the node does
    not declare, so a misspelt key (``durration``) would run with the default. ``nodes`` are the
    nodes that share the command line (one for ``ros2 run``, three for ``bringup``, whose ``-p``
    reaches all of them): a name is unknown if none of them declares it. QoS overrides
    (``qos_overrides.*``) are rclpy's own and are let through.
    """
    nodes = list(nodes)
    known = {name for node in nodes for name in node._parameters}
    problems = []
    for node in nodes:
        # Node._parameter_overrides: every override rclpy found for this node (no public getter).
        for name in sorted(getattr(node, '_parameter_overrides', {})):
            if name in known or name.startswith('qos_overrides.'):
                continue
            near = difflib.get_close_matches(name, sorted(known), n=1)
            hint = f' (did you mean {near[0]!r}?)' if near else ''
            problems.append(f'{node.get_fully_qualified_name()}: unknown parameter {name!r}{hint}')
    if problems:
        raise NodeError('; '.join(dict.fromkeys(problems)))


def _params_files(args: list[str] | None) -> list[str]:
    """Return the files named by ``--params-file`` after ``--ros-args`` in a node's arguments."""
    args = list(args or [])
    files, in_ros_args = [], False
    for k, arg in enumerate(args):
        if arg == '--ros-args':
            in_ros_args = True
        elif arg == '--':
            in_ros_args = False
        elif in_ros_args and arg == '--params-file' and k + 1 < len(args):
            files.append(args[k + 1])
    return files


def params_file_problem(args: list[str] | None, node_fqn: str | None = None) -> str | None:
    """
    Say what is wrong with the ``--params-file`` files of ``args`` (None: nothing).

    rcl stops with a traceback on a missing, binary or malformed file (and blocks on a FIFO);
    this says which file and why, in one line: :func:`tumble_ros.core.check_params_file`, the
    check every command reading a params file makes. With ``node_fqn`` (``/sim``,
    ``/ast1/sim``), a file must also have a section that applies to that node: an empty file,
    one written for another node, or a ``sim:`` section given to a namespaced simulator would
    otherwise run silently with the defaults.
    """
    for name in _params_files(args):
        from tumble_ros.core import check_params_file, ScenarioError
        try:
            check_params_file(name, node_fqn)
        except ScenarioError as err:
            return str(err)
    return None

"""
One asteroid: the simulator, the comparator and the recorder, as three processes.

    ros2 launch tumble_ros tumble.launch.py [scenario:=fig10] [model:=paper]
        [output:=run.mcap] [namespace:=ast1] [use_sim_time:=false]

The launch arguments:

* ``scenario``: a shipped scenario name (``default``, ``fig3`` ... ``fig10``: the file
  ``share/tumble_ros/config/<name>.yaml``) or the path of a ROS 2 params file.
* ``model``: the comparator's ``model`` parameter (analytic model, default ``paper``).
* ``output``: the recorder's ``output`` parameter, the MCAP file to write; empty (default) = the
  recorder's own default, ``recordings/tumble_<UTC time>.mcap`` under the current directory.
* ``namespace``: pushed for the three nodes (default: none). ``/clock`` is remapped into it, so
  that two asteroids launched side by side do not share one clock (see two_asteroids.launch.py).
* ``use_sim_time``: ``use_sim_time`` of the comparator and the recorder (default ``false``). The
  simulator is the clock source and ignores it.

The simulator runs with ``min_consumers = 2`` (it waits for the comparator and the recorder, and
never outruns them) and the ``real_time_factor`` of the scenario file, else its default. When one
of the three nodes ends, the launch stops the others; when it ended with a non-zero exit code (it
refused its parameters or scenario, it crashed), ``ros2 launch`` exits 1, so a script can tell a
refused scenario from a good run.

The params file's node sections apply whatever the namespace: a section keyed ``/**/sim`` (as in
the shipped files), ``sim``, ``/sim`` or ``<namespace>/sim`` configures the simulator, and likewise
``comparator`` and ``recorder``; ``/**`` applies to all three. (rcl itself applies ``sim:`` and
``/sim:`` only to the node ``/sim``, not to ``/ast1/sim``.) Each node gets one params file of its
own, written at launch time and removed when the launch ends: its sections, then the values above.
"""
import os
import re
import tempfile

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, GroupAction, OpaqueFunction
from launch.actions import RegisterEventHandler, Shutdown
from launch.event_handlers import OnShutdown
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node, PushROSNamespace
import yaml

PACKAGE = 'tumble_ros'
NODES = ('sim', 'comparator', 'recorder')

ARGUMENTS = (
    ('scenario', 'default',
     'shipped scenario name (default, fig3 ... fig10) or path of a ROS 2 params file'),
    ('model', 'paper', "the comparator's analytic model"),
    ('output', '', 'MCAP file to write; empty = recordings/tumble_<UTC time>.mcap'),
    ('namespace', '', 'namespace of the three nodes (empty: none)'),
    ('use_sim_time', 'false', 'use_sim_time of the comparator and the recorder (true|false)'),
)


def scenario_path(scenario):
    """Return the params file of a shipped scenario name, or ``scenario`` itself if a path."""
    looks_like_path = os.sep in scenario or scenario.endswith(('.yaml', '.yml'))
    if looks_like_path or os.path.isfile(scenario):
        path = os.path.abspath(os.path.expanduser(scenario))
        if not os.path.isfile(path):
            raise RuntimeError(f'scenario: no such params file {scenario!r}')
        return path
    config = os.path.join(get_package_share_directory(PACKAGE), 'config')
    path = os.path.join(config, scenario + '.yaml')
    if not os.path.isfile(path):
        names = sorted((f[:-5] for f in os.listdir(config) if f.endswith('.yaml')),
                       key=lambda n: [int(t) if t.isdigit() else t for t in re.split(r'(\d+)', n)])
        raise RuntimeError(
            f'scenario: {scenario!r} is neither a params file nor a shipped scenario '
            f"({', '.join(names)})")
    return path


def _applies(key, node, namespace):
    """Return True if the params-file section ``key`` is meant for ``node`` (see the docstring)."""
    key = '/' + str(key).strip('/')
    if key == '/**':
        return True
    prefix, _, name = key.rpartition('/')
    return name == node and prefix in ('', '/**', namespace)


def node_sections(path, namespace):
    """Return ``{node: ros__parameters}`` of ``path`` for each of :data:`NODES` (merged)."""
    with open(path, encoding='utf-8') as f:
        document = yaml.safe_load(f)
    if not isinstance(document, dict):
        raise RuntimeError(f'scenario: {path} is not a ROS 2 params file')
    sections = {}
    for node in NODES:
        merged = {}
        # The wildcard first, so that a node's own section wins, as in rcl.
        keys = sorted(document, key=lambda k: str(k).strip('/') != '**')
        for key in keys:
            section = document[key]
            if _applies(key, node, namespace) and isinstance(section, dict):
                merged.update(section.get('ros__parameters') or {})
        sections[node] = merged
    return sections


def params_file(node, parameters):
    """Write ``parameters`` as a params file keyed ``/**`` (the file is for ``node`` only)."""
    with tempfile.NamedTemporaryFile('w', prefix=f'tumble_{node}_', suffix='.yaml',
                                     delete=False, encoding='utf-8') as f:
        yaml.safe_dump({'/**': {'ros__parameters': parameters}}, f, sort_keys=False)
        return f.name


def _bool(name, text):
    value = text.strip().lower()
    if value not in ('true', 'false'):
        raise RuntimeError(f'{name}: must be true or false, got {text!r}')
    return value == 'true'


class NodeFailed(RuntimeError):
    """A node of the launch ended with a non-zero exit code (e.g. it refused its scenario)."""


def _stop_all(event, context):
    """
    Stop the launch when one node ends; fail it when that node failed.

    The others cannot go on without it: the simulator would wait for its consumers forever. A
    node that ends with a non-zero exit code (a refused scenario or parameter, a crash) makes
    the launch fail: upstream launch exits 0 after a ``Shutdown`` and 1 only after an exception
    in the launch, so the exception is raised here (launch logs "Caught exception in launch:
    ...", shuts the other nodes down and exits 1). During a shutdown (Ctrl-C, another node's
    end) a node's exit is not a failure of the launch.
    """
    if context.is_shutdown:
        return None
    reason = f'{event.action.name} ended with exit code {event.returncode}'
    if event.returncode != 0:
        raise NodeFailed(f'{reason}: the launch fails (the reason is in its output above)')
    return Shutdown(reason=reason)


#: What the launch sets unless the scenario file says otherwise: the 3D scene on (the bare
#: node's default is off, for throughput).
DEFAULTS = {'sim': {'markers': True}}


def launch_setup(context):
    """Build the three nodes from the launch arguments (resolved at launch time)."""
    def arg(name):
        return LaunchConfiguration(name).perform(context)

    pushed = arg('namespace').strip()
    outer = context.launch_configurations.get('ros_namespace', '') or ''
    namespace = '/'.join(p for p in (outer.strip('/'), pushed.strip('/')) if p)
    namespace = '/' + namespace if namespace else ''
    sections = node_sections(scenario_path(arg('scenario')), namespace)
    use_sim_time = _bool('use_sim_time', arg('use_sim_time'))

    overrides = {
        'sim': {'min_consumers': 2},
        'comparator': {'model': arg('model'), 'use_sim_time': use_sim_time},
        'recorder': {'use_sim_time': use_sim_time},
    }
    if arg('output'):
        overrides['recorder']['output'] = arg('output')

    nodes, files = [], []
    for node in NODES:
        # One file per node: its sections of the scenario file, then the launch's values.
        files.append(params_file(node, {**DEFAULTS.get(node, {}), **sections[node],
                                        **overrides[node]}))
        nodes.append(Node(
            package=PACKAGE, executable=node, name=node, output='screen',
            parameters=[files[-1]],
            # The simulator publishes the absolute /clock: keep it in the namespace.
            remappings=[('/clock', 'clock')],
            on_exit=_stop_all,
        ))
    actions = [PushROSNamespace(pushed)] if pushed else []
    # The nodes read their params files at start-up: remove them when the launch ends.
    cleanup = RegisterEventHandler(OnShutdown(on_shutdown=lambda event, context: _remove(files)))
    return [GroupAction(actions + nodes, scoped=True), cleanup]


def _remove(paths):
    for path in paths:
        try:
            os.unlink(path)
        except OSError:
            pass


def generate_launch_description():
    """Launch sim, comparator and recorder for one scenario."""
    return LaunchDescription(
        [DeclareLaunchArgument(name, default_value=default, description=description)
         for name, default, description in ARGUMENTS]
        + [OpaqueFunction(function=launch_setup)])

"""
Two asteroids side by side: tumble.launch.py twice, in the namespaces ast1 and ast2.

    ros2 launch tumble_ros two_asteroids.launch.py [scenario1:=fig4] [scenario2:=fig10]
        [output_dir:=recordings] [model:=paper] [use_sim_time:=false]

Each asteroid has its own simulator, comparator and recorder (``/ast1/sim``, ``/ast2/sim``, ...),
its own topics (``/ast1/angular_velocity``, ...) and its own clock (``/ast1/clock``), and writes
its own recording, ``<output_dir>/<namespace>_<UTC time>.mcap``.
"""
from datetime import datetime, timezone
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, GroupAction, IncludeLaunchDescription
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution

ASTEROIDS = (('ast1', 'fig4'), ('ast2', 'fig10'))


def generate_launch_description():
    """Include tumble.launch.py once per asteroid, each in its own namespace."""
    tumble = os.path.join(get_package_share_directory('tumble_ros'), 'launch', 'tumble.launch.py')
    started = f'{datetime.now(timezone.utc):%Y%m%dT%H%M%S}'
    actions = [
        DeclareLaunchArgument('output_dir', default_value='recordings',
                              description='folder of the two recordings'),
        DeclareLaunchArgument('model', default_value='paper',
                              description="the comparators' analytic model"),
        DeclareLaunchArgument('use_sim_time', default_value='false',
                              description='use_sim_time of the comparators and recorders'),
    ]
    for k, (namespace, scenario) in enumerate(ASTEROIDS, start=1):
        actions.append(DeclareLaunchArgument(
            f'scenario{k}', default_value=scenario,
            description=f'scenario of {namespace} (shipped name or params file)'))
        # Scoped: the arguments given to one include do not leak into the other.
        actions.append(GroupAction([IncludeLaunchDescription(
            PythonLaunchDescriptionSource(tumble),
            launch_arguments={
                'namespace': namespace,
                'scenario': LaunchConfiguration(f'scenario{k}'),
                'model': LaunchConfiguration('model'),
                'use_sim_time': LaunchConfiguration('use_sim_time'),
                'output': PathJoinSubstitution(
                    [LaunchConfiguration('output_dir'), f'{namespace}_{started}.mcap']),
            }.items(),
        )], scoped=True))
    return LaunchDescription(actions)

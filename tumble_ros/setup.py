"""ament_python build of tumble_ros (colcon build, or pip for the pip-only path)."""
from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'tumble_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        # Register the package in the ament index, so `ros2 run` / ament_index find it.
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # Scenario files and the Foxglove layout, found under share/tumble_ros/config.
        (os.path.join('share', package_name, 'config'),
         glob(os.path.join('config', '*.yaml')) + glob(os.path.join('config', '*.json'))),
        # Shape files of mass models (docs/physics.md, "Mass models"), under
        # share/tumble_ros/config/shapes, where a params file's body.shape_file finds them.
        (os.path.join('share', package_name, 'config', 'shapes'),
         glob(os.path.join('config', 'shapes', '*.obj'))
         + glob(os.path.join('config', 'shapes', '*.tab'))),
        # Ephemeris tables of perturbers (docs/physics.md, "Ephemerides"), beside the scenario
        # files that name them (perturbers.<name>.ephemeris_file: ephemerides/...).
        (os.path.join('share', package_name, 'config', 'ephemerides'),
         glob(os.path.join('config', 'ephemerides', '*.txt'))),
        # Launch files, found by `ros2 launch tumble_ros <file>` under share/tumble_ros/launch.
        (os.path.join('share', package_name, 'launch'),
         glob(os.path.join('launch', '*.launch.py'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='tumble_ros maintainers',
    maintainer_email='tumble_ros@example.com',
    description='Tumbling-asteroid rotation under solar gravity-gradient torque (ROS 2 Jazzy).',
    license='Apache-2.0',
    entry_points={
        # One line per executable, installed to lib/tumble_ros/<name> (setup.cfg) for `ros2 run`.
        # All go through tumble_ros.__main__:entry (the name is the script's), which installs the
        # stop-signal handlers before importing the executable (tumble_ros.__main__.EXECUTABLES).
        'console_scripts': [
            f'{name} = tumble_ros.__main__:entry'
            for name in ('sim', 'comparator', 'recorder', 'bringup', 'analyze', 'ensemble',
                         'encounter', 'invert')
        ],
    },
)

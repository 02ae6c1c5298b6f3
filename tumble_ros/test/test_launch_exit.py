"""
tumble.launch.py's exit handler: a node that fails makes the launch fail.

``launch`` is not on PyPI (it comes with a ROS install), so its few names the launch file
imports are stood in for here; what is tested is the launch file's own decision: a node ending
with a non-zero code raises (upstream launch turns an exception into exit code 1, after
shutting the other nodes down), a clean end shuts the launch down, and nothing is decided while
the launch is already shutting down (Ctrl-C).
"""
import importlib.util
from pathlib import Path
import sys
import types

import pytest

LAUNCH_FILE = Path(__file__).resolve().parents[1] / 'launch' / 'tumble.launch.py'


class _Action:
    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


class Shutdown(_Action):
    pass


@pytest.fixture
def launch_file(monkeypatch):
    """Return the launch file as a module, with launch and launch_ros stood in for."""
    names = {
        'launch': ['LaunchDescription'],
        'launch.actions': ['DeclareLaunchArgument', 'GroupAction', 'OpaqueFunction',
                           'RegisterEventHandler', 'Shutdown'],
        'launch.event_handlers': ['OnShutdown'],
        'launch.substitutions': ['LaunchConfiguration'],
        'launch_ros': [], 'launch_ros.actions': ['Node', 'PushROSNamespace'],
    }
    for module, attrs in names.items():
        stand_in = types.ModuleType(module)
        for attr in attrs:
            setattr(stand_in, attr, Shutdown if attr == 'Shutdown' else _Action)
        monkeypatch.setitem(sys.modules, module, stand_in)
    spec = importlib.util.spec_from_file_location('tumble_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _exit(name, code):
    return types.SimpleNamespace(action=types.SimpleNamespace(name=name), returncode=code)


def test_a_node_that_fails_fails_the_launch(launch_file):
    context = types.SimpleNamespace(is_shutdown=False)
    with pytest.raises(launch_file.NodeFailed, match=r'^sim-1 ended with exit code 1: the launch '
                                                     r'fails'):
        launch_file._stop_all(_exit('sim-1', 1), context)


def test_a_node_that_ends_cleanly_shuts_the_launch_down(launch_file):
    action = launch_file._stop_all(_exit('sim-1', 0), types.SimpleNamespace(is_shutdown=False))
    assert isinstance(action, Shutdown)
    assert action.kwargs == {'reason': 'sim-1 ended with exit code 0'}


@pytest.mark.parametrize('code', [0, 1, -2, -15])
def test_exits_during_a_shutdown_decide_nothing(launch_file, code):
    assert launch_file._stop_all(_exit('recorder-3', code),
                                 types.SimpleNamespace(is_shutdown=True)) is None

"""
The numerical core, the MCAP IO and the offline analysis are usable without ROS.

They import no rclpy, no message packages.
"""
import ast
from pathlib import Path
import subprocess
import sys

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'tumble_ros'
#: The ROS-free packages (a researcher uses them without a ROS install) and files each must have.
ROS_FREE = {
    'core': {'model/scenario.py', 'propagation/propagator.py', 'kernels/stepping.py',
             'propagation/ensemble.py',
             'integrators/splitting.py'},
    'io': {'msgdefs.py', 'mcap_reader.py', 'mcap_writer.py', 'ensemble_store.py'},
    'ensembles': {'__init__.py'},
    'runs/ensembles': {'__init__.py', 'dask_engine.py', 'chunks.py', 'to_store.py'},
    'analysis': {'recording.py', 'summary.py', 'figures.py', 'cli.py', '__main__.py',
                 '__init__.py'},
}


def _is_ros(module: str) -> bool:
    top = module.split('.')[0]
    return (top in {'rclpy', 'rosidl_runtime_py', 'rosbag2_py'}
            or top.endswith(('_msgs', '_interfaces', '_srvs')))


def _imported_names(path: Path) -> list[str]:
    """Return the modules the file at ``path`` imports, at any depth (``from . import x``: x)."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names += [node.module] if node.module else [a.name for a in node.names]
    return names


def _ros_imports(path: Path) -> list[str]:
    return [n for n in _imported_names(path) if _is_ros(n)]


@pytest.mark.parametrize('package', sorted(ROS_FREE))
def test_sources_import_no_ros(package):
    folder = PACKAGE / package
    offenders = [f'{path.relative_to(folder)}: {name}'
                 for path in folder.rglob('*.py') for name in _ros_imports(path)]
    assert not offenders
    assert {str(p.relative_to(folder)) for p in folder.rglob('*.py')} >= ROS_FREE[package]


def test_the_topics_module_imports_no_ros():
    """Nodes, analysis and tests share the topic names: the module must load without ROS."""
    assert _ros_imports(PACKAGE / 'topics.py') == []


def test_the_ros_check_catches_ros_imports():
    assert all(map(_is_ros,
                   ['rclpy.node', 'geometry_msgs.msg', 'tumble_ros_interfaces.srv', 'std_srvs']))
    assert not any(map(_is_ros,
                       ['numpy', 'mcap_ros2.decoder', 'tumble_ros.core', 'rosbags.highlevel']))


def _assert_loads_none(imports: str, prefixes: tuple[str, ...]) -> None:
    """Run ``imports`` in a fresh interpreter; fail if a module named ``prefix...`` is loaded."""
    code = (f'import sys; {imports}; '
            f'bad = [m for m in sys.modules if m.startswith({prefixes!r})]; print(bad); '
            'sys.exit(1 if bad else 0)')
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr


def test_importing_core_loads_no_rclpy():
    _assert_loads_none('import tumble_ros.core; from tumble_ros.core import Scenario, simulate',
                       ('rclpy', 'rosidl'))


def test_importing_the_ensemble_runs_loads_no_rclpy():
    _assert_loads_none('import tumble_ros.runs.ensembles, tumble_ros.ensembles',
                       ('rclpy', 'rosidl'))


def test_core_holds_no_dask_code():
    """Dask is the run layer's (runs/ensembles): no core module imports it, at any depth."""
    offenders = [f'{path.relative_to(PACKAGE)}: {name}'
                 for path in (PACKAGE / 'core').rglob('*.py')
                 for name in _imported_names(path) if name.split('.')[0] in {'dask', 'distributed'}
                 or name.endswith('ensemble_dask')]
    assert not offenders


def test_importing_core_loads_no_dask_xarray_or_zarr():
    """Dask, xarray and Zarr are imported by the runs that use them, not by every core user."""
    _assert_loads_none('import tumble_ros.core, tumble_ros.io',
                       ('dask', 'distributed', 'xarray', 'zarr'))

"""
package.xml declares every module the package's Python files import.

``rosdep install --from-paths tumble_ros`` installs what package.xml declares, nothing else. This
test reads every import (``import x``, ``from x import y``, also inside functions and ``try``
blocks: an optional import is still a dependency) of the package's Python files, maps each
top-level module to the rosdep key that provides it (:data:`ROSDEP_KEYS`) and checks that the key
is declared with the right kind: modules of the installed package and of the launch files need an
exec dependency, modules of the tests an exec or test dependency, setup.py a build(tool) one.
A module that is not in the table fails the test: add it there, and to package.xml.
"""
import ast
from pathlib import Path
import sys

from catkin_pkg.package import parse_package
import pytest

PACKAGE_DIR = Path(__file__).resolve().parents[1]

#: Top-level module -> rosdep key. ROS packages are their own keys; ``*-pip`` keys and
#: ``mcap-ros2-support`` are rosdep keys whose installer is pip.
ROSDEP_KEYS = {
    # ROS packages
    'ament_flake8': 'ament_flake8',
    'ament_index_python': 'ament_index_python',
    'ament_pep257': 'ament_pep257',
    'builtin_interfaces': 'builtin_interfaces',
    'diagnostic_msgs': 'diagnostic_msgs',
    'geometry_msgs': 'geometry_msgs',
    'launch': 'launch',
    'launch_ros': 'launch_ros',
    'rcl_interfaces': 'rcl_interfaces',
    'rclpy': 'rclpy',
    'rosgraph_msgs': 'rosgraph_msgs',
    'service_msgs': 'service_msgs',
    'std_msgs': 'std_msgs',
    'std_srvs': 'std_srvs',
    'tf2_msgs': 'tf2_msgs',   # vendor/tf2_msgs where no tf2_msgs is installed
    'tumble_ros_interfaces': 'tumble_ros_interfaces',
    'visualization_msgs': 'visualization_msgs',
    # Python libraries (rosdep/python.yaml of ros/rosdistro)
    'catkin_pkg': 'python3-catkin-pkg-modules',
    'astropy': 'python3-astropy',
    'dask': 'python3-dask',
    'distributed': 'python3-distributed',
    'matplotlib': 'python3-matplotlib',
    'mcap_ros2': 'mcap-ros2-support',  # pip installer
    'numba': 'python3-numba',
    'numpy': 'python3-numpy',
    'PIL': 'python3-pil',
    'psutil': 'python3-psutil',
    'pytest': 'python3-pytest',
    'rosbags': 'python3-rosbags-pip',  # pip installer
    'scipy': 'python3-scipy',
    'xarray': 'python3-xarray',
    'zarr': 'python3-zarr',
    'setuptools': 'python3-setuptools',
    'yaml': 'python3-yaml',
}

#: Modules without a rosdep key of their own, with what installs them. Keep this short: a
#: module listed here is missing after ``rosdep install`` unless the named key brings it.
PIP_ONLY = {
    'mcap': 'pip "mcap", a dependency of mcap-ros2-support',
    'lz4': 'pip "lz4", a dependency of mcap',
    'zstandard': 'pip "zstandard", a dependency of mcap',
    'mpl_toolkits': 'part of matplotlib (python3-matplotlib): its 3D axes',
    'emcee': 'no rosdep key: the optional posterior of `invert --posterior` (pip extra posterior)',
}

#: Where the imports are read, and which dependency kinds satisfy them.
RUNTIME = ('exec',)
SOURCES = {
    'tumble_ros': RUNTIME,
    'launch': RUNTIME,
    'test': ('exec', 'test'),
    'setup.py': ('build', 'buildtool'),
}


def _python_files(name):
    path = PACKAGE_DIR / name
    return [path] if path.is_file() else sorted(path.rglob('*.py'))


def imported_modules(path):
    """Return the top-level modules that ``path`` imports (absolute imports only)."""
    tree = ast.parse(path.read_text(encoding='utf-8'), str(path))
    modules = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            modules.add(node.module.split('.')[0])
    return modules


def _local_modules():
    """
    Return the package itself and the helpers imported by name.

    The test helpers (test/ is on sys.path) and the benchmark modules (test_bench_quick puts
    benchmarks/ on it).
    """
    test_dir = PACKAGE_DIR / 'test'
    helpers = {p.stem for p in test_dir.glob('*.py')}
    helpers |= {p.stem for p in (PACKAGE_DIR.parent / 'benchmarks').glob('*.py')}
    helpers |= {p.name for p in test_dir.iterdir() if (p / '__init__.py').is_file()}
    return {'tumble_ros'} | helpers


def third_party_imports(source):
    """Return ``{module: [files]}`` of the non-stdlib, non-local imports of ``source``."""
    local = _local_modules()
    found = {}
    for path in _python_files(source):
        for module in imported_modules(path):
            if module in sys.stdlib_module_names or module in local or module == '__future__':
                continue
            found.setdefault(module, []).append(str(path.relative_to(PACKAGE_DIR)))
    return found


def declared():
    """Return ``{kind: {rosdep keys}}`` of package.xml (``<depend>`` counts as build and exec)."""
    package = parse_package(str(PACKAGE_DIR))
    package.evaluate_conditions({'ROS_VERSION': '2', 'ROS_PYTHON_VERSION': '3'})

    def names(dependencies):
        return {d.name for d in dependencies if d.evaluated_condition is not False}
    return {
        'exec': names(package.exec_depends),
        'test': names(package.test_depends),
        'build': names(package.build_depends),
        'buildtool': names(package.buildtool_depends),
    }


def test_package_xml_is_valid():
    package = parse_package(str(PACKAGE_DIR))
    package.validate()
    assert package.name == 'tumble_ros'


def test_the_scan_finds_the_imports():
    # Guard against a scan that silently reads nothing (moved folders, a broken walk).
    assert {'rclpy', 'numpy', 'scipy', 'yaml'} <= set(third_party_imports('tumble_ros'))
    assert {'launch', 'launch_ros'} <= set(third_party_imports('launch'))
    assert 'pytest' in third_party_imports('test')


@pytest.mark.parametrize('source', sorted(SOURCES))
def test_every_import_has_a_known_rosdep_key(source):
    unknown = {m: files for m, files in third_party_imports(source).items()
               if m not in ROSDEP_KEYS and m not in PIP_ONLY}
    assert not unknown, (
        'imported but not in test_package_xml.ROSDEP_KEYS (module -> rosdep key) nor PIP_ONLY: '
        + '; '.join(f'{m} ({", ".join(files)})' for m, files in sorted(unknown.items()))
        + '. Add the module with its rosdep key there and declare the key in package.xml.')


@pytest.mark.parametrize('source', sorted(SOURCES))
def test_every_import_is_declared(source):
    kinds = SOURCES[source]
    deps = declared()
    accepted = set().union(*(deps[kind] for kind in kinds))
    missing = {m: files for m, files in third_party_imports(source).items()
               if m in ROSDEP_KEYS and ROSDEP_KEYS[m] not in accepted}
    tags = ' or '.join(f'<{kind}_depend>' for kind in kinds)
    assert not missing, (
        f'package.xml lacks a {tags} for: '
        + '; '.join(f'{ROSDEP_KEYS[m]} (module {m}: {", ".join(files)})'
                    for m, files in sorted(missing.items())))


def test_pip_only_modules_are_brought_by_a_declared_key():
    # mcap, lz4 and zstandard come with mcap-ros2-support: that key must stay declared while
    # any of them is imported.
    imported = set().union(*(third_party_imports(s) for s in SOURCES))
    if imported & set(PIP_ONLY):
        assert 'mcap-ros2-support' in declared()['exec']

"""
``pip install .`` at the repository root: the ROS-free package, its dependencies, its files.

The root's ``pyproject.toml`` maps the import package ``tumble_ros/tumble_ros/`` and the shipped
files ``tumble_ros/config/`` into one Python package (docs/setup.md, "The Python package").
Nothing here downloads: the package is built by the venv's setuptools, as a wheel's builder
would (``egg_info`` for the metadata, ``build_py`` for the files a pure wheel holds), from a copy
of the working tree, and "installed" by copying those files into a fresh venv that reaches the
dependencies through a ``.pth`` line (the ``pip install`` from PyPI is measured by hand:
docs/setup.md). LICENSE and CITATION.cff are checked against the other places that state them.
"""
import configparser
import hashlib
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys
import sysconfig
import tomllib

import pytest
from test_no_ros import _is_ros
from test_package_xml import imported_modules
import yaml

REPO = Path(__file__).resolve().parents[2]
SOURCE = REPO / 'tumble_ros' / 'tumble_ros'
CONFIG = REPO / 'tumble_ros' / 'config'
#: ROS modules the package imports besides rclpy and the message packages (test_no_ros.py's):
#: a ROS install's, not pip's (a pip install runs the ROS-free part: test_no_ros.py).
ROS_ONLY = {'ament_index_python', 'launch', 'launch_ros'}
#: Top-level module -> the distribution that provides it, for the ROS-free packages' imports.
DISTRIBUTIONS = {
    'emcee': 'emcee', 'numpy': 'numpy', 'scipy': 'scipy', 'numba': 'numba', 'yaml': 'pyyaml',
    'matplotlib': 'matplotlib', 'mpl_toolkits': 'matplotlib', 'PIL': 'pillow', 'mcap': 'mcap',
    'mcap_ros2': 'mcap-ros2-support', 'zstandard': 'zstandard', 'lz4': 'lz4',
    'dask': 'dask', 'distributed': 'dask', 'xarray': 'xarray', 'zarr': 'zarr',
    'astropy': 'astropy',
}
#: The canonical text of the Apache License 2.0 (www.apache.org/licenses/LICENSE-2.0.txt).
APACHE_2_SHA256 = 'cfc7749b96f63bd31c3c42b5c471bf756814053e847c10f3eb003417bc523d30'


def _pyproject():
    return tomllib.loads((REPO / 'pyproject.toml').read_text())


def _requirement_name(requirement):
    """Return the distribution a requirement names, normalised (``dask[distributed]>=1``: dask)."""
    for stop in '[<>=!~; ':
        requirement = requirement.split(stop)[0]
    return requirement.strip().lower().replace('_', '-')


def _working_tree(destination):
    """Copy the repository's working tree (tracked and new files, not the ignored) there."""
    listed = subprocess.run(['git', 'ls-files', '-z', '-co', '--exclude-standard'], cwd=REPO,
                            capture_output=True, check=True).stdout.decode().split('\0')
    for name in filter(None, listed):
        source = REPO / name
        if source.is_file():
            (destination / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, destination / name)
    return destination


@pytest.fixture(scope='module')
def built(tmp_path_factory):
    """Build the root package as a wheel's builder does; return (files, metadata) folders."""
    base = tmp_path_factory.mktemp('packaging')
    tree = _working_tree(base / 'tree')
    lib, meta = base / 'lib', base / 'meta'
    meta.mkdir()
    done = subprocess.run(
        [sys.executable, '-W', 'ignore', '-c', 'from setuptools import setup; setup()', '-q',
         'egg_info', '--egg-base', str(meta), 'build_py', '--build-lib', str(lib)],
        cwd=tree, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    (info,) = meta.glob('*.egg-info')
    return lib, info


# --- what pyproject.toml says ----------------------------------------------------------------

def test_pyproject_lists_every_package_of_the_source_tree():
    """A sub-package added to the source tree and not to pyproject.toml would miss the wheel."""
    setuptools = _pyproject()['tool']['setuptools']
    found = {'.'.join(('tumble_ros',) + p.parent.relative_to(SOURCE).parts)
             for p in SOURCE.rglob('__init__.py')}
    shipped = {'.'.join(('tumble_ros', 'config') + p.relative_to(CONFIG).parts)
               for p in [CONFIG, *CONFIG.iterdir()] if p.is_dir()}
    assert set(setuptools['packages']) == found | shipped
    assert setuptools['package-dir'] == {'tumble_ros': 'tumble_ros/tumble_ros',
                                         'tumble_ros.config': 'tumble_ros/config'}


def test_every_import_but_ros_is_a_declared_dependency():
    project = _pyproject()['project']
    required = {_requirement_name(r) for r in project['dependencies']}
    extras = project['optional-dependencies']
    extra = {_requirement_name(r) for r in extras['ensembles']}
    posterior = {_requirement_name(r) for r in extras['posterior']}
    imported = {}
    for path in SOURCE.rglob('*.py'):
        for top in imported_modules(path) - set(sys.stdlib_module_names) - {'__future__'}:
            if not (_is_ros(top) or top in ROS_ONLY or top == 'tumble_ros'):
                imported.setdefault(top, set()).add(path.relative_to(SOURCE).as_posix())
    assert {'numpy', 'scipy', 'yaml', 'xarray'} <= set(imported)    # the scan reads them
    unknown = set(imported) - set(DISTRIBUTIONS)
    assert not unknown, f'map these imports to their distribution in DISTRIBUTIONS: {unknown}'
    missing = {m: sorted(files) for m, files in imported.items()
               if DISTRIBUTIONS[m] not in required | extra | posterior}
    assert not missing, f'imported, not declared in pyproject.toml: {missing}'
    # the heavy ensemble stack is the extra, the rest is always installed
    assert {'dask', 'xarray', 'zarr'} == extra and not extra & required
    assert posterior == {'emcee'} and not posterior & required      # invert --posterior
    assert {'numpy', 'scipy', 'numba', 'pyyaml', 'matplotlib', 'mcap'} <= required


def test_every_dependency_has_a_lower_bound_and_no_pin():
    project = _pyproject()['project']
    extras = project['optional-dependencies']
    for requirement in project['dependencies'] + extras['ensembles'] + extras['posterior']:
        assert '>=' in requirement and '==' not in requirement and '<' not in requirement, (
            requirement)


def test_no_root_file_makes_colcon_take_the_root_for_a_package():
    """No setup.py, setup.cfg, COLCON_IGNORE: colcon would stop at the root (below)."""
    assert not (REPO / 'setup.py').exists() and not (REPO / 'setup.cfg').exists()
    assert not (REPO / 'COLCON_IGNORE').exists() and not (REPO / 'package.xml').exists()


# --- colcon in a workspace ------------------------------------------------------------------

def _colcon_list(workspace):
    """Return ``{name: (path, type)}`` of what ``colcon list`` finds in ``workspace``."""
    colcon = Path(sys.executable).with_name('colcon')
    done = subprocess.run([str(colcon), '--log-base', os.devnull, 'list'], cwd=workspace,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = [line.split('\t') for line in done.stdout.splitlines()]
    return {name: (path, kind) for name, path, kind in rows}


def test_colcon_finds_both_packages_of_a_clone_in_a_workspace_src(tmp_path):
    """The root's pyproject.toml is no colcon package: colcon goes on to the two below it."""
    _working_tree(tmp_path / 'src' / 'tumble_ros')
    assert (tmp_path / 'src' / 'tumble_ros' / 'pyproject.toml').is_file()
    assert _colcon_list(tmp_path) == {
        'tumble_ros': ('src/tumble_ros/tumble_ros', '(ros.ament_python)'),
        'tumble_ros_interfaces': ('src/tumble_ros/tumble_ros_interfaces', '(ros.ament_cmake)'),
    }


def test_colcon_would_stop_at_a_root_setup_cfg_naming_a_package(tmp_path):
    """What the test above guards against: colcon takes the root and hides the two below."""
    root = tmp_path / 'src' / 'tumble_ros'
    root.mkdir(parents=True)
    shutil.copytree(REPO / 'tumble_ros_interfaces', root / 'tumble_ros_interfaces')
    (root / 'setup.py').write_text('from setuptools import setup\nsetup()\n')
    (root / 'setup.cfg').write_text('[metadata]\nname = tumble_ros\n')
    assert _colcon_list(tmp_path) == {'tumble_ros': ('src/tumble_ros', '(python)')}


# --- the built package ---------------------------------------------------------------------

def test_the_built_package_holds_every_module_and_the_shipped_files(built):
    lib, _ = built
    modules = {p.relative_to(SOURCE).as_posix() for p in SOURCE.rglob('*.py')}
    assert {p.relative_to(lib / 'tumble_ros').as_posix()
            for p in (lib / 'tumble_ros').rglob('*.py')} == modules
    shipped = {p.relative_to(CONFIG).as_posix() for p in CONFIG.rglob('*') if p.is_file()}
    assert {'default.yaml', 'fig9.yaml', 'apophis_2029.yaml', 'foxglove_layout.json',
            'shapes/apophis.obj', 'ephemerides/apophis_2029_moon.txt'} <= shipped
    assert {p.relative_to(lib / 'tumble_ros' / 'config').as_posix()
            for p in (lib / 'tumble_ros' / 'config').rglob('*') if p.is_file()} == shipped


def test_the_built_metadata_declares_the_dependencies_and_the_command(built):
    _, info = built
    requires = configparser.ConfigParser(allow_no_value=True, delimiters=('\0',))
    requires.read_string('[base]\n' + (info / 'requires.txt').read_text())
    assert {_requirement_name(r) for r in requires['base']} == {
        _requirement_name(r) for r in _pyproject()['project']['dependencies']}
    assert {_requirement_name(r) for r in requires['ensembles']} == {'dask', 'xarray', 'zarr'}
    entry_points = configparser.ConfigParser()
    entry_points.read_string((info / 'entry_points.txt').read_text())
    assert dict(entry_points['console_scripts']) == {
        'tumble_ros': 'tumble_ros.__main__:console'}
    head = (info / 'PKG-INFO').read_text().split('\n\n')[0]
    assert 'Version: 0.1.0' in head and 'License: Apache-2.0' in head


def _fresh_venv(path, lib):
    """Make a venv holding the built package; the shared venv's packages reached by a .pth."""
    subprocess.run([sys.executable, '-m', 'venv', '--without-pip', str(path)], check=True,
                   timeout=60)
    python = path / 'bin' / 'python'
    site = Path(subprocess.run([str(python), '-c', 'import sysconfig; '
                                'print(sysconfig.get_paths()["purelib"])'],
                               capture_output=True, text=True, check=True).stdout.strip())
    shutil.copytree(lib / 'tumble_ros', site / 'tumble_ros')
    (site / 'shared_dependencies.pth').write_text(sysconfig.get_paths()['purelib'] + '\n')
    # no PYTHONPATH: the colcon install's tumble_ros (the source tree) must not be found
    env = {k: v for k, v in os.environ.items() if k not in ('PYTHONPATH', 'AMENT_PREFIX_PATH')}
    return python, site, env


def test_the_installed_package_runs_the_core_from_its_own_files_without_ros(built, tmp_path):
    lib, _ = built
    python, site, env = _fresh_venv(tmp_path / 'venv', lib)
    probe = (
        'import json, sys\n'
        'import tumble_ros.core as core\n'
        'from tumble_ros.core import load_scenario, shipped_scenario, simulate\n'
        'path = shipped_scenario("fig5")\n'
        'result = simulate(load_scenario(path), t_eval=[0.0, 0.5, 1.0])\n'
        'ros = [m for m in sys.modules if m.startswith(("rclpy", "rosidl"))]\n'
        'print(json.dumps({"core": core.__file__, "scenario": str(path), "ros": ros,\n'
        '                  "omega": result.omega.tolist()}))\n')
    done = subprocess.run([str(python), '-c', probe], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout.splitlines()[-1])
    assert Path(seen['core']) == site / 'tumble_ros' / 'core' / '__init__.py'
    assert Path(seen['scenario']) == site / 'tumble_ros' / 'config' / 'fig5.yaml'
    assert seen['ros'] == []
    # the same numbers as the source tree's core on the source tree's file
    from tumble_ros.core import load_scenario, simulate
    expected = simulate(load_scenario(CONFIG / 'fig5.yaml'), t_eval=[0.0, 0.5, 1.0]).omega
    assert seen['omega'] == expected.tolist()


def test_the_installed_command_is_the_entry_point_and_finds_its_shapes(built, tmp_path):
    lib, _ = built
    python, site, env = _fresh_venv(tmp_path / 'venv', lib)
    probe = (
        'import sys\n'
        'from tumble_ros.__main__ import console\n'
        'from tumble_ros.core.model.shape_files import resolve_shape_path\n'
        'print(resolve_shape_path("config/shapes/apophis.obj"))\n'
        'sys.argv = ["tumble_ros", "--help"]\n'
        'sys.exit(console())\n')
    done = subprocess.run([str(python), '-c', probe], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    shape, usage = done.stdout.split('\n', 1)
    assert Path(shape) == site / 'tumble_ros' / 'config' / 'shapes' / 'apophis.obj'
    assert usage.startswith('usage: python -m tumble_ros') and '  analyze ' in usage


# --- LICENSE, CITATION.cff -----------------------------------------------------------------

def test_the_license_file_is_the_apache_2_text_the_metadata_name():
    text = (REPO / 'LICENSE').read_bytes()
    assert hashlib.sha256(text).hexdigest() == APACHE_2_SHA256
    from catkin_pkg.package import parse_package
    for package in ('tumble_ros', 'tumble_ros_interfaces'):
        assert [str(x) for x in parse_package(str(REPO / package)).licenses] == ['Apache-2.0']
    assert _pyproject()['project']['license'] == {'text': 'Apache-2.0'}


def _printed_title():
    """Return the paper's title as docs/paper.md prints it (the first italic of "Citation")."""
    citation = (REPO / 'docs' / 'paper.md').read_text().split('## Citation', 1)[1]
    return ' '.join(citation.split('*', 2)[1].split())


def test_citation_cff_cites_the_software_and_the_paper_as_printed():
    cff = yaml.safe_load((REPO / 'CITATION.cff').read_text())
    assert cff['cff-version'] == '1.2.0'
    assert {'message', 'title', 'authors'} <= set(cff)
    assert cff['authors'] == [{'name': 'the tumble_ros developers'}]
    assert cff['type'] == 'software' and cff['license'] == 'Apache-2.0'
    import tumble_ros
    assert cff['version'] == tumble_ros.__version__ == _pyproject()['project']['version']
    (paper,) = cff['references']
    assert paper['type'] == 'article' and paper['authors']
    assert ' '.join(paper['title'].split()) == _printed_title()
    assert _printed_title().startswith('A Comparison Between Some Approximate')


# --- the shipped files, the command's missing modules ----------------------------------------

def test_a_shipped_scenario_is_found_by_name_and_an_unknown_one_named_with_the_shipped():
    from tumble_ros.core import ScenarioError, shipped_scenario, shipped_scenarios
    assert shipped_scenario('fig10') == shipped_scenario('fig10.yaml') == CONFIG / 'fig10.yaml'
    assert set(shipped_scenarios()) == {p.stem for p in CONFIG.glob('*.yaml')}
    with pytest.raises(ScenarioError) as raised:
        shipped_scenario('fig11')
    message = str(raised.value)
    assert "scenario: no shipped scenario 'fig11'" in message and 'fig10' in message
    assert '\n' not in message


@pytest.mark.parametrize('module, says', [
    ('tumble_probe_msgs.msg', "no module named 'tumble_probe_msgs.msg': it comes with ROS 2 "
                              'Jazzy (make setup, or a ROS install: docs/setup.md)'),
    ('distributed', "no module named 'distributed': it comes with the ensembles' extra: "
                    "pip install 'tumble_ros[ensembles]'"),
])
def test_the_command_says_in_one_line_which_module_it_misses(monkeypatch, capsys, module, says):
    """As a pip install without ROS (or without the extra) runs a subcommand that needs it."""
    import tumble_ros.__main__ as entry
    monkeypatch.setitem(sys.modules, module.split('.')[0], None)    # import fails: not found
    monkeypatch.setitem(entry.EXECUTABLES, 'probe', f'{module}:main')
    assert entry.main(['probe', '--flag']) == 1
    out, err = capsys.readouterr()
    assert out == '' and err.startswith(f'tumble_ros probe: {says}') and err.count('\n') == 1


def test_the_usage_into_a_closed_pipe_ends_quietly(tmp_path):
    """``tumble_ros --help | head -3``: exit 141 as every executable, not a BrokenPipeError."""
    read, write = os.pipe()
    os.close(read)          # the reader has gone before anything is written
    with open(tmp_path / 'stderr.log', 'w') as err:
        run = subprocess.run([sys.executable, '-m', 'tumble_ros', '--help'], stdout=write,
                             stderr=err, stdin=subprocess.DEVNULL, timeout=120)
    os.close(write)
    stderr = (tmp_path / 'stderr.log').read_text()
    assert run.returncode == 141, stderr
    assert 'Traceback' not in stderr and 'BrokenPipeError' not in stderr, stderr


def test_a_module_of_the_package_itself_missing_is_a_bug_not_the_environment(monkeypatch):
    import tumble_ros.__main__ as entry
    monkeypatch.setitem(entry.EXECUTABLES, 'probe', 'tumble_ros.no_such_module:main')
    with pytest.raises(ModuleNotFoundError, match='tumble_ros.no_such_module'):
        entry.main(['probe'])

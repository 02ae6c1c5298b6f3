"""
The files shipped with the package: scenario files, shapes, viewer layouts (``config/``).

One source tree, two installs, so two places:

- the source tree's ``tumble_ros/config/``, beside the import package ``tumble_ros/tumble_ros/``
  (colcon's ``--symlink-install`` and ``pip install -e .`` run the source tree; colcon also
  installs the files to ``share/tumble_ros/config``, where the ament index finds them);
- ``config/`` inside the import package, where ``pip install .`` puts the same files (the
  repository root's ``pyproject.toml`` maps them there: a wheel has no ``share/`` the code
  could find).

:func:`config_dir` returns whichever holds them. Paths a params file names relative to the
package (``body.shape_file: config/shapes/apophis.obj``) are relative to its parent,
:func:`package_dir`.
"""
from __future__ import annotations

from pathlib import Path

from tumble_ros.core.model.limits import ScenarioError

__all__ = ['config_dir', 'package_dir', 'shipped_scenarios', 'shipped_scenario']

#: The import package ``tumble_ros`` (the folder of its ``__init__.py``).
IMPORT_PACKAGE = Path(__file__).resolve().parents[2]
#: Where the shipped files are, in the order looked at: installed by pip, the source tree.
CONFIG_PLACES = (IMPORT_PACKAGE / 'config', IMPORT_PACKAGE.parent / 'config')


def config_dir() -> Path:
    """
    Return the folder of the shipped files: the first of :data:`CONFIG_PLACES` that exists.

    Neither (a colcon install without ``--symlink-install`` copies the import package alone):
    the source tree's place, which holds nothing; the ament index's ``share/tumble_ros`` is
    looked at by the callers that need it (:func:`~.shape_files.resolve_shape_path`).
    """
    for folder in CONFIG_PLACES:
        if folder.is_dir():
            return folder
    return CONFIG_PLACES[-1]


def package_dir() -> Path:
    """Return the folder package-relative paths start from (``config/...``): config's parent."""
    return config_dir().parent


def shipped_scenarios() -> dict[str, Path]:
    """Return the shipped scenario files by name: ``{'default': .../config/default.yaml, ...}``."""
    return {path.stem: path for path in sorted(config_dir().glob('*.yaml'))}


def shipped_scenario(name: str) -> Path:
    """
    Return the shipped scenario file ``name`` names (``'fig10'`` or ``'fig10.yaml'``).

    Raises ScenarioError naming the shipped scenarios when there is none of that name.
    """
    shipped = shipped_scenarios()
    stem = name[:-len('.yaml')] if name.endswith('.yaml') else name
    if stem not in shipped:
        known = ', '.join(shipped) or 'none'
        raise ScenarioError(f'scenario: no shipped scenario {name!r}: no '
                            f'{config_dir() / stem}.yaml (shipped: {known})')
    return shipped[stem]

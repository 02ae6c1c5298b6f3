r"""
The one check of a ROS 2 params file, for every command that reads one.

``sim`` and ``bringup`` (their ``--params-file``), ``ensemble`` and ``encounter`` (their
scenario file) read a params file through :func:`check_params_file` (``load_scenario`` calls
it): the same refusals, in one line naming the file, whoever reads it::

    params file F.yaml: no such file
    params file F.yaml: is a FIFO (named pipe), not a params file (only regular files are read)
    params file F.yaml: 61,000,000 bytes, above the limit of 4,194,304 (MAX_PARAMS_FILE_BYTES)
    params file F.yaml: cannot read it as text: it holds UTF-16 text, not UTF-8 ...
    params file F.yaml: not valid YAML: ...
    params file F.yaml: no parameters (expected a ROS 2 params file: node names mapping to ...)
    params file F.yaml: sim.body.stokes: a list mixing integers and decimals ([2, 0, -0.1]) ...
    params file F.yaml: no section applies to node /ast1/sim (sections: sim; ...)

A FIFO, a device or a socket is refused before any read, a file larger than
:data:`MAX_PARAMS_FILE_BYTES` before it is read (a 60-MB ``omega0`` list held 1.2 GB while
YAML parsed it), UTF-16 or binary data by name: :mod:`.user_files`, the
check of every file a user names.
"""
from __future__ import annotations

from collections.abc import Mapping
import functools
import os
from pathlib import Path
import re
from typing import Any, TYPE_CHECKING

from tumble_ros.core.model.limits import MAX_PARAMS_FILE_BYTES, ScenarioError
from tumble_ros.core.model.user_files import decode_user_text, read_user_bytes

if TYPE_CHECKING:
    import yaml

__all__ = ['check_params_file', 'mixed_list', 'node_sections', 'params_loader',
           'parse_params_text', 'section_applies']


def _read_bytes(path: Path) -> bytes:
    """Return the bytes of the regular file ``path``, never blocking, at most the limit."""
    return read_user_bytes(path, f'params file {path}', MAX_PARAMS_FILE_BYTES,
                           'MAX_PARAMS_FILE_BYTES', 'params file')


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def params_loader() -> type[yaml.SafeLoader]:
    """
    Return a YAML SafeLoader that reads numbers as ROS 2 does.

    PyYAML follows YAML 1.1, where ``1.3271244e11`` (no sign in the exponent) or ``4e5`` is a
    string; ROS 2's own params-file parser (rcl_yaml_param_parser) reads them as doubles, and so
    does YAML 1.2. The scenario must mean the same in ``ros2 run --params-file`` and here.
    """
    import yaml

    class ParamsLoader(yaml.SafeLoader):
        pass

    ParamsLoader.add_implicit_resolver(
        'tag:yaml.org,2002:float',
        re.compile(r'^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$'),
        list('-+0123456789.'))
    return ParamsLoader


@functools.lru_cache(maxsize=1)
def _fast_params_loader() -> type[yaml.SafeLoader]:
    """
    Return :func:`params_loader`'s resolvers on libyaml's parser when PyYAML has it.

    The same documents (the constructor and resolvers are PyYAML's), 4x faster: a scenario
    with 10,000 impacts is 0.7 MB of text (3 s to parse in pure Python, 0.7 s here).
    """
    import yaml

    base = params_loader()
    if not getattr(yaml, '__with_libyaml__', False):
        return base

    class FastParamsLoader(yaml.CSafeLoader):
        pass

    FastParamsLoader.yaml_implicit_resolvers = {
        key: list(value) for key, value in base.yaml_implicit_resolvers.items()}
    return FastParamsLoader   # type: ignore[return-value]


def parse_params_text(text: str, name: object = None) -> Mapping[str, Any]:
    """
    Return the document of a params file's text (read as ROS 2 reads it: :func:`params_loader`).

    ScenarioError (starting ``params file NAME:`` when ``name`` is given) if the text is not
    YAML or has no ``ros__parameters`` section.
    """
    import yaml

    prefix = '' if name is None else f'params file {name}: '
    try:
        document: Mapping[str, Any] = yaml.load(  # noqa: S506 (a SafeLoader)
            text, Loader=_fast_params_loader())
    except yaml.YAMLError:
        try:   # the pure-Python parser's message (it quotes the offending line)
            yaml.load(text, Loader=params_loader())  # noqa: S506 (a SafeLoader)
        except yaml.YAMLError as err:
            raise ScenarioError(f'{prefix}not valid YAML: {_one_line(err)}') from None
        raise
    if not node_sections(document):
        raise ScenarioError(f'{prefix}no parameters (expected a ROS 2 parameters file: node '
                            "names mapping to 'ros__parameters:' sections)")
    return document


def node_sections(tree: Any, path: tuple[str, ...] = ()) -> list[str]:
    """List a params file's node keys (``sim``, ``/ns/sim``, ``/**``): where ros__parameters is."""
    if not isinstance(tree, Mapping):
        return []
    if 'ros__parameters' in tree:
        return ['/'.join(path)]
    return [key for k, v in tree.items() for key in node_sections(v, (*path, str(k)))]


def section_applies(key: str, node_fqn: str) -> bool:
    """
    Tell whether a params-file node key applies to the node ``node_fqn``, by rcl's rules.

    Keys look like ``sim``, ``/ast1/sim``, ``/**`` or ``/**/sim``, nodes like ``/ast1/sim``. A key
    without a leading slash is in the root namespace (``sim`` is ``/sim`` only), ``*`` matches
    one name, ``/**`` any namespaces.
    """
    key = key if key.startswith('/') else '/' + key
    pattern = ''.join('(/[^/]+)*' if part == '**' else '/[^/]+' if part == '*'
                      else '/' + re.escape(part) for part in key.split('/')[1:])
    return re.fullmatch(pattern, node_fqn) is not None


#: The kinds of a list's elements, as rcl's parser types them (bool before int: a bool is an int).
_ELEMENT_KINDS = ((bool, 'true/false'), (int, 'integers'), (float, 'decimals'), (str, 'strings'))


def _element_kind(value: Any) -> str:
    return next((name for kind, name in _ELEMENT_KINDS if isinstance(value, kind)), 'other')


def mixed_list(document: Any, path: tuple[str, ...] = ()) -> str | None:
    """
    Say which parameter of a params file's document is a list of mixed kinds (None: none).

    rcl reads a list as one type and refuses ``[2, 0, -0.1, 0.0]`` ("Sequence should be of same
    type"), where YAML (``load_scenario``) reads it as numbers: every reader refuses it alike.
    """
    if isinstance(document, Mapping):
        for key, value in document.items():
            inner = path if key == 'ros__parameters' else (*path, str(key))
            found = mixed_list(value, inner)
            if found:
                return found
    elif isinstance(document, list):
        kinds = list(dict.fromkeys(_element_kind(v) for v in document))
        if len(kinds) > 1:
            name = '.'.join(path)
            quoted = repr(document) if len(document) <= 8 else f'list of {len(document):,}'
            return (f'{name}: a list mixing {" and ".join(kinds)} ({quoted}): ROS 2 reads a '
                    "list as one type (rcl: 'Sequence should be of same type'); write every "
                    'number of a list of decimals with a decimal point (2.0, not 2)')
    return None


def check_params_file(path: str | os.PathLike[str],
                      node_fqn: str | None = None) -> Mapping[str, Any]:
    """
    Read and check the params file ``path``; return its YAML document.

    Raises ScenarioError, one line starting ``params file PATH:``, for a missing file, a path
    that is not a regular file (a FIFO, a directory, a device: refused before any read), a file
    above :data:`MAX_PARAMS_FILE_BYTES`, one that is not UTF-8 text, not YAML or without any
    ``ros__parameters`` section, or with a list rcl refuses (:func:`mixed_list`). With
    ``node_fqn`` (``/sim``, ``/ast1/sim``) a section must also apply to that node: an empty
    file, one written for another node, or a ``sim:`` section given
    to a namespaced simulator would otherwise run silently with the defaults.
    """
    path = Path(os.fspath(path))
    text = decode_user_text(_read_bytes(path), f'params file {path}')
    document = parse_params_text(text, path)
    mixed = mixed_list(document)
    if mixed:
        raise ScenarioError(f'params file {path}: {mixed}')
    if node_fqn:
        sections = node_sections(document)
        if not any(section_applies(s, node_fqn) for s in sections):
            raise ScenarioError(
                f'params file {path}: no section applies to node {node_fqn} '
                f"(sections: {', '.join(sections)}; "
                f"'/**/{node_fqn.rsplit('/', 1)[-1]}:' applies in any namespace)")
    return document

r"""
The one check of a ROS 2 params file, for every command that reads one.

``sim`` and ``bringup`` (their ``--params-file``), ``ensemble`` and ``encounter`` (their
scenario file) read a params file through :func:`check_params_file` (``load_scenario`` calls
it): the same refusals, in one line naming the file, whoever reads it::

    params file F.yaml: no such file
    params file F.yaml: is a FIFO (named pipe), not a params file (only regular files are read)
    params file F.yaml: 61,000,000 bytes, above the limit of 4,194,304 (MAX_PARAMS_FILE_BYTES)
    params file F.yaml: cannot read it as text (UnicodeDecodeError: ...)
    params file F.yaml: not valid YAML: ...
    params file F.yaml: no parameters (expected a ROS 2 params file: node names mapping to ...)
    params file F.yaml: no section applies to node /ast1/sim (sections: sim; ...)

A FIFO, a device or a socket is refused before any read (opening a FIFO for reading blocks
until a writer comes: the file is opened with O_NONBLOCK and checked on the open descriptor,
as ``tumble_ros.io.mcap_reader`` opens a recording), and a file larger than
:data:`MAX_PARAMS_FILE_BYTES` before it is read (a 60-MB ``omega0`` list held 1.2 GB while
YAML parsed it).
"""
from __future__ import annotations

from collections.abc import Mapping
import functools
import os
from pathlib import Path
import re
import stat
from typing import Any, TYPE_CHECKING

from tumble_ros.core.model.limits import MAX_PARAMS_FILE_BYTES, ScenarioError

if TYPE_CHECKING:
    import yaml

__all__ = ['check_params_file', 'file_kind', 'node_sections', 'params_loader',
           'parse_params_text', 'section_applies']

_FILE_KINDS = ((stat.S_ISDIR, 'is a directory'), (stat.S_ISFIFO, 'is a FIFO (named pipe)'),
               (stat.S_ISCHR, 'is a character device'), (stat.S_ISBLK, 'is a block device'),
               (stat.S_ISSOCK, 'is a socket'))


def file_kind(mode: int) -> str:
    """Return what a non-regular file is, from its ``st_mode``: 'is a FIFO (named pipe)', ...."""
    return next((text for test, text in _FILE_KINDS if test(mode)), 'is not a regular file')


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def _read_bytes(path: Path) -> bytes:
    """Return the bytes of the regular file ``path``, never blocking, at most the limit."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise ScenarioError(f'params file {path}: no such file') from None
    except OSError as err:
        try:
            mode = os.stat(path).st_mode          # a socket or a directory fails to open
        except OSError:
            mode = stat.S_IFREG
        if not stat.S_ISREG(mode):
            raise ScenarioError(f'params file {path}: {file_kind(mode)}, not a params file (only '
                                'regular files are read)') from None
        raise ScenarioError(f'params file {path}: cannot open it: '
                            f'{_one_line(err.strerror or err)}') from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ScenarioError(f'params file {path}: {file_kind(info.st_mode)}, not a params '
                                'file (only regular files are read)')
        if info.st_size > MAX_PARAMS_FILE_BYTES:
            raise ScenarioError(f'params file {path}: {info.st_size:,} bytes, above the limit '
                                f'of {MAX_PARAMS_FILE_BYTES:,} (MAX_PARAMS_FILE_BYTES, '
                                'docs/ros.md "Limits of the inputs")')
        os.set_blocking(fd, True)
        with os.fdopen(fd, 'rb', closefd=False) as stream:
            data = stream.read(MAX_PARAMS_FILE_BYTES + 1)
    except OSError as err:
        raise ScenarioError(f'params file {path}: cannot read it: '
                            f'{_one_line(err.strerror or err)}') from None
    finally:
        os.close(fd)
    if len(data) > MAX_PARAMS_FILE_BYTES:                  # grew since the fstat
        raise ScenarioError(f'params file {path}: above the limit of '
                            f'{MAX_PARAMS_FILE_BYTES:,} bytes (MAX_PARAMS_FILE_BYTES)')
    return data


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


def check_params_file(path: str | os.PathLike[str],
                      node_fqn: str | None = None) -> Mapping[str, Any]:
    """
    Read and check the params file ``path``; return its YAML document.

    Raises ScenarioError, one line starting ``params file PATH:``, for a missing file, a path
    that is not a regular file (a FIFO, a directory, a device: refused before any read), a file
    above :data:`MAX_PARAMS_FILE_BYTES`, one that is not UTF-8 text, not YAML or without any
    ``ros__parameters`` section. With ``node_fqn`` (``/sim``, ``/ast1/sim``) a section must also
    apply to that node: an empty file, one written for another node, or a ``sim:`` section given
    to a namespaced simulator would otherwise run silently with the defaults.
    """
    path = Path(os.fspath(path))
    data = _read_bytes(path)
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError as err:
        raise ScenarioError(f'params file {path}: cannot read it as text '
                            f'({err.__class__.__name__}: {err})') from None
    document = parse_params_text(text, path)
    if node_fqn:
        sections = node_sections(document)
        if not any(section_applies(s, node_fqn) for s in sections):
            raise ScenarioError(
                f'params file {path}: no section applies to node {node_fqn} '
                f"(sections: {', '.join(sections)}; "
                f"'/**/{node_fqn.rsplit('/', 1)[-1]}:' applies in any namespace)")
    return document

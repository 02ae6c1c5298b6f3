r"""
ROS 2 message definitions as rosbag2 stores them in MCAP schemas (no ROS runtime needed).

``message_definition('geometry_msgs/msg/Vector3Stamped')`` returns the schema text that rosbag2's
MCAP storage plugin (Jazzy) writes for that type, schema encoding ``ros2msg``: the type's own
``.msg`` file verbatim, then every message type it depends on, recursively, each exactly once,
each preceded by a line of 80 ``=`` and a line ``MSG: pkg/Type``. This mirrors
``rosbag2_cpp::LocalMessageDefinitionSource::get_full_text`` (rosbag2_cpp/src/rosbag2_cpp/
message_definitions/local_message_definition_source.cpp, Jazzy branch):

- ``result = text`` of the type; then for each dependency *of that type*, in sorted order
  (``std::set<std::string>`` of ``pkg/Type`` names), not seen before anywhere in this definition:
  ``result += "\n" + "=" * 80 + "\n" + "MSG: pkg/Type\n" + <the dependency, recursively>``.
  The files keep their own trailing newline, so a blank line usually precedes each separator.
- a field type without a package is resolved to the package of the file it appears in;
  ``Header`` alone means ``std_msgs/Header`` (the ROS 1 convention, which rosbags follows;
  rosbag2's regex and mcap-ros2-support's parser would look for ``<pkg>/Header``), unless the
  package defines its own ``Header.msg`` (which is what ROS 2's rosidl would use). ROS 2 .msg
  files in practice always write ``std_msgs/Header``, where all of them agree.
- service event types ``pkg/srv/Name_Event`` (topics ``<service>/_service_event``, recorded when
  service introspection is on) are stored the way Jazzy's rosbag2 stores them since
  ros2/rosbag2#2042: ``"=" * 80 + "\nSRV: pkg/srv/Name\n"`` + the ``.srv`` file verbatim,
  then the message dependencies of the ``.srv`` file as above (still encoding ``ros2msg``).
  That text does not describe the event message itself (ros2/rosbag2#2365): generic ros2msg
  decoders cannot decode it, and rosbags' AnyReader refuses to open a file holding such a
  schema (its low-level ``rosbags.rosbag2.Reader`` is fine); :mod:`tumble_ros.io.mcap_reader`
  rebuilds the event definition from it.
- action types are refused: Jazzy's rosbag2 stores them with an empty definition.

Definitions are found as ``share/<pkg>/<msg|srv>/<Type>.<msg|srv>`` under every prefix of
``AMENT_PREFIX_PATH`` and then under ``sys.prefix`` (after ``source install/setup.bash`` the venv
that holds the pip-installed ROS packages is no longer on AMENT_PREFIX_PATH). Lookups are cached
per search path; :func:`clear_cache` forgets them.

Nothing here imports rclpy.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
import functools
import json
import os
from pathlib import Path
import re
import sys

from tumble_ros.errors import IoError

__all__ = [
    'SEPARATOR',
    'Constant',
    'Field',
    'MessageDefinitionError',
    'MsgSpec',
    'clear_cache',
    'message_definition',
    'message_spec',
    'normalize_type_name',
    'parse_msg',
    'search_prefixes',
    'type_hash',
]

#: The line that precedes every dependency in a ``ros2msg`` schema (rosbag2, mcap spec).
SEPARATOR = '=' * 80

#: Builtin field types of ROS 2 .msg files (rosidl_adapter.parser.PRIMITIVE_TYPES, minus the
#: ROS 1 compatibility names 'time' and 'duration', which are mapped to builtin_interfaces).
PRIMITIVE_TYPES = frozenset({
    'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16',
    'int32', 'uint32', 'int64', 'uint64', 'string', 'wstring',
})
_ROS1_BUILTINS = {'time': 'builtin_interfaces/Time', 'duration': 'builtin_interfaces/Duration'}

_NAME = r'[A-Za-z][A-Za-z0-9_]*'
_TYPE_NAME_RE = re.compile(rf'^({_NAME})/(?:(msg|srv|action)/)?({_NAME})$')
_FIELD_TYPE_RE = re.compile(
    r'^(?P<base>[A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*)?)'
    r'(?:<=(?P<strbound>[0-9]+))?'
    r'(?:\[(?P<array>(?:<=)?[0-9]*)\])?$')
_FIELD_NAME_RE = re.compile(r'^[a-z][a-z0-9_]*$')
_CONSTANT_NAME_RE = re.compile(r'^[A-Z][A-Z0-9_]*$')


class MessageDefinitionError(IoError, LookupError):
    """A message definition could not be found or parsed (one-line message)."""


@dataclass(frozen=True)
class Field:
    """
    A field of a .msg file.

    ``type`` is a primitive name ('float64', 'string', ...) or a resolved 'pkg/Type';
    ``array`` is None (scalar), '' (unbounded sequence ``[]``), 'N' (fixed ``[N]``) or '<=N'
    (bounded sequence); ``string_bound`` is N for ``string<=N``; ``default`` the default value
    text.
    """

    type: str  # noqa: A003 (the .msg grammar's word, as in rosidl_adapter; a class attribute)
    name: str
    array: str | None = None
    string_bound: int | None = None
    default: str | None = None

    @property
    def is_primitive(self) -> bool:
        return self.type in PRIMITIVE_TYPES


@dataclass(frozen=True)
class Constant:
    """A constant of a .msg file: ``TYPE NAME=value`` (value kept as text)."""

    type: str  # noqa: A003 (the .msg grammar's word, as in rosidl_adapter; a class attribute)
    name: str
    value: str


@dataclass(frozen=True)
class MsgSpec:
    """The parsed content of one .msg text (or of both halves of a .srv text)."""

    package: str
    fields: tuple[Field, ...] = ()
    constants: tuple[Constant, ...] = ()
    dependencies: tuple[str, ...] = field(default=())
    """Non-primitive field types, resolved to 'pkg/Type', sorted, each once (rosbag2's order)."""


def normalize_type_name(type_name: str) -> str:
    """'pkg/Type' or 'pkg/msg/Type' -> 'pkg/msg/Type' (srv and action names are kept)."""
    package, namespace, name = _split_type_name(type_name)
    return f'{package}/{namespace}/{name}'


def _split_type_name(type_name: str) -> tuple[str, str, str]:
    if not isinstance(type_name, str):
        raise MessageDefinitionError(
            f'not a ROS type name: {type_name!r} (expected a string like pkg/msg/Type)')
    match = _TYPE_NAME_RE.match(type_name.strip())
    if match is None:
        raise MessageDefinitionError(
            f'not a ROS type name: {type_name!r} (expected pkg/msg/Type or pkg/Type)')
    package, namespace, name = match.groups()
    return package, namespace or 'msg', name


def search_prefixes() -> tuple[Path, ...]:
    """Return the install prefixes searched, in order: AMENT_PREFIX_PATH, then sys.prefix."""
    prefixes: list[Path] = []
    for entry in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        if entry.strip():
            prefixes.append(Path(entry.strip()))
    prefixes.append(Path(sys.prefix))
    unique: list[Path] = []
    for prefix in prefixes:
        if prefix not in unique:
            unique.append(prefix)
    return tuple(unique)


def clear_cache() -> None:
    """Forget every cached lookup (files are read again on the next call)."""
    _find_file.cache_clear()
    _read_text.cache_clear()
    _definition.cache_clear()


@functools.lru_cache(maxsize=1024)
def _find_file(prefixes: tuple[Path, ...], package: str, namespace: str,
               filename: str) -> Path | None:
    for prefix in prefixes:
        candidate = prefix / 'share' / package / namespace / filename
        if candidate.is_file():
            return candidate
    return None


@functools.lru_cache(maxsize=1024)
def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding='utf-8')
    except (OSError, UnicodeDecodeError) as err:
        raise MessageDefinitionError(f'cannot read {path}: {err}') from None


def _locate(prefixes: tuple[Path, ...], package: str, namespace: str, name: str,
            extension: str, needed_by: str | None) -> Path:
    path = _find_file(prefixes, package, namespace, name + extension)
    if path is None:
        what = f'{package}/{namespace}/{name}'
        reason = f', needed by {needed_by}' if needed_by else ''
        raise MessageDefinitionError(
            f'no message definition for {what!r}{reason}: share/{package}/{namespace}/'
            f'{name}{extension} is in none of the {len(prefixes)} prefixes of '
            f'AMENT_PREFIX_PATH and sys.prefix')
    return path


def _split_comment(line: str) -> str:
    """Drop a '#' comment, but not a '#' inside a quoted string value."""
    quote = None
    for index, char in enumerate(line):
        if quote:
            if char == quote:
                quote = None
        elif char in '"\'':
            quote = char
        elif char == '#':
            return line[:index]
    return line


def _resolve(base: str, package: str, has_own_type: Callable[[str], bool]) -> str:
    if base in _ROS1_BUILTINS:
        return _ROS1_BUILTINS[base]
    if '/' in base:
        return base
    if base == 'Header' and not has_own_type(base):
        return 'std_msgs/Header'
    return f'{package}/{base}'


def parse_msg(text: str, package: str, *, source: str = '<text>',
              has_own_type: Callable[[str], bool] | None = None) -> MsgSpec:
    """
    Parse .msg text of ``package``: fields, constants and the resolved dependencies.

    Understands builtin types, bounded strings (``string<=N``), arrays (``[]``, ``[N]``,
    ``[<=N]``), constants (``TYPE NAME=value``), default values (``TYPE name value``), comments
    and blank lines; the ``---`` separators of .srv/.action files are skipped. ``has_own_type``
    (name -> bool) tells whether ``package`` defines a message of that name (used for a bare
    ``Header``); by default it is assumed not to. Raises MessageDefinitionError naming ``source``
    and the line for anything else.
    """
    if has_own_type is None:
        def has_own_type(_name: str) -> bool:
            return False
    fields: list[Field] = []
    constants: list[Constant] = []
    dependencies: set[str] = set()
    for number, raw in enumerate(text.replace('\t', ' ').splitlines(), start=1):
        line = _split_comment(raw).strip()
        if not line or line == '---':
            continue
        type_text, _, rest = line.partition(' ')
        rest = rest.strip()
        where = f'{source} line {number}'
        if not rest:
            raise MessageDefinitionError(f'{where}: expected "TYPE NAME", got {raw.strip()!r}')
        match = _FIELD_TYPE_RE.match(type_text)
        if match is None:
            raise MessageDefinitionError(f'{where}: bad field type {type_text!r}')
        base = match['base']
        string_bound = int(match['strbound']) if match['strbound'] is not None else None
        array = match['array']
        if string_bound is not None and base not in ('string', 'wstring'):
            raise MessageDefinitionError(f'{where}: only strings can be bounded: {type_text!r}')
        if array not in (None, ''):
            size = array[2:] if array.startswith('<=') else array
            if not size or int(size) <= 0:
                raise MessageDefinitionError(f'{where}: bad array size in {type_text!r}')
        resolved = base if base in PRIMITIVE_TYPES else _resolve(base, package, has_own_type)
        if '=' in rest:
            name, _, value = rest.partition('=')
            name, value = name.strip(), value.strip()
            if array is not None or resolved not in PRIMITIVE_TYPES:
                raise MessageDefinitionError(
                    f'{where}: constants must have a primitive scalar type: {raw.strip()!r}')
            if not _CONSTANT_NAME_RE.match(name) or not value:
                raise MessageDefinitionError(f'{where}: bad constant {raw.strip()!r}')
            constants.append(Constant(resolved, name, value))
            continue
        name, _, default_text = rest.partition(' ')
        default = default_text.strip() or None
        if not _FIELD_NAME_RE.match(name):
            raise MessageDefinitionError(f'{where}: bad field name {name!r}')
        fields.append(Field(resolved, name, array, string_bound, default))
        if resolved not in PRIMITIVE_TYPES:
            dependencies.add(resolved)
    return MsgSpec(package, tuple(fields), tuple(constants), tuple(sorted(dependencies)))


def message_definition(type_name: str) -> str:
    """
    Return the ``ros2msg`` schema text rosbag2 (Jazzy) stores for ``type_name``.

    ``type_name`` is 'pkg/msg/Type' or 'pkg/Type' (or 'pkg/srv/Name_Event' for a service event).
    Raises MessageDefinitionError (a LookupError) with a one-line message if the type or one of
    its dependencies cannot be found or parsed.
    """
    package, namespace, name = _split_type_name(type_name)
    return _definition(search_prefixes(), package, namespace, name)


def message_spec(type_name: str) -> MsgSpec:
    """Parse the .msg file of one message type 'pkg/msg/Type' (its own fields only)."""
    package, namespace, name = _split_type_name(type_name)
    if namespace != 'msg':
        raise MessageDefinitionError(f'{type_name!r} is not a message type (pkg/msg/Type)')
    return _load_spec(search_prefixes(), package, 'msg', name, '.msg', None)[1]


def _has_own_type(prefixes: tuple[Path, ...], package: str) -> Callable[[str], bool]:
    def has(name: str) -> bool:
        return _find_file(prefixes, package, 'msg', name + '.msg') is not None
    return has


def _load_spec(prefixes: tuple[Path, ...], package: str, namespace: str, name: str,
               extension: str, needed_by: str | None) -> tuple[str, MsgSpec]:
    path = _locate(prefixes, package, namespace, name, extension, needed_by)
    text = _read_text(path)
    spec = parse_msg(text, package, source=str(path),
                     has_own_type=_has_own_type(prefixes, package))
    return text, spec


@functools.lru_cache(maxsize=256)
def _definition(prefixes: tuple[Path, ...], package: str, namespace: str, name: str) -> str:
    root = f'{package}/{namespace}/{name}'
    seen: set[str] = set()

    def append_dependencies(spec: MsgSpec, parent: str, depth: int) -> str:
        out = ''
        for dependency in spec.dependencies:
            if dependency in seen:
                continue
            seen.add(dependency)
            out += f'\n{SEPARATOR}\nMSG: {dependency}\n' + expand(dependency, parent, depth - 1)
        return out

    def expand(dependency: str, parent: str, depth: int) -> str:
        if depth <= 0:
            raise MessageDefinitionError(f'dependencies of {root!r} nest too deep (a cycle?)')
        dep_package, _, dep_name = dependency.partition('/')
        text, spec = _load_spec(prefixes, dep_package, 'msg', dep_name, '.msg', parent)
        return text + append_dependencies(spec, dependency, depth)

    if namespace == 'msg':
        text, spec = _load_spec(prefixes, package, 'msg', name, '.msg', None)
        return text + append_dependencies(spec, f'{package}/{name}', 64)
    if namespace == 'srv':
        if not name.endswith('_Event') or name == '_Event':
            raise MessageDefinitionError(
                f'{root!r} is not a message type: of a service only the introspection event '
                f'type {package}/srv/<Service>_Event is recorded')
        service = name[:-len('_Event')]
        text, spec = _load_spec(prefixes, package, 'srv', service, '.srv', None)
        seen.add(f'{package}/srv/{service}')
        return (f'{SEPARATOR}\nSRV: {package}/srv/{service}\n' + text
                + append_dependencies(spec, f'{package}/srv/{service}', 64))
    raise MessageDefinitionError(
        f'{root!r}: action types are not supported (rosbag2 Jazzy stores no definition for them)')


def type_hash(type_name: str) -> str:
    """
    Return the RIHS01 type hash rosidl generated for ``type_name`` ('' if it cannot be found).

    Read from ``share/<pkg>/<msg|srv>/<Name>.json`` (rosidl_generator_type_description);
    rosbag2 stores it as the channel metadata ``topic_type_hash``.
    """
    try:
        package, namespace, name = _split_type_name(type_name)
    except MessageDefinitionError:
        return ''
    prefixes = search_prefixes()
    full = f'{package}/{namespace}/{name}'
    stem = name
    if namespace == 'srv':
        for suffix in ('_Event', '_Request', '_Response'):
            if name.endswith(suffix):
                stem = name[:-len(suffix)]
                break
    path = _find_file(prefixes, package, namespace, stem + '.json')
    if path is None:
        return ''
    try:
        hashes = json.loads(_read_text(path)).get('type_hashes', [])
    except (MessageDefinitionError, ValueError, AttributeError):
        return ''
    for entry in hashes:
        if isinstance(entry, dict) and entry.get('type_name') == full:
            return str(entry.get('hash_string', ''))
    return ''

"""tumble_ros.io.msgdefs: message definitions in rosbag2's (Jazzy) ros2msg schema format."""
import os
from pathlib import Path
import re
import subprocess
import sys

import pytest

from tumble_ros.io import msgdefs
from tumble_ros.io.msgdefs import (message_definition, MessageDefinitionError, normalize_type_name,
                                   parse_msg, SEPARATOR, type_hash)

REPO = Path(__file__).resolve().parents[2]
INSTALL_PREFIX = REPO / 'install' / 'tumble_ros_interfaces'
VENV_SHARE = Path(sys.prefix) / 'share'


def msg_file(prefix_share: Path, package: str, name: str, namespace='msg', ext='.msg') -> str:
    return (prefix_share / package / namespace / f'{name}{ext}').read_text()


@pytest.fixture(autouse=True)
def fresh_cache():
    msgdefs.clear_cache()
    yield
    msgdefs.clear_cache()


# -- an independent oracle: rosbag2's algorithm, transcribed from local_message_definition_source
# (rosbag2_cpp, Jazzy): a regex finds field types, primitive types are skipped, a type without '/'
# gets the package of its file, dependencies are a std::set (sorted), each appended once, depth
# first, as "\n" + 80 '=' + "\nMSG: " + name + "\n" + text.

ROSBAG2_FIELD_TYPE = re.compile(r'(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+')
ROSBAG2_PRIMITIVES = {'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16',
                      'uint16', 'int32', 'uint32', 'int64', 'uint64', 'string'}


def rosbag2_full_text(root: str, find, std_header=False) -> str:
    # std_header: resolve a bare 'Header' to std_msgs/Header (our documented addition; rosbag2's
    # regex would look for <package>/Header).
    def deps(text, package):
        out = set()
        for found in ROSBAG2_FIELD_TYPE.findall(text):
            if found in ROSBAG2_PRIMITIVES:
                continue
            if std_header and found == 'Header':
                found = 'std_msgs/Header'
            out.add(found if '/' in found else f'{package}/{found}')
        return sorted(out)

    seen = set()

    def with_dependencies(text, package):
        result = text
        for dep in deps(text, package):
            if dep not in seen:
                seen.add(dep)
                dep_package, dep_name = dep.split('/')
                result += '\n' + '=' * 80 + '\nMSG: ' + dep + '\n'
                result += with_dependencies(find(dep_package, 'msg', dep_name), dep_package)
        return result

    package, namespace, name = root.split('/')
    if namespace == 'srv':   # Jazzy: service event -> the .srv file under an SRV: delimiter
        service = name[:-len('_Event')]
        seen.add(f'{package}/srv/{service}')
        return '=' * 80 + f'\nSRV: {package}/srv/{service}\n' + with_dependencies(
            find(package, 'srv', service), package)
    return with_dependencies(find(package, namespace, name), package)


def find_installed(package, namespace, name):
    ext = '.srv' if namespace == 'srv' else '.msg'
    for share in (INSTALL_PREFIX / 'share', VENV_SHARE):
        path = share / package / namespace / f'{name}{ext}'
        if path.is_file():
            return path.read_text()
    raise AssertionError(f'{package}/{namespace}/{name} not installed')


PROJECT_TYPES = [
    'geometry_msgs/msg/Vector3Stamped',
    'geometry_msgs/msg/QuaternionStamped',
    'rosgraph_msgs/msg/Clock',
    'tumble_ros_interfaces/msg/ImpactEvent',
    'tumble_ros_interfaces/msg/ScenarioDescription',
    'tumble_ros_interfaces/msg/SimStatus',
    'tumble_ros_interfaces/srv/ApplyImpact_Event',
    'std_srvs/srv/Trigger_Event',
]


@pytest.mark.parametrize('type_name', PROJECT_TYPES)
def test_definition_equals_rosbag2_algorithm(type_name):
    assert message_definition(type_name) == rosbag2_full_text(type_name, find_installed)


def test_vector3stamped_layout_exactly():
    share = VENV_SHARE
    expected = (
        msg_file(share, 'geometry_msgs', 'Vector3Stamped')
        + '\n' + '=' * 80 + '\nMSG: geometry_msgs/Vector3\n'
        + msg_file(share, 'geometry_msgs', 'Vector3')
        + '\n' + '=' * 80 + '\nMSG: std_msgs/Header\n'
        + msg_file(share, 'std_msgs', 'Header')
        + '\n' + '=' * 80 + '\nMSG: builtin_interfaces/Time\n'
        + msg_file(share, 'builtin_interfaces', 'Time'))
    text = message_definition('geometry_msgs/msg/Vector3Stamped')
    assert text == expected
    assert message_definition('geometry_msgs/Vector3Stamped') == text
    # Each dependency exactly once, each after a line of exactly 80 '='.
    lines = text.split('\n')
    separators = [i for i, line in enumerate(lines) if set(line) == {'='}]
    assert all(len(lines[i]) == 80 for i in separators)
    assert [lines[i + 1] for i in separators] == [
        'MSG: geometry_msgs/Vector3', 'MSG: std_msgs/Header', 'MSG: builtin_interfaces/Time']
    assert SEPARATOR == '=' * 80


def test_our_interface_is_found_under_install():
    text = message_definition('tumble_ros_interfaces/msg/ImpactEvent')
    own = (INSTALL_PREFIX / 'share' / 'tumble_ros_interfaces' / 'msg' / 'ImpactEvent.msg')
    assert own.is_file()
    assert text.startswith(own.read_text())
    headers = [line for line in text.split('\n') if line.startswith('MSG: ')]
    assert headers == ['MSG: geometry_msgs/Vector3', 'MSG: std_msgs/Header',
                       'MSG: builtin_interfaces/Time']


def test_venv_missing_from_ament_prefix_path(monkeypatch):
    # After `source install/setup.bash` the venv prefix is gone from AMENT_PREFIX_PATH: the
    # pip-installed geometry_msgs etc. must still be found through sys.prefix.
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(INSTALL_PREFIX))
    assert Path(sys.prefix) not in [Path(p) for p in os.environ['AMENT_PREFIX_PATH'].split(':')]
    text = message_definition('tumble_ros_interfaces/msg/ImpactEvent')
    assert 'MSG: geometry_msgs/Vector3' in text
    assert message_definition('geometry_msgs/msg/Vector3Stamped').count('MSG: ') == 3
    # ... and AMENT_PREFIX_PATH is what finds our own interfaces (they are not in the venv).
    monkeypatch.setenv('AMENT_PREFIX_PATH', '')
    with pytest.raises(MessageDefinitionError, match='tumble_ros_interfaces/msg/SimStatus'):
        message_definition('tumble_ros_interfaces/msg/SimStatus')


@pytest.mark.parametrize('type_name', [
    'geometry_msgs/msg/NoSuchType', 'no_such_pkg/msg/Thing', 'no_such_pkg/Thing'])
def test_unknown_type_is_named(type_name):
    with pytest.raises(MessageDefinitionError) as info:
        message_definition(type_name)
    message = str(info.value)
    assert '\n' not in message
    assert normalize_type_name(type_name) in message
    assert isinstance(info.value, LookupError)


@pytest.mark.parametrize('bad', ['', 'Vector3', 'a/b/c/d', 'geometry_msgs/msg/', '/x', 42])
def test_bad_type_names(bad):
    with pytest.raises(MessageDefinitionError) as info:
        message_definition(bad)
    assert '\n' not in str(info.value)


def test_services_and_actions():
    text = message_definition('tumble_ros_interfaces/srv/ApplyImpact_Event')
    srv = find_installed('tumble_ros_interfaces', 'srv', 'ApplyImpact')
    assert text.startswith('=' * 80 + '\nSRV: tumble_ros_interfaces/srv/ApplyImpact\n' + srv)
    with pytest.raises(MessageDefinitionError, match='_Event'):
        message_definition('tumble_ros_interfaces/srv/ApplyImpact')
    with pytest.raises(MessageDefinitionError, match='action'):
        message_definition('example_interfaces/action/Fibonacci_FeedbackMessage')


def test_parse_arrays_bounded_strings_constants_defaults():
    text = '\n'.join([
        '# a file-level comment, with = and # signs',
        'uint8 MODE_A=0   # a constant',
        'string NAME="has # inside"',
        'int32 LIMIT = -5',
        '',
        'float64[] values          # unbounded',
        'float64[3] fixed',
        'int32[<=4] bounded',
        'string<=10 short_name',
        'string<=8[<=2] short_names',
        'Other[] others            # same package',
        'other_pkg/Thing thing',
        'Header header             # std_msgs/Header',
        'bool flag true            # default value',
        'float64[] gains [1.0, 2.0]',
        '    # an indented comment line',
        '---',
        'uint32 response_field',
    ])
    spec = parse_msg(text, 'my_pkg')
    assert [(c.type, c.name, c.value) for c in spec.constants] == [
        ('uint8', 'MODE_A', '0'), ('string', 'NAME', '"has # inside"'), ('int32', 'LIMIT', '-5')]
    fields = {f.name: f for f in spec.fields}
    assert list(fields) == ['values', 'fixed', 'bounded', 'short_name', 'short_names', 'others',
                            'thing', 'header', 'flag', 'gains', 'response_field']
    assert fields['values'].array == '' and fields['fixed'].array == '3'
    assert fields['bounded'].array == '<=4' and fields['bounded'].type == 'int32'
    assert fields['short_name'].string_bound == 10 and fields['short_name'].array is None
    assert fields['short_names'].string_bound == 8 and fields['short_names'].array == '<=2'
    assert fields['others'].type == 'my_pkg/Other'
    assert fields['header'].type == 'std_msgs/Header'
    assert fields['flag'].default == 'true' and fields['gains'].default == '[1.0, 2.0]'
    assert spec.dependencies == ('my_pkg/Other', 'other_pkg/Thing', 'std_msgs/Header')


@pytest.mark.parametrize('line', [
    'float64', 'float64[0] zero', 'int32<=3 bounded_int', 'Bad-Type x', 'uint8 lower=1',
    'float64 BadName', 'Other[] X=1'])
def test_parse_errors_name_the_line(line):
    with pytest.raises(MessageDefinitionError) as info:
        parse_msg(f'# header\n{line}\n', 'pkg', source='pkg/msg/T.msg')
    assert 'pkg/msg/T.msg line 2' in str(info.value)
    assert '\n' not in str(info.value)


def test_synthetic_package_nesting_order_and_header(tmp_path, monkeypatch):
    share = tmp_path / 'share'
    (share / 'demo_msgs' / 'msg').mkdir(parents=True)
    files = {
        'Top.msg': 'Header header\nInner[] inners\nZeta z\nstring<=5 tag\n',
        'Inner.msg': 'Leaf[2] leaves\nuint8 K=1\n',
        'Leaf.msg': 'builtin_interfaces/Time stamp\nfloat64 v\n',
        'Zeta.msg': 'Leaf l\nInner i\n',
    }
    for name, text in files.items():
        (share / 'demo_msgs' / 'msg' / name).write_text(text)
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path))
    text = message_definition('demo_msgs/Top')
    headers = [line for line in text.split('\n') if line.startswith('MSG: ')]
    # Sorted dependencies of Top, each expanded depth-first where first met, each only once.
    assert headers == ['MSG: demo_msgs/Inner', 'MSG: demo_msgs/Leaf',
                       'MSG: builtin_interfaces/Time', 'MSG: demo_msgs/Zeta',
                       'MSG: std_msgs/Header']
    assert text == rosbag2_full_text(
        'demo_msgs/msg/Top',
        lambda p, n, t: (share / p / n / f'{t}.msg').read_text() if p == 'demo_msgs'
        else find_installed(p, n, t), std_header=True)
    # A package that defines its own Header keeps it (rosidl resolves bare names to the package).
    (share / 'demo_msgs' / 'msg' / 'Header.msg').write_text('uint8 own\n')
    msgdefs.clear_cache()
    assert 'MSG: demo_msgs/Header\nuint8 own' in message_definition('demo_msgs/msg/Top')
    # A missing dependency names the type that needs it.
    (share / 'demo_msgs' / 'msg' / 'Broken.msg').write_text('Missing m\n')
    with pytest.raises(MessageDefinitionError, match='demo_msgs/msg/Missing.*needed by '
                                                     'demo_msgs/Broken'):
        message_definition('demo_msgs/msg/Broken')


def test_lookups_are_cached(monkeypatch):
    reads = []
    original = Path.read_text

    def counting(self, *args, **kwargs):
        reads.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Path, 'read_text', counting)
    first = message_definition('geometry_msgs/msg/QuaternionStamped')
    count = len(reads)
    assert count >= 4
    assert message_definition('geometry_msgs/QuaternionStamped') == first
    assert len(reads) == count


def test_type_hash():
    value = type_hash('geometry_msgs/msg/Vector3Stamped')
    assert re.fullmatch(r'RIHS01_[0-9a-f]{64}', value)
    assert type_hash('tumble_ros_interfaces/srv/ApplyImpact_Event').startswith('RIHS01_')
    assert type_hash('tumble_ros_interfaces/srv/ApplyImpact_Event') != type_hash(
        'tumble_ros_interfaces/srv/ApplyImpact_Request')
    assert type_hash('no_such_pkg/msg/X') == '' and type_hash('garbage') == ''


def test_importing_and_using_io_loads_no_rclpy(tmp_path):
    golden = Path(__file__).parent / 'data' / 'golden.mcap'
    code = (
        'import sys\n'
        'import tumble_ros.io.mcap_reader, tumble_ros.io.mcap_writer, tumble_ros.io.msgdefs\n'
        'from tumble_ros.io import McapWriter, read_messages, summarize, message_definition\n'
        f'messages = list(read_messages({str(golden)!r}))\n'
        f'summarize({str(golden)!r})\n'
        'message_definition("tumble_ros_interfaces/msg/ImpactEvent")\n'
        f'with McapWriter({str(tmp_path / "x.mcap")!r}) as w:\n'
        '    w.write(w.add_channel("/c", "rosgraph_msgs/msg/Clock"), bytes(12), 1)\n'
        'bad = sorted(m for m in sys.modules\n'
        '             if m.split(".")[0] in ("rclpy", "rosidl_runtime_py")\n'
        '             or m.split(".")[0].endswith("_msgs"))\n'
        'print(len(messages), bad)\n'
        'sys.exit(1 if bad or not messages else 0)\n')
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr

"""
The workspace is set up as documented: interfaces built, package metadata, test isolation.

Run through `make test` (scripts/env.sh): the venv active and install/setup.bash sourced.
"""
import os
from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from catkin_pkg.package import parse_package
from geometry_msgs.msg import Vector3
import pytest
import rclpy
from rclpy.context import Context
from rclpy.serialization import deserialize_message, serialize_message
from tumble_ros_interfaces.msg import ImpactEvent, SimStatus
from tumble_ros_interfaces.srv import ApplyImpact

REPO = Path(__file__).resolve().parents[2]


# --- interfaces ---------------------------------------------------------------------------------

@pytest.mark.parametrize('msg_type, fields', [
    (ApplyImpact.Request, {
        'torque': 'geometry_msgs/Vector3',
        'frame': 'uint8',
        'duration': 'double',
        'start': 'double',
        'start_now': 'boolean',
    }),
    (ApplyImpact.Response, {
        'accepted': 'boolean',
        'message': 'string',
        'scheduled_start': 'double',
        'scheduled_end': 'double',
        'id': 'uint32',
    }),
    (ImpactEvent, {
        'header': 'std_msgs/Header',
        'id': 'uint32',
        'start': 'double',
        'end': 'double',
        'frame': 'uint8',
        'torque': 'geometry_msgs/Vector3',
        'delta_omega': 'geometry_msgs/Vector3',
    }),
    (SimStatus, {
        'header': 'std_msgs/Header',
        'state': 'uint8',
        't': 'double',
        'message': 'string',
    }),
], ids=['ApplyImpact.Request', 'ApplyImpact.Response', 'ImpactEvent', 'SimStatus'])
def test_interface_fields(msg_type, fields):
    # dict equality also checks the order of the fields (the wire format).
    assert list(msg_type.get_fields_and_field_types().items()) == list(fields.items())


def test_interface_constants():
    assert (ApplyImpact.Request.FRAME_BODY, ApplyImpact.Request.FRAME_ORBITAL) == (0, 1)
    assert (ImpactEvent.FRAME_BODY, ImpactEvent.FRAME_ORBITAL) == (0, 1)
    assert (SimStatus.RUNNING, SimStatus.PAUSED, SimStatus.FINISHED, SimStatus.DIVERGED) == (
        0, 1, 2, 3)
    # Defaults: a bare request is a body-frame pulse with an explicit start time.
    request = ApplyImpact.Request()
    assert request.frame == ApplyImpact.Request.FRAME_BODY
    assert request.start_now is False


def test_apply_impact_request_round_trips_through_cdr():
    request = ApplyImpact.Request(
        torque=Vector3(x=1.5e3, y=-2.25, z=1e-12),
        frame=ApplyImpact.Request.FRAME_ORBITAL,
        duration=3e-7,
        start=1234.5678901234,
        start_now=True,
    )
    data = serialize_message(request)
    assert isinstance(data, bytes) and len(data) > 0
    back = deserialize_message(data, ApplyImpact.Request)
    assert back == request
    assert back.start == 1234.5678901234  # float64 on the wire: bit-exact
    assert back is not request


def test_impact_event_round_trips_through_cdr():
    event = ImpactEvent(id=7, start=1.0, end=1.0 + 3e-7, frame=ImpactEvent.FRAME_ORBITAL,
                        torque=Vector3(x=1.0), delta_omega=Vector3(z=-0.5))
    event.header.stamp.sec = 2**31 - 1
    event.header.frame_id = 'body'
    assert deserialize_message(serialize_message(event), ImpactEvent) == event


def test_interface_definitions_are_installed():
    # tumble_ros.io looks message definitions up here to write MCAP schemas.
    share = Path(get_package_share_directory('tumble_ros_interfaces'))
    srv = (share / 'srv' / 'ApplyImpact.srv').read_text()
    assert 'uint8 FRAME_ORBITAL=1' in srv
    assert (share / 'msg' / 'ImpactEvent.msg').is_file()
    assert (share / 'msg' / 'SimStatus.msg').is_file()


# --- environment (scripts/env.sh) ---------------------------------------------------------------

def test_tumble_ros_is_imported_from_the_source_tree():
    import tumble_ros  # noqa: PLC0415 - the import location is what is tested
    # colcon --symlink-install: edits of the source are live, no rebuild needed.
    assert (Path(tumble_ros.__file__).resolve()
            == REPO / 'tumble_ros' / 'tumble_ros' / '__init__.py')
    assert tumble_ros.__version__ == '0.1.0'


def test_ament_index_finds_workspace_and_venv_packages():
    # install/setup.bash drops the venv from AMENT_PREFIX_PATH; scripts/env.sh appends it again.
    assert (Path(get_package_share_directory('tumble_ros')) / 'package.xml').is_file()
    assert (Path(get_package_share_directory('geometry_msgs')) / 'msg' / 'Vector3.msg').is_file()


# --- DDS isolation (conftest.py) ----------------------------------------------------------------

def test_dds_isolation_env_vars_are_set(domain_id_from_caller):
    assert os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] == 'LOCALHOST'
    domain_id = int(os.environ['ROS_DOMAIN_ID'])
    if domain_id_from_caller:
        assert 0 <= domain_id <= 232
    elif os.environ.get('PYTEST_XDIST_WORKER', '').startswith('gw'):
        # a worker of pytest -n N: the controller's pid picks a block of N domains, the
        # worker's number its own in it (two workers of one run never share a domain)
        count = int(os.environ['PYTEST_XDIST_WORKER_COUNT'])
        worker = int(os.environ['PYTEST_XDIST_WORKER'][2:])
        assert domain_id == 1 + ((os.getppid() % (101 // count)) * count + worker) % 101
        assert 1 <= domain_id <= 101
    else:
        assert domain_id == 1 + os.getpid() % 101
        assert 1 <= domain_id <= 101


def test_two_xdist_workers_of_one_run_get_two_domains(tmp_path):
    """The conftest run in two workers of one controller: different domains, not the caller's."""
    import subprocess
    import sys

    probe = ('import os, sys; sys.path.insert(0, sys.argv[1]); import conftest; '
             'print(os.environ["ROS_DOMAIN_ID"], conftest.DOMAIN_ID_FROM_CALLER)')
    here = str(Path(__file__).resolve().parent)
    seen = []
    for worker in ('gw0', 'gw1'):
        # as xdist starts them: the controller's ROS_DOMAIN_ID (and marker) inherited
        env = dict(os.environ, PYTEST_XDIST_WORKER=worker, PYTEST_XDIST_WORKER_COUNT='2')
        done = subprocess.run([sys.executable, '-c', probe, here], env=env, capture_output=True,
                              text=True, check=True)
        seen.append(done.stdout.split())
    if os.environ.get('TUMBLE_ROS_TEST_DOMAIN_ID') != os.environ['ROS_DOMAIN_ID']:
        # the caller chose the domain: every worker keeps it
        assert seen == [[os.environ['ROS_DOMAIN_ID'], 'True']] * 2, seen
        return
    assert seen[0][1] == seen[1][1] == 'False'
    assert seen[0][0] != seen[1][0], seen


def test_rclpy_context_uses_the_test_domain():
    context = Context()
    rclpy.init(context=context)
    try:
        assert context.get_domain_id() == int(os.environ['ROS_DOMAIN_ID'])
    finally:
        rclpy.shutdown(context=context)


# --- package metadata ---------------------------------------------------------------------------

def _package(name):
    return parse_package(str(REPO / name / 'package.xml'))


def test_tumble_ros_package_xml():
    package = _package('tumble_ros')
    assert package.name == 'tumble_ros'
    assert package.package_format == 3
    assert package.get_build_type() == 'ament_python'
    # The complete lists are checked against the imports by test_package_xml.py.
    assert {
        'rclpy', 'geometry_msgs', 'rosgraph_msgs', 'std_msgs', 'tumble_ros_interfaces',
        'python3-numpy', 'python3-scipy', 'python3-yaml'} <= {d.name for d in package.exec_depends}
    assert 'python3-pytest' in {d.name for d in package.test_depends}
    assert package.version == __import__('tumble_ros').__version__


def test_tumble_ros_interfaces_package_xml():
    package = _package('tumble_ros_interfaces')
    assert package.name == 'tumble_ros_interfaces'
    assert package.package_format == 3
    assert package.get_build_type() == 'ament_cmake'
    assert [g.name for g in package.member_of_groups] == ['rosidl_interface_packages']
    assert {d.name for d in package.buildtool_depends} == {
        'ament_cmake', 'rosidl_default_generators'}
    # <depend> = build + exec dependency
    for kind in (package.build_depends, package.exec_depends):
        assert {'builtin_interfaces', 'geometry_msgs', 'std_msgs'} <= {d.name for d in kind}
    assert 'rosidl_default_runtime' in {d.name for d in package.exec_depends}

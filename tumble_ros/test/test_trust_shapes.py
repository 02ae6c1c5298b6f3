"""
Shape files and mass models from a user: every bad one refused alike by the node and the API.

Issue 48's cases, each written into a params file and run through both readers of a scenario:
``load_scenario`` (``ensemble``, ``encounter``, the Python API) and the simulator node's own
``main`` (``ros2 run tumble_ros sim --ros-args --params-file F``: ``run_node``, in process). Both
refuse in one line with the same reason; before, a FIFO blocked for 30 s, /dev/zero grew to
2.88 GB, a UTF-16 file read as "0 vertices and 0 facets", 1e200 km and 1e-300 km were
tracebacks, a dented body silently had no lightcurve, two bodies were taken as one, a sliver
facet failed only at the lightcurve without file or line, and a list of integers and decimals
was refused by the node alone.
"""
import os
import signal
import time

import numpy as np
import pytest

from tumble_ros.core import load_scenario, ScenarioError
from tumble_ros.core.model.shape_files import box_mesh, write_obj
from tumble_ros.nodes.runner import run_node
from tumble_ros.nodes.shutdown import StopDuringSetUp, StopSignals
from tumble_ros.nodes.sim import SimNode

CUBE_V, CUBE_F = box_mesh((1.0, 1.0, 1.0))


def dented_cube(path):
    """Write a cube whose top face is four triangles meeting at a vertex pushed inwards."""
    lines = ['v -1 -1 -1', 'v 1 -1 -1', 'v 1 1 -1', 'v -1 1 -1',
             'v -1 -1 1', 'v 1 -1 1', 'v 1 1 1', 'v -1 1 1', 'v 0 0 0.5']
    faces = ['f 1 3 2', 'f 1 4 3', 'f 1 2 6', 'f 1 6 5', 'f 2 3 7', 'f 2 7 6',
             'f 3 4 8', 'f 3 8 7', 'f 4 1 5', 'f 4 5 8',
             'f 5 6 9', 'f 6 7 9', 'f 7 8 9', 'f 8 5 9']
    path.write_text('\n'.join(lines + faces) + '\n')


def two_cubes(path):
    """Two unit cubes 3 km apart in one file."""
    vertices = np.concatenate([CUBE_V, CUBE_V + [3.0, 0.0, 0.0]])
    write_obj(path, vertices, np.concatenate([CUBE_F, CUBE_F + len(CUBE_V)]))


def sliver(path):
    """Write a cube whose edge (0, 1) is split by a vertex m, closed by a zero-area facet."""
    vertices = np.concatenate([CUBE_V, [(CUBE_V[0] + CUBE_V[1]) / 2.0]])
    m = len(CUBE_V)
    keep, split = [], None
    for facet in CUBE_F.tolist():
        edges = list(zip(facet, facet[1:] + facet[:1]))
        if (0, 1) in edges and split is None:
            split = facet
            continue
        keep.append(facet)
    x = next(k for k in split if k not in (0, 1))
    # (0, m, x) and (m, 1, x) replace (0, 1, x); the sliver (0, 1, m) runs the reverse of both
    # new edges and the (0, 1) the neighbour across the old edge expects
    facets = keep + [[0, m, x], [m, 1, x], [0, 1, m]]
    write_obj(path, vertices, np.array(facets))


def far_away(path):
    write_obj(path, CUBE_V * 1e200, CUBE_F)


def utf16(path):
    path.write_text(''.join(f'v {x} {y} {z}\n' for x, y, z in CUBE_V)
                    + ''.join(f'f {i + 1} {j + 1} {k + 1}\n' for i, j, k in CUBE_F),
                    encoding='utf-16')


def binary(path):
    path.write_bytes(bytes(range(256)) * 16)


def million_facets(path):
    path.write_text('500002 1000000\n0 0 0\n')     # the counts announce it: refused at line 1


def fifo(path):
    os.mkfifo(path)


#: name -> (how to make the shape file at a path, what the refusal says)
SHAPES = {
    'non-convex with a lightcurve': (dented_cube, 'lightcurve.enabled: the polyhedron of '
                                                  'body.shape_file'),
    'two bodies': (two_cubes, 'the surface is 2 separate bodies'),
    'sliver facet': (sliver, 'has no area'),
    '1e200 km': (far_away, 'MAX_BODY_SIZE'),
    'UTF-16': (utf16, 'cannot read it as text: it holds UTF-16 text, not UTF-8'),
    'binary': (binary, 'cannot read it as text: it holds binary data'),
    '10^6 facets': (million_facets, 'more than 300,000 facets (MAX_FACETS'),
    'FIFO': (fifo, 'is a FIFO (named pipe), not a shape file (only regular files are read)'),
}
#: name -> (body.* parameters, what the refusal says): bodies given by numbers, no file
BODIES = {
    'semi-axes 1e-300 km': ({'body.model': 'ellipsoid', 'body.density': 2600.0,
                             'body.semi_axes': [1e-300, 1e-300, 1e-300]}, 'MIN_BODY_SIZE'),
    'Stokes degree 100,000': ({'body.model': 'moments', 'body.mass': 5e10,
                               'body.reference_radius': 0.2,
                               'body.principal_moments': [1.0e8, 1.5e8, 2.0e8],
                               'body.stokes': [100000.0, 0.0, 0.0, 0.0]},
                              'degree n at most 30 (MAX_DEGREE'),
    'integers among decimals': ({'body.model': 'moments', 'body.mass': 5e10,
                                 'body.reference_radius': 0.2,
                                 'body.principal_moments': [1.0e8, 1.5e8, 2.0e8],
                                 'body.stokes': [2, 0, -0.1, 0.0]},
                                'sim.body.stokes: a list mixing integers and decimals'),
}


def params_file(path, params):
    lines = ['sim:', '  ros__parameters:']
    for key, value in params.items():
        text = value if isinstance(value, str) else repr(value)
        lines.append(f'    {key}: {text}')
    path.write_text('\n'.join(lines) + '\n')
    return path


def both_refusals(path, capfd):
    """Return (load_scenario's message, the node's one line) for the params file ``path``."""
    with pytest.raises(ScenarioError) as api:
        load_scenario(path)
    capfd.readouterr()
    code = run_node(SimNode, ['sim', '--ros-args', '--params-file', str(path)], 'sim',
                    needs_params_section=True)
    lines = capfd.readouterr().err.strip().splitlines()
    assert code == 1, lines
    assert len(lines) == 1 and 'Traceback' not in lines[0], lines
    return str(api.value), lines[0]


def same_reason(api, node, path):
    """Tell whether the API's and the node's refusals say the same (each names the file)."""
    reason = api.removeprefix(f'{path}: ')
    return node.endswith(reason)


@pytest.mark.parametrize('name', SHAPES)
def test_a_bad_shape_file_is_refused_alike_by_the_node_and_load_scenario(tmp_path, capfd, name):
    make, expected = SHAPES[name]
    shape = tmp_path / 'shape.obj'
    make(shape)
    path = params_file(tmp_path / 'scenario.yaml', {
        'body.model': 'polyhedron', 'body.density': 2600.0, 'body.shape_file': str(shape)})
    api, node = both_refusals(path, capfd)
    assert expected in api and str(shape) in api, api
    assert same_reason(api, node, path), (api, node)


@pytest.mark.parametrize('name', BODIES)
def test_a_bad_body_is_refused_alike_by_the_node_and_load_scenario(tmp_path, capfd, name):
    params, expected = BODIES[name]
    path = params_file(tmp_path / 'scenario.yaml', params)
    api, node = both_refusals(path, capfd)
    assert expected in api, api
    assert same_reason(api, node, path), (api, node)


@pytest.mark.parametrize('kind', ['directory', 'device'])
def test_a_directory_or_a_device_named_as_shape_is_refused_by_its_kind(tmp_path, kind):
    """A directory and /dev/zero were "does not exist"; /dev/zero, read, grew to 2.88 GB."""
    shape = tmp_path if kind == 'directory' else '/dev/zero'
    path = params_file(tmp_path / 'scenario.yaml', {
        'body.model': 'polyhedron', 'body.density': 2600.0, 'body.shape_file': str(shape)})
    with pytest.raises(ScenarioError) as api:
        load_scenario(path)
    said = {'directory': 'is a directory', 'device': 'is a character device'}[kind]
    assert f'shape_file: {shape}: {said}, not a shape file' in str(api.value)


def test_a_non_convex_body_runs_without_a_lightcurve_when_asked(tmp_path):
    shape = tmp_path / 'dented.obj'
    dented_cube(shape)
    path = params_file(tmp_path / 'scenario.yaml', {
        'body.model': 'polyhedron', 'body.density': 2600.0, 'body.shape_file': str(shape),
        'lightcurve.enabled': 'false'})
    assert load_scenario(path).body.mass_model.convex is False


# -- a signal while the node is being built -----------------------------------------------------

def test_a_signal_during_a_long_set_up_stops_it_there():
    """
    The node's build (a large shape read and checked) is stopped by the signal, not finished.

    An 82,000-facet scenario ignored SIGINT for 120 s: the signal was only recorded, for the
    spin loop that comes after the build. Here the build sends itself SIGTERM, then works in
    pure Python (as the shape readers do) for up to 60 s.
    """
    done = []

    def make_node():
        os.kill(os.getpid(), signal.SIGTERM)
        until = time.monotonic() + 60.0
        while time.monotonic() < until:
            sum(range(1000))
        done.append(True)
        raise AssertionError('the build was not stopped')

    code = run_node(make_node, ['sim'], 'sim')
    assert code == 0 and not done


def test_stop_signals_raise_only_while_interrupting():
    with StopSignals('test') as stop:
        with pytest.raises(StopDuringSetUp):
            with stop.interrupting():
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(10**8):
                    pass
        assert stop.requested and stop.signum == signal.SIGTERM
        os.kill(os.getpid(), signal.SIGTERM)      # a second one, outside: recorded, no raise
        with pytest.raises(StopDuringSetUp):      # entering after a stop raises at once
            with stop.interrupting():
                pass


def test_the_sliver_of_these_tests_is_closed_with_one_facet_of_no_area(tmp_path):
    shape = tmp_path / 'sliver.obj'
    sliver(shape)
    from tumble_ros.core.model.mass_models import _check_closed
    from tumble_ros.core.model.mesh_checks import degenerate_facet
    from tumble_ros.core.model.shape_files import read_mesh
    mesh = read_mesh(shape)
    _check_closed(mesh.facets)
    assert degenerate_facet(mesh.vertices, mesh.facets) == len(mesh.facets) - 1


@pytest.mark.parametrize('offline', [True, False], ids=['offline', 'ros graph'])
def test_a_signal_while_bringup_builds_the_simulator_stops_it_there(tmp_path, monkeypatch,
                                                                    capfd, offline):
    """The bringup builds the simulator under the same rule: stopped there, nothing recorded."""
    import tumble_ros.nodes.bringup as bringup
    done = []

    class SlowSim(SimNode):
        def _set_up(self):
            os.kill(os.getpid(), signal.SIGTERM)
            until = time.monotonic() + 60.0
            while time.monotonic() < until:
                sum(range(1000))
            done.append(True)
            raise AssertionError('the build was not stopped')

    monkeypatch.setattr(bringup, 'SimNode', SlowSim)
    output = tmp_path / 'run.mcap'
    code = bringup.main(['--quiet', '--output', str(output), *(['--offline'] if offline else [])])
    err = capfd.readouterr().err
    assert code == 128 + signal.SIGTERM and not done, err
    assert err.strip() == 'bringup: stopped by SIGTERM while starting: nothing recorded'
    assert not output.exists()

"""The simulator node with several perturbers: their parameters declared, the first published."""
from geometry_msgs.msg import Vector3Stamped
import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.core import simulate, TimeBase
from tumble_ros.nodes.sim import SimNode
from tumble_ros_interfaces.msg import SimStatus

#: The Sun on an ellipse and the Moon on a hyperbola (GM [km^3/s^2], km, yr), no orbit_rate.
PERTURBERS = {
    'orbit_rate': 0.0, 'duration': 0.1, 'output_interval': 0.002, 'real_time_factor': 0.0,
    'perturbers.names': ['sun', 'moon'],
    'perturbers.sun.kind': 'kepler', 'perturbers.sun.gm': 1.3271244e11,
    'perturbers.sun.a': 1.5e8, 'perturbers.sun.e': 0.2,
    'perturbers.moon.kind': 'flyby', 'perturbers.moon.gm': 4902.800066,
    'perturbers.moon.perigee': 3000.0, 'perturbers.moon.v_inf': 1.0, 'perturbers.moon.t_p': 0.05,
    'perturbers.moon.j2': 2.0e-4, 'perturbers.moon.pole': [0.1, 0.0, 1.0],
}


def test_the_perturbers_parameters_are_declared_and_the_first_is_published(ros):
    perturber = ros.collect(Vector3Stamped, topics.PERTURBER)
    omega = ros.collect(Vector3Stamped, topics.ANGULAR_VELOCITY)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = ros.start(SimNode, **{k.replace('.', '__'): v for k, v in PERTURBERS.items()})
    assert sim.get_parameter('perturbers.moon.j2').value == 2.0e-4
    assert [p.name for p in sim.scenario.perturbers] == ['sun', 'moon']
    assert sim.scenario.perturbers[1].j2 == 2.0e-4
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)
    ros.spin_until(lambda: len(perturber) == 51 and len(omega) == 51, 5.0)
    assert len(perturber) == len(omega) == 51
    tb = TimeBase(1.0)
    t = np.array([tb.to_years(tb.stamp_ns(m.header.stamp.sec, m.header.stamp.nanosec))
                  for m in perturber])
    ref = simulate(sim.scenario, t_eval=t)
    np.testing.assert_array_equal([[m.vector.x, m.vector.y, m.vector.z] for m in omega],
                                  ref.omega)
    sun = sim.scenario.perturber_in_body(t, ref.quaternion)          # the first: the Sun
    np.testing.assert_allclose([[m.vector.x, m.vector.y, m.vector.z] for m in perturber], sun,
                               rtol=1e-12)


def test_a_body_given_by_its_mass_model_runs_in_the_node_with_the_derived_inertia(ros):
    """
    ``body.*`` without ``inertia``: the node's declared default inertia does not refuse it.

    (The node holds every declared parameter, the default inertia (1, 1, 1.5) too; a params
    file with a polyhedron and no inertia was refused as "disagreeing" with it.)
    """
    from tumble_ros.core import Scenario
    from tumble_ros.core.model.body import BodySpec

    body = {'body.model': 'polyhedron', 'body.density': 2600.0,
            'body.shape_file': 'config/shapes/apophis.obj', 'lightcurve.enabled': False,
            'orbit_rate': 1.0, 'duration': 0.01, 'output_interval': 0.002,
            'real_time_factor': 0.0}
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = ros.start(SimNode, **{k.replace('.', '__'): v for k, v in body.items()})
    expected = Scenario(body=BodySpec(model='polyhedron', density=2600.0,
                                      shape_file='config/shapes/apophis.obj'))
    np.testing.assert_allclose(sim.scenario.inertia, (0.64, 0.97, 1.0), rtol=1e-9)
    assert sim.scenario.inertia == expected.inertia
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)


# -- issue 48: one validation for both paths ------------------------------------------------------
def _nested(flat: dict) -> dict:
    """Return ``{'a.b': v}`` as ``{'a': {'b': v}}`` (a params file's layout)."""
    out: dict = {}
    for key, value in flat.items():
        *heads, last = key.split('.')
        place = out
        for head in heads:
            place = place.setdefault(head, {})
        place[last] = value
    return out


def _gap_table(path, nan: bool = False) -> str:
    """Write the Apophis flyby every hour as a plain table (hours); 24 h cut at the perigee."""
    from test_core_ephemeris import ORBIT

    hours = np.arange(0.0, 145.0)
    if not nan:
        hours = hours[np.abs(hours - 72.0) > 12.0]
    t = hours / 8766.0
    rows = [[h, *x] for h, x in zip(hours.tolist(), ORBIT.position(t).tolist())]
    lines = [', '.join(repr(v) for v in row) for row in rows]
    if nan:
        lines[5] = lines[5].replace(repr(rows[5][2]), 'NaN')
    path.write_text('t, x, y, z\n' + '\n'.join(lines) + '\n')
    return str(path)


_SUN = {'orbit_rate': 0.0, 'orbit.kind': 'kepler', 'orbit.gm': 1.3271244e11, 'orbit.radius': 1.0}
_TABLE = {'orbit_rate': 0.0, 'duration': 0.01, 'output_interval': 0.001, 'time_unit': 'yr',
          'perturbers.names': ['earth'], 'perturbers.earth.kind': 'ephemeris',
          'perturbers.earth.gm': 398600.4418, 'perturbers.earth.ephemeris_time_unit': 'h'}
#: Issue 48's inputs: (parameters, how the refusal starts); {table} is the ephemeris file.
BAD_INPUTS = {
    'gap': ({**_TABLE, 'perturbers.earth.ephemeris_file': '{gap}'},
            r'perturbers\.earth\.ephemeris_file: .*gap\.csv\.times: the knots t = 0\.00673055 '
            r'to 0\.00969655 yr, 26 h apart, allow interpolation errors up to'),
    'nan': ({**_TABLE, 'perturbers.earth.ephemeris_file': '{nan}'},
            r"perturbers\.earth\.ephemeris_file: .*nan\.csv:7: 'NaN' is not a finite number"),
    'body': ({'orbit_rate': 0.0, 'orbit.kind': 'flyby', 'orbit.gm': 398600.4418,
              'orbit.perigee': 38326.0, 'orbit.v_inf': 5.8, 'gravity.degree': 4,
              'body.model': 'ellipsoid', 'body.semi_axes': [45000.0, 30000.0, 20000.0],
              'body.density': 2000.0},
             r"body\.semi_axes: the body's bounding radius 45000 km must lie inside"),
    # the issue's own 100,000-km ellipsoid: beyond the body sizes accepted at all
    'huge': ({'orbit_rate': 0.0, 'orbit.kind': 'flyby', 'orbit.gm': 398600.4418,
              'orbit.perigee': 38326.0, 'orbit.v_inf': 5.8, 'gravity.degree': 4,
              'body.model': 'ellipsoid', 'body.semi_axes': [100000.0, 80000.0, 60000.0],
              'body.density': 2000.0},
             r'body\.semi_axes\[0\]: a body 2e\+05 km across is outside \[1e-05, 100000\] km'),
    'parabola': ({**_SUN, 'orbit.a': 1.496e8, 'orbit.e': 1.00001},
                 r'orbit\.e: the speed at the pericentre 1496 km, .* = 13320\.1 km/s'),
    'inside': ({**_SUN, 'orbit.a': 2992.0, 'orbit.e': 1.5},
               r'orbit\.e: the speed at the pericentre 1496 km, .* = 14892\.2 km/s'),
    'name': ({'orbit_rate': 0.0, 'perturbers.names': ['moon-1']},
             r"perturbers\.names: each name must be an identifier .*got 'moon-1'$"),
}


@pytest.mark.parametrize('case', sorted(BAD_INPUTS))
def test_every_bad_input_of_issue_48_is_refused_alike_by_load_scenario_and_the_node(
        ros, tmp_path, case):
    """The same file: load_scenario's refusal is the node's, prefixed with the file's path."""
    import re

    import yaml

    from tumble_ros.core import load_scenario, ScenarioError

    params, expected = BAD_INPUTS[case]
    tables = {'gap': _gap_table(tmp_path / 'gap.csv'),
              'nan': _gap_table(tmp_path / 'nan.csv', nan=True)}
    params = {k: v.format(**tables) if isinstance(v, str) else v for k, v in params.items()}
    path = tmp_path / f'{case}.yaml'
    path.write_text(yaml.safe_dump({'/**/sim': {'ros__parameters': _nested(params)}}))
    with pytest.raises(ScenarioError) as api:
        load_scenario(path)
    with pytest.raises(ScenarioError) as node:
        ros.add(SimNode(context=ros.context,
                        cli_args=['--ros-args', '--params-file', str(path)]))
    assert re.match(expected, str(node.value)), str(node.value)
    assert str(api.value) == f'{path}: {node.value}'

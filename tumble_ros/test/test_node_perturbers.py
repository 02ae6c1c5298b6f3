"""The simulator node with several perturbers: their parameters declared, the first published."""
from geometry_msgs.msg import Vector3Stamped
import numpy as np

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

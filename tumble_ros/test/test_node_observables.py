"""The simulator node given the spin state as the literature gives it (the ``spin.*`` block)."""
from pathlib import Path

from rclpy.parameter import Parameter

from tumble_ros.core import load_scenario
from tumble_ros.nodes.sim import SimNode

CONFIG = Path(__file__).resolve().parents[1] / 'config' / 'tumbling_from_observables.yaml'


def test_the_node_reads_the_spin_block_of_a_params_file_as_load_scenario_does(ros):
    """
    ``--params-file`` through rcl, the node's declared parameters, Scenario.from_parameters.

    The node holds every declared parameter (omega0 and euler0 at their defaults too): the same
    omega0, euler0 and inertia as load_scenario's.
    """
    expected = load_scenario(CONFIG)
    sim = ros.add(SimNode(context=ros.context,
                          cli_args=['--ros-args', '--params-file', str(CONFIG)],
                          parameter_overrides=[Parameter('start_paused', value=True)]))
    assert sim.get_parameter('spin.mode').value == 'SAM'
    assert list(sim.get_parameter('spin.inertia_ratios').value) == [0.61, 0.965]
    assert sim.scenario.omega0 == expected.omega0
    assert sim.scenario.euler0 == expected.euler0
    assert sim.scenario.inertia == expected.inertia == (0.61, 0.965, 1.0)
    assert (sim.scenario.duration, sim.scenario.output_interval) == (expected.duration,
                                                                     expected.output_interval)

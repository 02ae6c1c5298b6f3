"""The simulator node given the spin state as the literature gives it (the ``spin.*`` block)."""
from pathlib import Path

import pytest
from rclpy.parameter import Parameter

from tumble_ros.core import load_scenario, ScenarioError
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


def test_the_node_refuses_a_second_statement_of_the_spin_in_one_line(ros):
    """omega0 beside spin.mode: refused at start-up naming omega0, as load_scenario does."""
    block = {'spin__mode': 'SAM', 'spin__precession_period': 0.003,
             'spin__rotation_period': 0.03, 'spin__inertia_ratios': [0.61, 0.965],
             'spin__pole': [1.0, -1.0], 'orbit_rate': 0.0, 'start_paused': True}
    with pytest.raises(ScenarioError, match='^omega0: give the spin state once') as err:
        ros.start(SimNode, omega0=[1.0, 2.0, 3.0], **block)
    assert '\n' not in str(err.value)
    sim = ros.start(SimNode, **block)            # the block alone starts
    assert sim.scenario.inertia == (0.61, 0.965, 1.0)

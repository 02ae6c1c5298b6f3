"""The README documents every parameter, topic and service that the code declares."""
from pathlib import Path
import re

from tumble_ros.core import Scenario
from tumble_ros.nodes.comparator import PARAMETERS as COMPARATOR_PARAMETERS
from tumble_ros.nodes.recorder import PARAMETERS as RECORDER_PARAMETERS
from tumble_ros.topics import SIM_NODE_PARAMETERS as NODE_PARAMETERS

README = (Path(__file__).resolve().parents[2] / 'README.md').read_text()


def table_rows(text):
    return {m.group(1) for m in re.finditer(r'^\| `([^`]+)`', text, re.M)}


def test_every_parameter_has_a_readme_row():
    rows = table_rows(README)
    names = (list(Scenario().to_parameters()) + list(NODE_PARAMETERS) + list(COMPARATOR_PARAMETERS)
             + list(RECORDER_PARAMETERS))
    missing = [n for n in names if n not in rows]
    assert not missing


def test_every_topic_and_service_has_a_readme_row(ros):
    from tumble_ros.nodes.comparator import ComparatorNode
    from tumble_ros.nodes.sim import SimNode

    ros.start(SimNode, start_paused=True)
    ros.start(ComparatorNode)
    assert ros.spin_until(lambda: len(ros.probe.get_topic_names_and_types()) >= 12, 10.0), \
        ros.probe.get_topic_names_and_types()
    # The names as the README spells them, typed out on purpose (not from tumble_ros.topics):
    # they are the contract checked here. Its row `pause`, `resume`, `step` gives
    # table_rows only its first name; `/clock` keeps its slash there.
    rows = table_rows(README) | {'pause', 'resume', 'step'}
    topics = {n.lstrip('/') if n != '/clock' else n
              for n, _ in ros.probe.get_topic_names_and_types()}
    ignored = {'rosout', 'parameter_events', 'apply_impact/_service_event'}
    assert not sorted(topics - rows - ignored)
    services = {n.lstrip('/') for n, _ in ros.probe.get_service_names_and_types()
                if not n.startswith(('/sim/', '/probe/', '/comparator/'))}
    assert not sorted(services - rows)


def test_readme_starts_with_the_two_commands():
    first_block = README.split('```')[1]
    assert first_block.split() == ['bash', 'make', 'run', '#', 'runs', 'the', 'main', 'job',
                                   'make', 'test', '#', 'runs', 'the', 'tests']


def test_scenario_description_documents_parameters_yaml_as_the_scenario_as_started():
    """
    The .msg says what the simulator sends (test_trust_nodes: the same text in every segment).

    The field's comment (its line and the comment lines under it) must say the scenario as
    started, as README does, not the impacts scheduled so far (what the simulator used to send).
    """
    msg = (Path(__file__).resolve().parents[2] / 'tumble_ros_interfaces' / 'msg'
           / 'ScenarioDescription.msg').read_text()
    lines = msg.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith('string parameters_yaml'))
    comment = [lines[start].split('#', 1)[1]]
    for line in lines[start + 1:]:   # the continuation lines: indented comments
        if not (line.startswith(' ') and line.lstrip().startswith('#')):
            break
        comment.append(line.lstrip()[1:])
    text = ' '.join(' '.join(comment).split())
    assert 'the scenario as started' in text
    assert 'scheduled so far' not in text
    assert 'the scenario as started' in README

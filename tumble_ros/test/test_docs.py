"""The docs: every parameter, topic and service has a row in docs/ros.md; no outside paths."""
import os
from pathlib import Path
import re
import subprocess

from tumble_ros.core import Scenario
from tumble_ros.nodes.comparator import PARAMETERS as COMPARATOR_PARAMETERS
from tumble_ros.nodes.recorder import PARAMETERS as RECORDER_PARAMETERS
from tumble_ros.topics import SIM_NODE_PARAMETERS as NODE_PARAMETERS

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / 'README.md').read_text()
#: The ROS reference: the tables of parameters, topics and services.
REFERENCE = (ROOT / 'docs' / 'ros.md').read_text()
# A path into a directory named "shared" (relative, or beside or above the repository): a clone
# does not have it. Spelt in pieces so that this file does not match itself.
SHARED_PATH = re.compile(rb'(?<![\w.-])' + b'shared' + rb'/')
NOT_TRACKED = {'.git', '.venv', 'build', 'install', 'log', 'recordings', '__pycache__'}


def table_rows(text):
    return {m.group(1) for m in re.finditer(r'^\| `([^`]+)`', text, re.M)}


def test_every_parameter_has_a_reference_row():
    rows = table_rows(REFERENCE)
    names = (list(Scenario().to_parameters()) + list(NODE_PARAMETERS) + list(COMPARATOR_PARAMETERS)
             + list(RECORDER_PARAMETERS))
    missing = [n for n in names if n not in rows]
    assert not missing


def test_every_topic_and_service_has_a_reference_row(ros):
    from tumble_ros.nodes.comparator import ComparatorNode
    from tumble_ros.nodes.sim import SimNode

    ros.start(SimNode, start_paused=True)
    ros.start(ComparatorNode)
    assert ros.spin_until(lambda: len(ros.probe.get_topic_names_and_types()) >= 12, 10.0), \
        ros.probe.get_topic_names_and_types()
    # The names as docs/ros.md spells them, typed out on purpose (not from tumble_ros.topics):
    # they are the contract checked here. Its row `pause`, `resume`, `step` gives
    # table_rows only its first name; the global names (`/clock`, `/tf`, `/tf_static`) keep
    # their slash there.
    rows = table_rows(REFERENCE) | {'pause', 'resume', 'step'}
    topics = {n.lstrip('/') if n not in ('/clock', '/tf', '/tf_static') else n
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


def tracked_files():
    """Return the tracked files, relative to ROOT: git ls-files, or without git the tree."""
    try:
        out = subprocess.run(['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True, check=True)
        return [Path(name) for name in out.stdout.decode().split('\0') if name]
    except (OSError, subprocess.CalledProcessError):
        found = []
        for directory, dirs, files in os.walk(ROOT):
            dirs[:] = [d for d in dirs if d not in NOT_TRACKED]
            found += [Path(directory, f).relative_to(ROOT) for f in files]
        return found


def test_no_tracked_file_refers_to_a_shared_directory():
    """
    Nothing in the repository points into a "shared" directory, which a clone does not have.

    The paper is cited, and its corrections are listed, in docs/paper.md.
    """
    files = tracked_files()
    assert Path('README.md') in files and Path('docs/paper.md') in files
    hits = []
    for name in files:
        path = ROOT / name
        if not path.is_file():
            continue
        for number, line in enumerate(path.read_bytes().splitlines(), 1):
            if SHARED_PATH.search(line):
                hits.append(f'{name}:{number}: {line.decode(errors="replace").strip()[:120]}')
    assert not hits, 'references to a "shared" directory:\n' + '\n'.join(hits)


def test_scenario_description_documents_parameters_yaml_as_the_scenario_as_started():
    """
    The .msg says what the simulator sends (test_trust_nodes: the same text in every segment).

    The field's comment (its line and the comment lines under it) must say the scenario as
    started, as docs/ros.md does, not the impacts scheduled so far (what the simulator used to
    send).
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
    assert 'the scenario as started' in REFERENCE

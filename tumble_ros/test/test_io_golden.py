"""
The committed golden MCAP file, checked against scripts/make_golden_mcap.py and golden.json.

It is in sync with scripts/make_golden_mcap.py (byte-identical when regenerated) and read back
by tumble_ros.io exactly as golden.json (written by the script from its own inputs) says.
"""
import json
from pathlib import Path
import subprocess
import sys

from mcap.reader import make_reader
import pytest

from tumble_ros.io import offered_qos_yaml, read_messages, summarize

DATA = Path(__file__).parent / 'data'
SCRIPT = Path(__file__).resolve().parents[2] / 'scripts' / 'make_golden_mcap.py'


@pytest.fixture(scope='module')
def expected():
    return json.loads((DATA / 'golden.json').read_text())


def plain(value):
    if hasattr(value, '__slots__') and hasattr(value, '_type'):
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if isinstance(value, list):
        return [plain(v) for v in value]
    return value


def test_script_reproduces_the_committed_files(tmp_path):
    done = subprocess.run([sys.executable, str(SCRIPT), '--out-dir', str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    for name in ('golden.mcap', 'golden.json'):
        assert (tmp_path / name).read_bytes() == (DATA / name).read_bytes(), (
            f'{name} is out of date: run scripts/env.sh python scripts/make_golden_mcap.py')
    assert (DATA / 'golden.mcap').stat().st_size < 40_000


def test_reader_output_equals_golden_json(expected):
    messages = list(read_messages(DATA / 'golden.mcap'))
    assert len(messages) == expected['message_count']
    topics = expected['topics']
    by_topic = {}
    for message in messages:
        by_topic.setdefault(message.topic, []).append(message)
    assert set(by_topic) == set(topics)
    for topic, spec in topics.items():
        got = by_topic[topic]
        assert len(got) == spec['count'], topic
        assert {m.type_name for m in got} == {spec['type']}
        for which, message in (('first', got[0]), ('last', got[-1])):
            want = spec[which]
            assert message.log_time_ns == want['log_time_ns'], (topic, which)
            assert message.publish_time_ns == want['publish_time_ns'], (topic, which)
            assert plain(message.message) == want['message'], (topic, which)
    # Spot checks in the terms of the brief. Names typed out: the committed file's own content.
    w = by_topic['/angular_velocity']
    assert w[100].message.header.stamp.sec == 0
    assert w[100].message.header.stamp.nanosec == 200_000_000
    assert w[-1].message.vector.z == 30.0 and w[0].message.vector.x == 1.0
    assert [m.log_time_ns for m in messages] == sorted(m.log_time_ns for m in messages)


def test_summary_equals_golden_json(expected):
    summary = summarize(DATA / 'golden.mcap')
    assert summary.finalised and summary.profile == expected['profile']
    assert summary.message_count == expected['message_count']
    assert summary.start_time_ns == expected['start_time_ns']
    assert summary.end_time_ns == expected['end_time_ns']
    assert {t: (s.type_name, s.message_count) for t, s in summary.topics.items()} == {
        t: (spec['type'], spec['count']) for t, spec in expected['topics'].items()}
    assert summary.compressions == (expected['compression'],)
    assert summary.chunk_count > 1


def test_channel_metadata_equals_golden_json(expected):
    with open(DATA / 'golden.mcap', 'rb') as stream:
        summary = make_reader(stream).get_summary()
    qos = {c.topic: c.metadata['offered_qos_profiles'] for c in summary.channels.values()}
    assert qos == {t: spec['offered_qos_profiles'] for t, spec in expected['topics'].items()}
    # The script's literal QoS text is what offered_qos_yaml makes (names: the file's channels).
    assert qos['/scenario'] == offered_qos_yaml({'depth': 1, 'durability': 'transient_local'})
    assert qos['/clock'] == offered_qos_yaml({'depth': 1000})


def test_scan_summary_of_a_copy_without_footer_matches(tmp_path, expected):
    # Cutting off everything after the data section forces summarize() to scan; it must find the
    # same topics and counts as golden.json.
    data = (DATA / 'golden.mcap').read_bytes()
    # Footer: ... summary_start (u64), summary_offset_start (u64), summary_crc (u32), magic (8).
    summary_start = int.from_bytes(data[-28:-20], 'little')
    assert 0 < summary_start < len(data)
    path = tmp_path / 'nofooter.mcap'
    path.write_bytes(data[:summary_start])
    summary = summarize(path)
    assert summary.truncated
    assert {t: (s.type_name, s.message_count) for t, s in summary.topics.items()} == {
        t: (spec['type'], spec['count']) for t, spec in expected['topics'].items()}
    assert (summary.start_time_ns, summary.end_time_ns) == (expected['start_time_ns'],
                                                            expected['end_time_ns'])
    assert summary.chunk_count == summarize(DATA / 'golden.mcap').chunk_count

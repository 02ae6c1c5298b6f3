"""
The offline recording (bringup --offline, the main job) against a live one, message by message.

The same scenario with impacts (config/fig10.yaml) recorded both ways: the same channels,
schemas and offered-QoS metadata, and on every topic the same messages in the same order (all
their fields) at the same log times (simulated time on the ROS clock), apart from what
runs/offline.py says differs (publish times, the simulator's wall-clock heartbeats on /status).
Both read as a viewer reads them (viewer_checks.py): they play in the run's own time.
"""
from pathlib import Path

from mcap.reader import make_reader
import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.core import Impact, IntegratorSettings, load_scenario, Scenario
from tumble_ros.io import read_messages, summarize
from tumble_ros.nodes.bringup import run_bringup
from tumble_ros.runs.offline import record_offline
from tumble_ros_interfaces.msg import SimStatus
from viewer_checks import check_timeline, timeline

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def _by_topic(path) -> dict[str, list[dict]]:
    result: dict[str, list[dict]] = {}
    for m in read_messages(path):
        result.setdefault(m.topic, []).append(_ros_fields(m.message))
    return result


def _ros_fields(decoded) -> dict:
    """Return the decoded (mcap-ros2) message's fields as plain values."""
    out = {}
    for name in decoded.__slots__:
        value = getattr(decoded, name)
        if hasattr(value, '__slots__') and not isinstance(value, (str, bytes)):
            out.update({f'{name}.{k}': v for k, v in _ros_fields(value).items()})
        elif isinstance(value, list) and value and hasattr(value[0], '__slots__'):
            out[name] = [_ros_fields(v) for v in value]
        else:
            out[name] = bytes(value) if isinstance(value, (bytes, bytearray)) else value
    return out


def _channels(path) -> dict[str, tuple]:
    with open(path, 'rb') as f:
        summary = make_reader(f).get_summary()
    return {c.topic: (summary.schemas[c.schema_id].name, summary.schemas[c.schema_id].data,
                      c.message_encoding, dict(c.metadata))
            for c in summary.channels.values()}


@pytest.fixture(scope='module')
def both(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('offline')
    live = run_bringup(str(CONFIG / 'fig10.yaml'), str(tmp / 'live.mcap'), progress=None)
    offline = run_bringup(str(CONFIG / 'fig10.yaml'), str(tmp / 'offline.mcap'), progress=None,
                          offline=True)
    assert live.ok and offline.ok, (live, offline)
    return live, offline


def test_the_same_channels_schemas_and_qos_metadata(both):
    live, offline = both
    assert _channels(offline.output) == _channels(live.output)


def test_every_topic_holds_the_same_messages(both):
    live, offline = both
    a, b = _by_topic(live.output), _by_topic(offline.output)
    assert set(a) == set(b)
    status, latched = '/' + topics.STATUS, '/' + topics.COMPARISON_STATUS
    # every description carries its run's id: one per recording, different between the two runs
    runs = [{d.pop('run_id') for d in rec['/' + topics.SCENARIO]} for rec in (a, b)]
    assert all(len(run) == 1 for run in runs) and runs[0] != runs[1], runs
    for topic in sorted(set(a) - {status, latched}):
        assert len(a[topic]) == len(b[topic]), topic
        for k, (x, y) in enumerate(zip(a[topic], b[topic])):
            assert x == y, (topic, k, x, y)
    # impacts: fig10 has one; its event and the post-impact description are there
    assert len(b['/' + topics.IMPACT_EVENTS]) == 1 and len(b['/' + topics.SCENARIO]) == 2
    # comparison/status is latched with depth 1: a live recorder that subscribes after the
    # comparator's first status misses it; the rest is the same
    assert a[latched] == b[latched][len(b[latched]) - len(a[latched]):]
    assert b[latched][0]['level'] == 1 and len(b[latched]) == 3   # WARN waiting, 2 anchors
    # /status: the same state changes (a live run adds wall-clock heartbeats while running; it is
    # latched with depth 1 too)
    changes = [(s['state'], s['message']) for k, s in enumerate(a[status])
               if k == 0 or s['state'] != a[status][k - 1]['state']]
    offline_states = [(s['state'], s['message']) for s in b[status]]
    assert changes == offline_states[len(offline_states) - len(changes):]
    assert offline_states[0] == (SimStatus.RUNNING, 'started')
    assert b[status][-1]['state'] == SimStatus.FINISHED


def test_both_play_in_simulated_time_as_a_viewer_reads_them(both):
    scenario = load_scenario(CONFIG / 'fig10.yaml')
    for result in both:
        t = check_timeline(result.output, scenario.duration, scenario.output_interval)
        (impact,) = t.log_times['/' + topics.IMPACT_EVENTS]
        assert impact == 1_000_000_300      # its end: 1 + 3e-7 yr, on the ROS clock
        assert list(t.log_times['/' + topics.SCENARIO]) == [0, impact]


def test_every_message_is_logged_at_the_live_time(both):
    """Per topic, the same log times live and offline (the per-sample ones: their stamps)."""
    live, offline = both
    a, b = timeline(live.output).log_times, timeline(offline.output).log_times
    status, latched = '/' + topics.STATUS, '/' + topics.COMPARISON_STATUS
    for topic in sorted(set(a) - {status, latched}):
        np.testing.assert_array_equal(a[topic], b[topic], err_msg=topic)
    # comparison/status has no stamp: live, the latest stamp the recorder had received, at or
    # after the sample it is about (offline; the simulator runs ahead of the comparator); the
    # depth-1 latched topic lost its first
    ahead = a[latched] - b[latched][len(b[latched]) - len(a[latched]):]
    assert np.all(ahead >= 0) and a[latched][-1] <= a[topics.CLOCK][-1], ahead
    # /status: every state change at the time of its sample (the last before it)
    assert b[status][0] == 0 and b[status][-1] == a[status][-1] == a[topics.CLOCK][-1]


def test_the_counts_are_the_live_counts(both):
    live, offline = both
    per_sample = {'/' + t if not t.startswith('/') else t for t in topics.PER_SAMPLE}
    assert {t: n for t, n in offline.counts.items() if t in per_sample} == {
        t: n for t, n in live.counts.items() if t in per_sample}
    assert summarize(offline.output).finalised


def test_a_diverging_run_is_stopped_and_reported_offline(tmp_path):
    sc = Scenario(inertia=(1.0, 1.6, 2.2), duration=1.0, output_interval=0.1,
                  impacts=(Impact(0.0, 0.5, (1e300, 1e300, 1e300)),),
                  integrator=IntegratorSettings(method='rk4', step=0.1))
    result = record_offline(sc, tmp_path / 'diverged.mcap')
    assert result.state == SimStatus.DIVERGED and 'non-finite' in result.message
    assert result.samples < 11
    messages = list(read_messages(result.output, '/' + topics.ANGULAR_VELOCITY))
    assert len(messages) == result.samples
    assert all(np.isfinite([m.message.vector.x for m in messages]))
    assert summarize(result.output).finalised


def test_a_stop_request_finalises_what_was_written(tmp_path):
    sc = load_scenario(CONFIG / 'fig9.yaml').replace(duration=200.0)
    calls = []
    result = record_offline(sc, tmp_path / 'stopped.mcap', stop=lambda: len(calls) > 0,
                            progress=lambda t, k: calls.append(k))
    assert 0 < result.samples < 20001 and result.state == SimStatus.RUNNING
    assert summarize(result.output).finalised
    assert summarize(result.output).topics['/' + topics.ANGULAR_VELOCITY].message_count == (
        result.samples)


def test_a_kepler_orbit_from_a_params_file_runs_and_is_reported(tmp_path):
    from tumble_ros.analysis import analyze, load_recording

    params = tmp_path / 'kepler.yaml'
    params.write_text('sim:\n  ros__parameters:\n    orbit_rate: 0.0\n    duration: 0.5\n'
                      '    output_interval: 0.01\n    orbit.kind: kepler\n'
                      '    orbit.gm: 1.3271244e11\n    orbit.a: 1.5e8\n    orbit.e: 0.5\n')
    result = run_bringup(str(params), str(tmp_path / 'kepler.mcap'), progress=None,
                         offline=True)
    assert result.ok and result.samples == 51
    status = [m.message for m in read_messages(result.output, '/' + topics.COMPARISON_STATUS)]
    assert status[-1].level == 1 and 'circular orbit' in status[-1].message
    rec = load_recording(result.output)
    assert rec.scenario.orbit is not None and rec.scenario.orbit.e == 0.5
    summary = analyze(rec)
    assert summary.invariant is None
    assert 'not conserved on a Kepler orbit' in summary.invariant_note


def test_a_model_that_leaves_the_solution_is_reported_live_and_offline(tmp_path):
    """Fig 9's paper model outgrows w: the status says from when, live and offline alike."""
    from tumble_ros.analysis import analyze, load_recording

    params = tmp_path / 'fig9_20yr.yaml'
    text = (CONFIG / 'fig9.yaml').read_text()
    params.write_text(text.replace('duration: 2000.0', 'duration: 20.0'))
    live = run_bringup(str(params), str(tmp_path / 'live.mcap'), progress=None)
    offline = run_bringup(str(params), str(tmp_path / 'off.mcap'), progress=None, offline=True)
    assert live.ok and offline.ok
    latched = '/' + topics.COMPARISON_STATUS
    a, b = _by_topic(live.output)[latched], _by_topic(offline.output)[latched]
    assert a == b[len(b) - len(a):]
    # the first sample whose |w - w_model| exceeds |w|, from the recorded w and model
    rec = load_recording(offline.output)
    rel = (np.linalg.norm(rec.omega - rec.model_omega, axis=1)
           / np.linalg.norm(rec.omega, axis=1))
    t_first = rec.t[np.argmax(rel > 1.0)]
    assert rel.max() > 1.0 and 5.0 < t_first < 20.0
    assert b[-1]['level'] == 1 and f'left the numeric solution at t = {t_first:.9g} yr' in (
        b[-1]['message'])
    summary = analyze(rec)
    assert summary.comparator.t_departure == t_first
    assert summary.comparator.departed == int(np.sum(rel > 1.0))


def test_a_stop_is_served_after_one_bounded_slice_and_slices_change_no_bit(tmp_path):
    """
    The integration runs in slices of bounded work: a stop request is seen after the first.

    Before, one compiled call did a whole batch (up to 8192 samples and 50,000 steps: seconds
    with 1,000 impacts) before the stop was looked at. The sliced samples are bit for bit those
    of one uninterrupted call (Propagator.sample_many's contract, checked here on the file).
    """
    from tumble_ros.core import Propagator, TimeBase
    from tumble_ros.core.propagation.propagator import FAST_WORK_BUDGET

    sc = Scenario(duration=2.0, output_interval=0.002)
    checks = []

    def stop_after_first_slice() -> bool:
        checks.append(None)
        return len(checks) > 1

    stopped = record_offline(sc, tmp_path / 'stopped.mcap', stop=stop_after_first_slice)
    grid = TimeBase().grid(sc.output_interval, sc.duration)
    assert 0 < stopped.samples < grid.count    # one slice, not the whole batch
    assert summarize(stopped.output).finalised
    full = record_offline(sc, tmp_path / 'full.mcap')
    omega = np.array([[m.message.vector.x, m.message.vector.y, m.message.vector.z]
                      for m in read_messages(full.output, topics=['/' + topics.ANGULAR_VELOCITY])])
    done, arrays, failure = Propagator(sc).sample_many(grid.times(0, grid.count),
                                                       budget=FAST_WORK_BUDGET * 1000)
    assert done == grid.count and not failure
    assert np.array_equal(omega, arrays['omega'])   # bit for bit

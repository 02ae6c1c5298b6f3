"""
Helpers of the analysis tests: synthetic recordings with known content.

``write_recording`` writes an MCAP file laid out as the simulator, comparator and recorder
write theirs (same topics, types and stamps), from arrays given by the test, with
``tumble_ros.io.McapWriter`` and messages serialised by rclpy (tests may import rclpy; the
analysis modules may not). The one test here checks the helper itself against the io reader.
"""
from __future__ import annotations

import math

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import QuaternionStamped, Vector3Stamped
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from tumble_ros import topics
from tumble_ros.core import dump_scenario, Scenario, TimeBase
from tumble_ros.io import McapWriter, read_messages
from tumble_ros_interfaces.msg import ErrorNorm, ImpactEvent, ScenarioDescription, SimStatus

#: The full names (root namespace) a recording holds, with each topic's type and class.
TYPES = {
    '/' + topics.ANGULAR_VELOCITY: ('geometry_msgs/msg/Vector3Stamped', Vector3Stamped),
    '/' + topics.ATTITUDE: ('geometry_msgs/msg/QuaternionStamped', QuaternionStamped),
    '/' + topics.EULER_ANGLES: ('geometry_msgs/msg/Vector3Stamped', Vector3Stamped),
    topics.CLOCK: ('rosgraph_msgs/msg/Clock', Clock),
    '/' + topics.IMPACT_EVENTS: ('tumble_ros_interfaces/msg/ImpactEvent', ImpactEvent),
    '/' + topics.STATUS: ('tumble_ros_interfaces/msg/SimStatus', SimStatus),
    '/' + topics.SCENARIO: ('tumble_ros_interfaces/msg/ScenarioDescription', ScenarioDescription),
    '/' + topics.MODEL_ANGULAR_VELOCITY: ('geometry_msgs/msg/Vector3Stamped', Vector3Stamped),
    '/' + topics.ERROR: ('geometry_msgs/msg/Vector3Stamped', Vector3Stamped),
    '/' + topics.ERROR_NORM: ('tumble_ros_interfaces/msg/ErrorNorm', ErrorNorm),
    '/' + topics.COMPARISON_STATUS: ('diagnostic_msgs/msg/DiagnosticStatus', DiagnosticStatus),
}


def _time(stamp, ns: int) -> None:
    stamp.sec = ns // 1_000_000_000
    stamp.nanosec = ns % 1_000_000_000


def _stamp(header, ns: int) -> None:
    _time(header.stamp, ns)


def _vector3(msg, ns, v, frame=topics.FRAME_BODY):
    _stamp(msg.header, ns)
    msg.header.frame_id = frame
    msg.vector.x, msg.vector.y, msg.vector.z = (float(c) for c in v)
    return msg


#: The run id of the descriptions :func:`write_recording` writes.
RUN_ID = '0a1b2c3d4e5f'


def write_recording(path, t, omega, *, quaternion=None, euler=None,
                    scenario: Scenario | None = None,
                    seconds_per_year: float = 1.0, impacts=(), model=None, model_name='paper',
                    error_norm=True, error_vectors=True, clock=True, status=True,
                    segments=None, extra_topics=(), chunk_bytes=1_000_000, run_id=RUN_ID,
                    foreign_descriptions=()):
    """
    Write a recording; returns its path.

    ``t`` (n,) [yr], ``omega`` (n, 3); ``quaternion`` (n, 4) (w, x, y, z), ``euler`` (n, 3);
    ``scenario``: published on /scenario (revision 0 at t[0]) with ``seconds_per_year``;
    ``segments``: extra (revision, segment_start, omega, quaternion) descriptions;
    ``run_id``: the run id of those descriptions; ``foreign_descriptions``: ScenarioDescription
    messages of a second publisher, also on /scenario (at their header stamps);
    ``impacts``: dicts with id, start, end, frame, torque, delta_omega (published at end);
    ``model`` (n, 3): the comparator's model w at the same stamps; with it
    /comparison/error = omega - model and (if ``error_norm``) /comparison/error_norm.
    """
    tb = TimeBase(seconds_per_year)
    t = np.asarray(t, dtype=float)
    omega = np.asarray(omega, dtype=float)
    events = []   # (stamp ns, order, topic, message)

    def add(topic, ns, msg, order=0):
        events.append((ns, order, topic, msg))

    if scenario is not None:
        desc = ScenarioDescription()
        _stamp(desc.header, tb.to_ns(t[0]))
        desc.revision = 0
        desc.run_id = run_id
        desc.parameters_yaml = dump_scenario(scenario)
        desc.seconds_per_year = float(seconds_per_year)
        desc.segment_start = float(t[0])
        desc.omega.x, desc.omega.y, desc.omega.z = (float(c) for c in omega[0])
        if quaternion is not None:
            q = quaternion[0]
            att = desc.attitude
            att.w, att.x, att.y, att.z = (float(c) for c in q)
        add('/' + topics.SCENARIO, tb.to_ns(t[0]), desc, -2)
        for revision, start, w, q in segments or ():
            d = ScenarioDescription()
            _stamp(d.header, tb.to_ns(start))
            d.revision = revision
            d.run_id = run_id
            d.parameters_yaml = dump_scenario(scenario)
            d.seconds_per_year = float(seconds_per_year)
            d.segment_start = float(start)
            d.omega.x, d.omega.y, d.omega.z = (float(c) for c in w)
            d.attitude.w, d.attitude.x, d.attitude.y, d.attitude.z = (float(c) for c in q)
            add('/' + topics.SCENARIO, tb.to_ns(start), d, 1)
    for d in foreign_descriptions:
        add('/' + topics.SCENARIO,
            TimeBase.stamp_ns(d.header.stamp.sec, d.header.stamp.nanosec), d, 1)
    if status:
        s = SimStatus()
        _stamp(s.header, tb.to_ns(t[0]))
        s.state, s.t = SimStatus.RUNNING, float(t[0])
        add('/' + topics.STATUS, tb.to_ns(t[0]), s, -1)
    if model is not None:
        st = DiagnosticStatus(level=DiagnosticStatus.OK, name='/comparator', message='anchored')
        st.values = [KeyValue(key='model', value=model_name)]
        add('/' + topics.COMPARISON_STATUS, tb.to_ns(t[0]), st, -1)
    for k in range(len(t)):
        ns = tb.to_ns(t[k])
        if clock:
            c = Clock()
            _time(c.clock, ns)
            add(topics.CLOCK, ns, c)
        add('/' + topics.ANGULAR_VELOCITY, ns, _vector3(Vector3Stamped(), ns, omega[k]))
        if quaternion is not None:
            m = QuaternionStamped()
            _stamp(m.header, ns)
            m.header.frame_id = topics.FRAME_ORBITAL
            q = quaternion[k]
            m.quaternion.w, m.quaternion.x, m.quaternion.y, m.quaternion.z = (float(c) for c in q)
            add('/' + topics.ATTITUDE, ns, m)
        if euler is not None:
            add('/' + topics.EULER_ANGLES, ns,
                _vector3(Vector3Stamped(), ns, euler[k], topics.FRAME_ORBITAL))
        if model is not None:
            add('/' + topics.MODEL_ANGULAR_VELOCITY, ns,
                _vector3(Vector3Stamped(), ns, model[k]), 1)
            err = omega[k] - model[k]
            if error_vectors:
                add('/' + topics.ERROR, ns, _vector3(Vector3Stamped(), ns, err), 1)
            if error_norm:
                e = ErrorNorm()
                _stamp(e.header, ns)
                e.header.frame_id = topics.FRAME_BODY
                e.model = model_name
                e.norm = float(np.linalg.norm(err))
                mag = float(np.linalg.norm(omega[k]))
                e.relative = e.norm / mag if mag > 0 else math.inf
                add('/' + topics.ERROR_NORM, ns, e, 1)
    for imp in impacts:
        ev = ImpactEvent()
        ns = tb.to_ns(imp['end'])
        _stamp(ev.header, ns)
        ev.header.frame_id = topics.FRAME_BODY
        ev.id = imp.get('id', 0)
        ev.start, ev.end = float(imp['start']), float(imp['end'])
        ev.frame = (ImpactEvent.FRAME_ORBITAL if imp.get('frame') == topics.FRAME_ORBITAL
                    else ImpactEvent.FRAME_BODY)
        ev.torque.x, ev.torque.y, ev.torque.z = (float(c) for c in imp['torque'])
        ev.delta_omega.x, ev.delta_omega.y, ev.delta_omega.z = (
            float(c) for c in imp['delta_omega'])
        add('/' + topics.IMPACT_EVENTS, ns, ev, 2)
    if status:
        s = SimStatus()
        _stamp(s.header, tb.to_ns(t[-1]))
        s.state, s.t, s.message = SimStatus.FINISHED, float(t[-1]), 'reached duration'
        add('/' + topics.STATUS, tb.to_ns(t[-1]), s, 3)
    for topic, type_name, ns, data in extra_topics:
        events.append((ns, 4, (topic, type_name), data))
    events.sort(key=lambda e: (e[0], e[1]))
    with McapWriter(path, chunk_bytes=chunk_bytes, chunk_seconds=math.inf) as writer:
        channels = {}
        for ns, _, topic, msg in events:
            if isinstance(topic, tuple):
                topic, type_name = topic
                data = msg
            else:
                type_name = TYPES[topic][0]
                data = serialize_message(msg)
            if topic not in channels:
                channels[topic] = writer.add_channel(topic, type_name)
            writer.write(channels[topic], data, ns + 1000, ns)
    return path


def test_write_recording_round_trips_through_the_io_reader(tmp_path):
    t = np.arange(5) * 0.5
    omega = np.stack([np.cos(t), np.sin(t), np.full(5, 3.0)], -1)
    path = write_recording(tmp_path / 'r.mcap', t, omega, scenario=Scenario(),
                           seconds_per_year=2.0,
                           model=omega * 0.5)
    got = list(read_messages(path, '/' + topics.ANGULAR_VELOCITY))
    assert [m.message.header.stamp.sec * 10**9 + m.message.header.stamp.nanosec for m in got] == \
        [int(round(x * 2e9)) for x in t]
    assert np.allclose([[m.message.vector.x, m.message.vector.y, m.message.vector.z] for m in got],
                       omega)
    norms = [m.message.norm for m in read_messages(path, '/' + topics.ERROR_NORM)]
    assert np.allclose(norms, np.linalg.norm(omega * 0.5, axis=1))


@pytest.mark.parametrize('span, unit', [
    (2000.0, 'yr'), (1.0, 'yr'), (0.2, 'd'), (144 / 8766, 'h'), (10 / 8766, 'h'),
    (9 / 8766, 'min'), (0.5 / 8766, 'min'), (10 / (8766 * 3600), 's'), (0.0, 's')])
def test_a_short_run_is_shown_in_hours_or_days(span, unit):
    from tumble_ros.analysis.timeaxis import display_unit
    from tumble_ros.core.units import TIME_UNITS

    name, years = display_unit(span)
    assert (name, years) == (unit, TIME_UNITS[unit])


def test_the_time_axis_of_a_flyby_reads_in_round_hours():
    """The Apophis flyby (144 h = 0.016 yr): ticks at round hours, labelled in hours."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from tumble_ros.analysis.display import display_units
    from tumble_ros.analysis.figures import time_axis

    t = np.linspace(0.0, 144 / 8766, 145)           # [yr]
    fig = Figure()
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1, sharex=True)
    for ax in axes:
        ax.plot(t, np.sin(t))
    time_axis(axes, display_units(t[-1]))
    fig.canvas.draw()
    hours = [tick * 8766 for tick in axes[-1].get_xticks() if 0 <= tick <= t[-1]]
    assert len(hours) >= 3
    assert all(abs(h - round(h)) < 1e-6 and round(h) % 5 == 0 for h in hours), hours
    labels = [label.get_text() for label in axes[-1].get_xticklabels()]
    assert any(text == f'{round(hours[1]):d}' for text in labels), labels
    assert axes[-1].get_xlabel() == 't [h]'


def test_a_series_with_a_gap_is_drawn_broken_not_bridged():
    """No straight line across an encounter window where the model published nothing."""
    from tumble_ros.analysis.figures import envelope, ENVELOPE_BINS, gapped_envelope
    from tumble_ros.analysis.timeaxis import runs

    t = np.concatenate([np.arange(0, 10), np.arange(20, 30)]) * 0.1
    y = np.cos(t)
    assert runs(t) == [(0, 10), (10, 20)]
    gt, gy = gapped_envelope(t, y)
    assert np.isnan(gy).sum() == 1 and np.isnan(gy[10])
    np.testing.assert_array_equal(np.delete(gt, 10), t)
    np.testing.assert_array_equal(np.delete(gy, 10), y)
    assert runs(np.arange(30.0)) == [(0, 30)]
    # long runs keep their envelope (every extreme), one break between them
    n = 20 * ENVELOPE_BINS
    t = np.concatenate([np.arange(n), np.arange(2 * n, 3 * n)]) * 1e-3
    y = np.sin(t * 37.0)
    gt, gy = gapped_envelope(t, y)
    assert np.isnan(gy).sum() == 1
    first, second = envelope(t[:n], y[:n]), envelope(t[n:], y[n:])
    k = len(first[0])
    np.testing.assert_array_equal(gt[:k], first[0])
    np.testing.assert_array_equal(gy[k + 1:], second[1])
    assert gy[:k].max() == y[:n].max() and gy[k + 1:].min() == y[n:].min()


def test_every_theory_line_of_the_spectrum_has_its_own_look(tmp_path, monkeypatch):
    """Ten theory lines (more than the colour cycle has): no two drawn alike."""
    import dataclasses

    from tumble_ros.analysis import analyze, load_recording
    from tumble_ros.analysis import figures
    from tumble_ros.analysis.theory import TheoryLine

    t = np.arange(2000) * 0.001
    omega = np.stack([np.cos(40 * t), np.sin(40 * t), np.full_like(t, 30.0)], -1)
    rec = load_recording(write_recording(tmp_path / 'lines.mcap', t, omega,
                                         scenario=Scenario(duration=2.0, output_interval=0.001)))
    lines = tuple(TheoryLine(f'line {k}', 10.0 * (k + 1), 'test') for k in range(10))
    summary = dataclasses.replace(analyze(rec), theory=lines)
    drawn = {}
    real_png = figures._png
    monkeypatch.setattr(figures, '_png', lambda fig, name: (drawn.setdefault(name, fig),
                                                            real_png(fig, name))[1])
    figures._draw_spectrum(rec, summary)
    ax = drawn['spectrum_wx.png'].axes[0]
    looks = [(line.get_color(), line.get_linestyle()) for line in ax.get_lines()
             if line.get_label().startswith('line ')]
    assert len(looks) == 10 and len(set(looks)) == 10, looks
    # brown and grey read as red and black in a thin dashed line
    assert not {color for color, _ in looks} & {'C5', 'C7', 'tab:brown', 'tab:gray'}, looks

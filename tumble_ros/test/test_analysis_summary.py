"""
tumble_ros.analysis as functions.

Recordings with known content give the numbers they were built with (golden.mcap from
scripts/make_golden_mcap.py's literal inputs; synthetic recordings written here).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from test_analysis_support import write_recording

from tumble_ros import topics
from tumble_ros.analysis import analyze, format_summary, load_recording, summary_to_dict
from tumble_ros.analysis.summary import spectrum, theory_lines
from tumble_ros.core import Impact, Scenario, simulate

DATA = Path(__file__).resolve().parent / 'data'
GOLDEN = DATA / 'golden.mcap'
EXPECTED = json.loads((DATA / 'golden.json').read_text())

# scripts/make_golden_mcap.py's literal inputs: 200 samples t_k = 0.002 k, wx = cos(2 pi 15 t).
GOLDEN_N, GOLDEN_DT, GOLDEN_F = 200, 0.002, 15.0


# -- golden.mcap ------------------------------------------------------------------------------

@pytest.fixture(scope='module')
def golden():
    rec = load_recording(GOLDEN)
    return rec, analyze(rec)


def test_golden_counts_types_and_time_axis(golden):
    rec, s = golden
    assert s.topics == {name: (e['type'], e['count']) for name, e in EXPECTED['topics'].items()}
    assert s.finalised and s.problem is None
    assert rec.n == GOLDEN_N == s.sampling.n
    assert s.seconds_per_year == 1.0 and s.seconds_per_year_source == '/' + topics.SCENARIO
    assert s.sampling.t_first == 0.0
    assert s.sampling.duration == pytest.approx((GOLDEN_N - 1) * GOLDEN_DT, abs=1e-15)
    assert s.sampling.dt == pytest.approx(GOLDEN_DT, rel=1e-12) and s.sampling.uniform
    t = np.arange(GOLDEN_N) * GOLDEN_DT
    assert np.allclose(rec.t, t, rtol=0, atol=1e-15)
    assert np.allclose(rec.omega[:, 0], np.cos(2 * np.pi * GOLDEN_F * t), atol=1e-15)
    assert np.allclose(rec.omega[:, 2], 30.0)
    # attitude every 10th sample: q = (cos 15 t, 0, 0, sin 15 t)
    tq = t[::10]
    assert np.array_equal(rec.quaternion_t, rec.t[::10])
    assert np.allclose(rec.quaternion,
                       np.stack([np.cos(15 * tq), 0 * tq, 0 * tq, np.sin(15 * tq)], -1))
    assert len(rec.euler_t) == 0 and not rec.has_comparator


def test_golden_scenario_status_and_impact(golden):
    rec, s = golden
    assert rec.scenario is not None
    assert rec.scenario.omega0 == (1.0, 0.0, 30.0) and rec.scenario.duration == 0.4
    # a 0.4-yr run is shown in days, as its figures are (display.display_units)
    assert s.final_status == f'FINISHED at t = {0.398 * 365.25:.6g} d: reached duration'
    (imp,) = s.impacts
    e = imp.event
    assert (e.id, e.start, e.end, e.frame) == (1, 0.1, 0.1000003, topics.FRAME_BODY)
    assert e.torque == (0.0, 1.0e6, 0.0) and e.delta_omega == (0.0, 0.3, 0.0)
    assert e.t == pytest.approx(0.1000003, abs=1e-15)
    # the samples around the pulse are t = 0.1 (k = 50) and 0.102 (k = 51)
    assert imp.t_before == pytest.approx(0.1) and imp.t_after == pytest.approx(0.102)

    def w(t):
        return np.array([math.cos(2 * math.pi * 15 * t), math.sin(2 * math.pi * 15 * t), 30.0])
    assert np.allclose(imp.sampled_jump, w(0.102) - w(0.1), atol=1e-12)


def test_golden_dominant_frequency_is_2_pi_15(golden):
    _, s = golden
    sp = s.spectrum
    resolution = 2 * math.pi / (GOLDEN_N * GOLDEN_DT)
    assert sp.resolution == pytest.approx(resolution)
    assert sp.nyquist == pytest.approx(math.pi / GOLDEN_DT)
    top = sp.peaks[0]
    assert abs(top.omega - 2 * math.pi * GOLDEN_F) <= resolution
    assert top.amplitude == pytest.approx(1.0, rel=0.05)
    # a pure tone: no second peak above the threshold
    assert len(sp.peaks) == 1


def test_golden_jacobi_is_constant_per_segment(golden):
    """
    Check J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' for the golden content, by hand.

    The attitude turns about z, so z' = (0, 0, 1) and u stays in the body xy plane
    (u.Iu = Ix = 1); with |w_perp| = 1, wz = 30, I = (1, 1, 1.5), ws = 1:
    J = 1/2 (1 + 1.5*900) + 3/2 + 1.5*30 = 722.
    """
    _, s = golden
    inv = s.invariant
    assert inv.attitude_source == '/' + topics.ATTITUDE
    assert [seg.index for seg in inv.segments] == [0, 1]         # split at the impact
    assert (inv.segments[0].t_end == pytest.approx(0.1)
            and inv.segments[1].t_start == pytest.approx(0.12))
    assert sum(seg.n for seg in inv.segments) == 20
    for seg in inv.segments:
        assert seg.j0 == pytest.approx(722.0, rel=1e-14)
        assert seg.rel_drift < 1e-13


def test_golden_summary_text_and_json(golden):
    _, s = golden
    text = format_summary(s)
    assert ('/' + topics.ANGULAR_VELOCITY) in text and 'comparator error: none' in text
    assert 'WARNING' not in text
    data = json.loads(json.dumps(summary_to_dict(s), allow_nan=False))
    assert data['topics']['/' + topics.ANGULAR_VELOCITY] == {
        'type': 'geometry_msgs/msg/Vector3Stamped', 'count': 200}
    assert (data['comparator'] is None
            and data['impacts'][0]['event']['delta_omega'] == [0.0, 0.3, 0.0])
    assert data['spectrum']['peaks'][0]['omega'] == pytest.approx(
        2 * math.pi * 15, abs=data['spectrum']['resolution'])
    assert 'omega_axis' not in data['spectrum']


# -- comparator error -------------------------------------------------------------------------

def _comparator_case(tmp_path, **kwargs):
    """
    Analyze a comparator recording of 101 samples, t = 0 .. 1 yr.

    w = (cos 20 t, sin 20 t, 30); error = w - model = (0.01 k, 0, 0).
    """
    t = np.arange(101) * 0.01
    omega = np.stack([np.cos(20 * t), np.sin(20 * t), np.full_like(t, 30.0)], -1)
    err = np.zeros_like(omega)
    err[:, 0] = 0.01 * np.arange(101)
    path = write_recording(tmp_path / 'cmp.mcap', t, omega, model=omega - err,
                           model_name='fast_spin',
                           scenario=Scenario(duration=1.0, output_interval=0.01), **kwargs)
    return analyze(load_recording(path))


@pytest.mark.parametrize('source, kwargs', [
    ('/' + topics.ERROR_NORM, {}),
    ('/' + topics.ERROR, {'error_norm': False}),
    (f'/{topics.ANGULAR_VELOCITY} - /{topics.MODEL_ANGULAR_VELOCITY}',
     {'error_norm': False, 'error_vectors': False}),
])
def test_comparator_max_and_rms_error_come_out_as_constructed(tmp_path, source, kwargs):
    s = _comparator_case(tmp_path, **kwargs)
    c = s.comparator
    assert c.source == source and c.n == 101
    assert c.models == ('fast_spin',)
    # max 0.01 * 100 at t = 1; RMS 0.01 sqrt(sum k^2 / 101) = 0.01 sqrt(100 * 201 / 6)
    assert c.max_abs == pytest.approx(1.0, rel=1e-12) and c.t_max_abs == pytest.approx(1.0)
    assert c.rms_abs == pytest.approx(0.01 * math.sqrt(100 * 201 / 6), rel=1e-12)
    norm_w = math.sqrt(1 + 900)
    assert c.max_rel == pytest.approx(1.0 / norm_w, rel=1e-12)
    assert c.rms_rel == pytest.approx(0.01 * math.sqrt(100 * 201 / 6) / norm_w, rel=1e-12)
    assert c.infinite_rel == 0
    text = format_summary(s)
    assert "model 'fast_spin'" in text and 'max 1 rad/yr at t = 1 yr' in text


def test_relative_error_at_zero_rate_is_left_out(tmp_path):
    t = np.arange(20) * 0.1
    omega = np.ones((20, 3))
    omega[3] = 0.0
    model = omega - 0.5
    s = analyze(load_recording(write_recording(tmp_path / 'z.mcap', t, omega, model=model)))
    assert s.comparator.infinite_rel == 1
    assert s.comparator.max_rel == pytest.approx(math.sqrt(0.75) / math.sqrt(3))
    assert json.dumps(summary_to_dict(s), allow_nan=False)


def test_comparator_status_without_errors_is_reported(tmp_path):
    from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
    from rclpy.serialization import serialize_message
    st = DiagnosticStatus(level=DiagnosticStatus.WARN, name='/comparator',
                          message='inertia: a linearised model needs a symmetric body')
    st.values = [KeyValue(key='model', value='paper')]
    t = np.arange(10) * 0.1
    path = write_recording(tmp_path / 's.mcap', t, np.ones((10, 3)), extra_topics=[
        ('/' + topics.COMPARISON_STATUS, 'diagnostic_msgs/msg/DiagnosticStatus', 0,
         serialize_message(st))])
    s = analyze(load_recording(path))
    assert s.comparator is None
    assert 'WARN: inertia: a linearised model needs a symmetric body' in s.comparator_note


# -- impacts and the Jacobi integral on a real simulation ----------------------------------------

@pytest.fixture(scope='module')
def impact_run():
    scenario = Scenario(duration=0.2, output_interval=0.002,
                        impacts=(Impact(0.1, 3e-7, (0.0, 1e6, 0.0)),))
    return scenario, simulate(scenario)


def test_impact_delta_omega_and_jacobi_per_segment(tmp_path, impact_run):
    scenario, res = impact_run
    events = [{'id': 7, 'start': 0.1, 'end': 0.1 + 3e-7, 'torque': (0.0, 1e6, 0.0),
               'delta_omega': (0.001, 0.3, -0.002)}]
    path = write_recording(tmp_path / 'imp.mcap', res.t, res.omega, quaternion=res.quaternion,
                           scenario=scenario, impacts=events)
    s = analyze(load_recording(path))
    (imp,) = s.impacts
    assert imp.event.id == 7 and imp.event.delta_omega == (0.001, 0.3, -0.002)
    assert imp.event.duration == pytest.approx(3e-7)
    # the recorded jump over one sampling interval: 0.3 about y plus < 0.05 of free motion
    assert imp.sampled_jump[1] == pytest.approx(0.3, abs=0.05)
    inv = s.invariant
    assert [seg.n for seg in inv.segments] == [51, 50]
    j_core = res.jacobi
    assert inv.segments[0].j0 == pytest.approx(j_core[0], rel=1e-12)
    assert inv.segments[1].j0 == pytest.approx(j_core[51], rel=1e-12)
    for seg in inv.segments:
        assert seg.rel_drift < 1e-8
    # the impact changes J (here by 0.044, 6e-5 relative): one segment over the whole run would
    # show a drift 10^6 times what integration error gives within a segment
    jump = abs(inv.segments[1].j0 - inv.segments[0].j0)
    assert jump > 1e6 * max(seg.max_drift for seg in inv.segments)
    text = format_summary(s)
    # a 0.2-yr run reads in days: torque [I rad/d^2], delta_omega [rad/d]
    d = 1 / 365.25
    assert f'#7: body torque (0, {1e6 * d * d:.6g}, 0) I rad/d^2' in text, text
    assert f'delta_omega ({0.001 * d:.6g}, {0.3 * d:.6g}, {-0.002 * d:.6g}) rad/d' in text


def test_jacobi_from_euler_angles_without_attitude(tmp_path, impact_run):
    scenario, res = impact_run
    n = 51
    path = write_recording(tmp_path / 'eul.mcap', res.t[:n], res.omega[:n], euler=res.euler[:n],
                           scenario=scenario.replace(impacts=()))
    inv = analyze(load_recording(path)).invariant
    assert inv.attitude_source == '/' + topics.EULER_ANGLES
    assert len(inv.segments) == 1 and inv.segments[0].rel_drift < 1e-8
    assert inv.segments[0].j0 == pytest.approx(res.jacobi[0], rel=1e-12)


# -- aliasing -----------------------------------------------------------------------------------

FIG9 = Scenario(inertia=(1.0, 1.0, 4.0), allow_unphysical_inertia=True, omega0=(0.1, 0.1, 30.0),
                euler0=(0.5, 0.0, 0.9), duration=2000.0, output_interval=2.0)


def _nutation(t, w_e=90.0):
    return np.stack([0.14 * np.cos(w_e * t), 0.14 * np.sin(w_e * t), np.full_like(t, 30.0)], -1)


def test_paper_sampling_of_fig9_aliases_the_nutation(tmp_path):
    """
    Check the aliasing of the nutation by the paper's sampling (docs/paper.md, conventions).

    n = 1000 over 2000 yr (dt = 2 yr) undersamples the 2 pi/wE ~ 0.07-yr oscillation
    (wE = a w0 = 3 * 30 = 90 rad/yr); pi/dt = 1.57 rad/yr.
    """
    t = np.arange(1001) * 2.0
    path = write_recording(tmp_path / 'fig9.mcap', t, _nutation(t), scenario=FIG9, clock=False)
    s = analyze(load_recording(path))
    al = s.aliasing
    assert al.nyquist == pytest.approx(math.pi / 2.0)
    names = {line.name: alias for line, alias in al.aliased}
    assert 'wE' in names and '|w0|' in names
    # 90 rad/yr sampled every 2 yr shows up at |90 - 29 pi| = 1.106 rad/yr ...
    assert names['wE'] == pytest.approx(abs(90.0 - 29 * math.pi))
    # ... which is where the spectrum finds it
    top = s.spectrum.peaks[0]
    assert abs(top.omega - abs(90.0 - 29 * math.pi)) <= s.spectrum.resolution
    assert top.nearest == 'wE' and top.nearest_aliased and abs(top.offset) <= s.spectrum.resolution
    assert al.warning and any(w == al.warning for w in s.warnings)
    text = format_summary(s)
    warning_lines = [line for line in text.splitlines() if line.startswith('WARNING:')]
    assert len(warning_lines) == 1 and 'aliases wE = 90 rad/yr' in warning_lines[0]
    assert '(docs/paper.md, conventions)' in warning_lines[0]


def test_fine_sampling_does_not_alias(tmp_path):
    t = np.arange(2001) * 0.001
    scenario = FIG9.replace(duration=2.0, output_interval=0.001)
    path = write_recording(tmp_path / 'fine.mcap', t, _nutation(t), scenario=scenario, clock=False)
    s = analyze(load_recording(path))
    lines = {line.name: line.omega for line in s.theory}
    # the theory's lines for a = 3, w0 = 30, ws = 1, theta0 = 0.9 (docs/analytic.md)
    w_a = 2 * (1 + (30 + 90) / math.cos(0.9))
    assert lines['wE'] == pytest.approx(90.0)
    assert lines['|wA+wE|'] == pytest.approx(w_a + 90.0)
    assert lines['|wA-wE|'] == pytest.approx(w_a - 90.0)
    assert s.aliasing.fastest.name == '|wA+wE|' and not s.aliasing.aliased
    assert s.aliasing.warning is None and not s.warnings
    top = s.spectrum.peaks[0]
    assert abs(top.omega - 90.0) <= s.spectrum.resolution and top.nearest == 'wE'
    assert 'aliasing: none expected' in format_summary(s)


def test_aliasing_rule_in_isolation():
    from tumble_ros.analysis.summary import Sampling, TheoryLine, check_aliasing
    lines = [TheoryLine('a', 10.0, ''), TheoryLine('b', 3.0, '')]
    samp = lambda dt: Sampling(100, 0.0, 99 * dt, 99 * dt, dt, dt, dt, True, 0, 0)  # noqa: E731
    assert check_aliasing(samp(math.pi / 10.5), lines).warning is None
    hit = check_aliasing(samp(math.pi / 9.5), lines)
    assert [line.name for line, _ in hit.aliased] == ['a'] and hit.warning
    assert hit.aliased[0][1] == pytest.approx(2 * 9.5 - 10.0)


def test_theory_lines_for_other_bodies():
    lines, basis = theory_lines(Scenario(orbit_rate=0.0))
    assert [line.name for line in lines] == ['wE'] and lines[0].omega == pytest.approx(15.0)
    asym = Scenario(inertia=(1.0, 1.6, 2.2), orbit_rate=0.0, omega0=(3.0, 0.5, 10.0))
    lines, basis = theory_lines(asym)
    assert lines[0].name == 'Euler-Poinsot' and lines[0].omega > 0 and 'asymmetric' in basis
    lines, basis = theory_lines(asym.replace(orbit_rate=1.0))
    assert 'estimate' in basis and len(lines) == 2
    assert theory_lines(None)[0] == []


def test_theory_lines_are_asked_of_the_analytic_models():
    """The analysis derives no frequency itself: its lines are core.analytic's, bit for bit."""
    from tumble_ros.core.analytic import characteristic_frequencies, make_model
    lines, basis = theory_lines(FIG9)
    assert (tuple(lines), basis) == characteristic_frequencies(FIG9)
    paper = {f.name: f for f in make_model('paper', FIG9).frequencies()}
    assert lines[1:3] == [paper['|wA-wE|'], paper['|wA+wE|']]
    asym = Scenario(inertia=(1.0, 1.6, 2.2), omega0=(3.0, 0.5, 10.0))
    omega = np.array([[3.0, 0.5, 10.0], [0.0, 0.0, 20.0]])
    assert theory_lines(asym, omega) == (list(characteristic_frequencies(asym, 20.0).lines),
                                         characteristic_frequencies(asym).basis)


# -- what may be absent, odd sampling ----------------------------------------------------------

def test_only_angular_velocity(tmp_path):
    t = np.arange(50) * 0.01
    path = write_recording(tmp_path / 'bare.mcap', t, _nutation(t, 40.0), clock=False,
                           status=False)
    rec = load_recording(path)
    s = analyze(rec)
    assert rec.topics == {'/' + topics.ANGULAR_VELOCITY: ('geometry_msgs/msg/Vector3Stamped', 50)}
    assert s.seconds_per_year_source == 'default' and rec.scenario is None
    assert s.comparator is None and s.invariant is None and s.impacts == ()
    assert s.theory == () and s.aliasing.warning is None
    text = format_summary(s)
    for phrase in ('comparator error: none', 'invariant drift: not computed',
                   'impacts: none recorded',
                   'scenario: none', 'aliasing: not checked', 'seconds_per_year = 1 assumed'):
        assert phrase in text
    assert abs(s.spectrum.peaks[0].omega - 40.0) <= s.spectrum.resolution


def test_seconds_per_year_and_uneven_sampling(tmp_path):
    rng = np.random.default_rng(3)
    t = np.sort(np.concatenate([[0.0, 4.0], rng.uniform(0, 4.0, 1500)]))
    t = np.round(t * 1e6) / 1e6
    path = write_recording(tmp_path / 'uneven.mcap', t, _nutation(t, 12.0),
                           scenario=Scenario(duration=4.0, output_interval=0.01),
                           seconds_per_year=3600.0)
    rec = load_recording(path)
    assert rec.seconds_per_year == 3600.0
    assert np.allclose(rec.t, t, atol=1e-9)
    s = analyze(rec)
    assert s.sampling.duration == pytest.approx(4.0) and not s.sampling.uniform
    assert s.spectrum.resampled and any('interpolated' in note for note in s.notes)
    assert abs(s.spectrum.peaks[0].omega - 12.0) <= s.spectrum.resolution


def test_spectrum_separates_two_lines():
    t = np.arange(4000) * 0.001
    x = np.cos(90.0 * t) + 0.05 * np.cos(30.0 * t + 0.3)
    sp = spectrum(t, x)
    got = sorted(p.omega for p in sp.peaks)
    assert len(got) == 2
    assert abs(got[0] - 30.0) < 0.2 * sp.resolution and abs(got[1] - 90.0) < 0.2 * sp.resolution
    assert sp.peaks[1].amplitude == pytest.approx(0.05, rel=0.1)


def test_the_spin_state_at_start_and_end_is_reported(tmp_path):
    """An impact changes the tumbling state: the summary's start and end states say how."""
    from tumble_ros.core.model.spinstate import spin_state

    sc = Scenario(inertia=(1.0, 1.5, 2.0), orbit_rate=0.0, omega0=(2.0, 1.0, 10.0),
                  duration=1.0, output_interval=0.01,
                  impacts=(Impact(0.5, 1e-3, (0.0, 0.0, -18000.0)),))
    r = simulate(sc)
    path = write_recording(tmp_path / 'spin.mcap', r.t, r.omega, quaternion=r.quaternion,
                           scenario=sc)
    s = analyze(load_recording(path))
    assert s.spin is not None
    expected_start = spin_state(r.omega[0], sc.inertia, r.quaternion[0])
    expected_end = spin_state(r.omega[-1], sc.inertia, r.quaternion[-1])
    assert s.spin.start == expected_start and s.spin.end == expected_end
    assert s.spin.start.mode == 'SAM' and s.spin.end.mode == 'LAM'   # the impact flipped it
    assert s.spin.pole_shift > 0.01
    text = format_summary(s)
    assert 'start (t = 0 yr): SAM' in text and 'LAM' in text and 'pole shift' in text
    assert summary_to_dict(s)['spin']['end']['mode'] == 'LAM'


def test_no_spin_state_without_attitude(tmp_path):
    sc = Scenario(duration=0.1, output_interval=0.01)
    r = simulate(sc)
    s = analyze(load_recording(write_recording(tmp_path / 'w.mcap', r.t, r.omega, scenario=sc)))
    assert s.spin is None and s.spin_note == 'no attitude recorded'
    assert 'spin state: not computed (no attitude recorded)' in format_summary(s)


def test_samples_are_placed_in_segments_as_a_scan_of_every_pulse_places_them():
    """
    impact_segments (binary search) against the scan over every pulse it replaced.

    The scan cost pulses x samples: 10,000 impacts in a 2000-yr run took 9 s of the analysis.
    Sample times on the pulses' edges included (an edge belongs to the segment after it).
    """
    from tumble_ros.analysis.impacts import impact_intervals
    from tumble_ros.analysis.invariants import impact_segments

    rng = np.random.default_rng(4)
    starts = np.sort(rng.uniform(0.0, 100.0, 300))
    durations = np.where(rng.uniform(size=300) < 0.1, rng.uniform(0.1, 3.0, 300), 3e-7)

    class Rec:   # what impact_intervals reads
        impacts = [Impact(float(s), float(d), (0.0, 0.0, 1.0)) for s, d in zip(starts, durations)]
        scenario = None

    intervals = impact_intervals(Rec)
    assert 0 < len(intervals) < 300   # some merged
    edges = np.array([x for interval in intervals for x in interval])
    t = np.sort(np.concatenate([rng.uniform(-1.0, 101.0, 5000), edges, [0.0, 100.0]]))
    segment, inside = impact_segments(t, intervals)
    want_segment = np.zeros(len(t), dtype=int)
    want_inside = np.zeros(len(t), dtype=bool)
    for start, end in intervals:
        want_inside |= (t > start) & (t < end)
        want_segment += t >= end
    assert np.array_equal(segment, want_segment)
    assert np.array_equal(inside, want_inside)
    empty = impact_segments(t, [])
    assert not empty[0].any() and not empty[1].any()

"""
The run layer without ROS: the simulation session's and the comparison's records.

The session's samples are simulate()'s (bit for bit, batch by batch), an impact gives its event
and a new segment before the samples after it, a failure a status change; the comparison block
is the analytic model, anchored on each segment's start, minus the numeric solution, and the
per-sample path (the live comparator's) gives the block's bits (the offline recording's).
"""
import math

import numpy as np
import pytest
from test_no_ros import _assert_loads_none

from tumble_ros.core import (departure_text, Impact, IntegratorSettings, make_model, Scenario,
                             simulate, TimeBase)
from tumble_ros.runs.comparison import (Comparison, error_norms, error_norms_of_rows, SampleGate,
                                        WAITING)
from tumble_ros.runs.records import (ComparisonBlock, DIVERGED, FINISHED, ImpactEnded, OK,
                                     RUNNING, SampleBlock, SegmentStart, StatusChange, WARN)
from tumble_ros.runs.session import output_grid, SimulationSession

SHORT = Scenario(duration=0.2, output_interval=0.002)
#: A pulse about z in the middle of SHORT (Mz dt / Iz = 0.2 rad/yr).
IMPACT = Impact(0.1, 3e-7, (0.0, 0.0, 1.0e6))


def run(scenario, batch=7, budget=None):
    """All the records of a session advanced ``batch`` samples at a time."""
    session = SimulationSession(scenario, output_grid(scenario, TimeBase()), run_id='r1')
    records = session.start()
    while session.state == RUNNING:
        records += session.advance(session.samples + batch - 1, budget=budget)
    return session, records


def blocks(records):
    found = [r for r in records if isinstance(r, SampleBlock)]
    return {name: np.concatenate([getattr(b, name) for b in found])
            for name in ('times', 'stamps', 'omega', 'quaternion', 'euler')}


def test_the_sessions_samples_are_simulates_bit_for_bit():
    session, records = run(SHORT)
    ref = simulate(SHORT)
    got = blocks(records)
    assert len(got['times']) == len(ref.t) == 101 == session.samples
    for name in ('omega', 'quaternion', 'euler'):
        assert np.array_equal(got[name], getattr(ref, name)), name
    assert np.array_equal(got['times'], ref.t)
    assert np.array_equal(got['stamps'], np.arange(101) * 2_000_000)   # 0.002 yr at 1 s/yr
    # each block is the grid indices it says
    starts = [r.start for r in records if isinstance(r, SampleBlock)]
    assert starts == list(range(0, 101, 7))


def test_a_run_starts_with_its_first_segment_and_ends_finished():
    session, records = run(SHORT)
    first, started = records[:2]
    assert isinstance(first, SegmentStart) and (first.revision, first.t0, first.stamp_ns) == (
        0, 0.0, 0)
    assert first.omega == tuple(SHORT.omega0) and first.run_id == 'r1'
    assert 'duration: 0.2' in first.parameters_yaml and first.seconds_per_year == 1.0
    assert started == StatusChange(RUNNING, 0.0, 0, 'started')
    assert records[-1] == StatusChange(FINISHED, 0.2, 200_000_000, 'finished at t = 0.2 yr')
    assert sum(isinstance(r, StatusChange) for r in records) == 2
    assert session.advance(200) == []   # nothing more, said once


def test_an_impact_ends_with_its_event_then_a_new_segment_before_the_samples_after_it():
    session = SimulationSession(SHORT, output_grid(SHORT, TimeBase()))
    session.start()
    session.advance(10)
    session.request_impact(IMPACT, impact_id=7)
    assert session.impacts_in_progress == 1
    records = session.advance(100)
    kinds = [type(r) for r in records]
    assert kinds == [ImpactEnded, SegmentStart, SampleBlock, StatusChange]
    ended, segment = records[0], records[1]
    assert ended.impact is IMPACT and ended.impact_id == 7 and session.impacts_in_progress == 0
    assert ended.stamp_ns == TimeBase().to_ns(IMPACT.end)
    # the jump of w over the pulse, from simulate at the pulse's edges
    ref = simulate(SHORT.replace(impacts=(IMPACT,)), t_eval=[IMPACT.start, IMPACT.end])
    np.testing.assert_allclose(ended.delta_omega, ref.omega[1] - ref.omega[0], rtol=0,
                               atol=1e-12)
    assert ended.delta_omega[2] == pytest.approx(1.0e6 * 3e-7 / 1.5, rel=1e-9)
    assert (segment.revision, segment.t0) == (1, IMPACT.end)
    # (scheduled at t = 0.02, not from the start: another step sequence, the same motion)
    np.testing.assert_allclose(segment.omega, ref.omega[1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(segment.quaternion, ref.quaternion[1], rtol=0, atol=1e-10)
    with_impact = simulate(SHORT.replace(impacts=(IMPACT,)))
    np.testing.assert_allclose(records[2].omega, with_impact.omega[11:], rtol=0, atol=1e-9)


def test_a_failed_integration_is_a_status_change_after_the_good_samples():
    sc = Scenario(inertia=(1.0, 1.6, 2.2), duration=1.0, output_interval=0.1,
                  impacts=(Impact(0.0, 0.5, (1e300, 1e300, 1e300)),),
                  integrator=IntegratorSettings(method='rk4', step=0.1))
    session, records = run(sc, batch=100)
    change = records[-1]
    assert isinstance(change, StatusChange) and change.state == DIVERGED == session.state
    assert 'non-finite' in change.message
    got = [r for r in records if isinstance(r, SampleBlock)]
    assert session.samples < 11 and sum(map(len, got)) == session.samples
    assert all(np.isfinite(b.omega).all() for b in got)
    assert change.stamp_ns == max(0, session.samples - 1) * 100_000_000


def test_pause_and_resume_are_status_changes_once():
    session = SimulationSession(SHORT, output_grid(SHORT, TimeBase()), paused=True)
    assert session.start()[1].state == 1 and session.pause() is None
    assert session.resume() == StatusChange(RUNNING, 0.0, 0, 'resumed at t = 0 yr')
    assert session.resume() is None


def model_minus_numeric(scenario, start, times, omega):
    """Return omega - the paper's model anchored at ``start``'s state (evaluated here)."""
    model = make_model('paper', scenario, t0=start.t0, omega=start.omega,
                       quaternion=start.quaternion)
    return omega - model.omega(times)


def test_the_comparison_block_is_the_model_anchored_on_each_segment_minus_the_numeric_one():
    sc = SHORT.replace(impacts=(IMPACT,))
    _, records = run(sc, batch=30)
    comparison = Comparison('paper')
    assert comparison.waiting().message == WAITING
    starts, errors, compared = [], [], []
    for record in records:
        if isinstance(record, SegmentStart):
            status = comparison.anchor(record)
            assert status.level == OK and f'(segment {record.revision})' in status.message
            starts.append(record)
        elif isinstance(record, SampleBlock):
            block = comparison.compare(record)
            assert isinstance(block, ComparisonBlock) and block.departures == ()
            assert np.array_equal(block.stamps, record.stamps)
            errors.append(block)
            compared.append(block.compared)
    assert len(starts) == 2 and all(np.concatenate(compared))
    got = blocks(records)
    error = np.concatenate([b.error for b in errors])
    after = got['times'] >= IMPACT.end
    expected = np.where(after[:, None],
                        model_minus_numeric(sc, starts[1], got['times'], got['omega']),
                        model_minus_numeric(sc, starts[0], got['times'], got['omega']))
    np.testing.assert_allclose(error, expected, rtol=0, atol=1e-12)
    assert np.abs(error).max() > 1e-6   # (the model is not the numeric solution)
    norm = np.concatenate([b.norm for b in errors])
    relative = np.concatenate([b.relative for b in errors])
    np.testing.assert_allclose(norm, np.linalg.norm(expected, axis=1), rtol=1e-12)
    np.testing.assert_allclose(relative, norm / np.linalg.norm(got['omega'], axis=1),
                               rtol=1e-15)


def test_one_sample_at_a_time_gives_the_blocks_bits():
    """The live comparator's path (compare_one) and the offline one (compare) agree exactly."""
    sc = SHORT.replace(impacts=(IMPACT,))
    _, records = run(sc, batch=30)
    by_block, by_sample = Comparison('paper'), Comparison('paper')
    for record in records:
        if isinstance(record, SegmentStart):
            by_block.anchor(record)
            by_sample.anchor(record)
        elif isinstance(record, SampleBlock):
            block = by_block.compare(record)
            for j, (stamp, omega) in enumerate(zip(record.stamps.tolist(),
                                                   record.omega.tolist())):
                one = by_sample.compare_one(stamp, omega)
                assert one is not None and one.stamp_ns == stamp
                assert one.model == block.model[j].tolist()
                assert one.error == block.error[j].tolist()
                assert (one.norm, one.relative) == (block.norm[j], block.relative[j])


def synthetic_block(comparison, start, k0, n, scale):
    """Grid samples k0 .. k0 + n - 1 whose omega is ``scale`` times the anchored model's."""
    grid = comparison.grid
    times = grid.times(k0, k0 + n)
    model = make_model('paper', SHORT, t0=start.t0, omega=start.omega,
                       quaternion=start.quaternion).omega(times)
    zeros = np.zeros((n, 3))
    return SampleBlock(k0, times, np.arange(k0, k0 + n, dtype=np.int64) * grid.interval_ns,
                       model * scale[:, None], np.tile([1.0, 0, 0, 0], (n, 1)), zeros)


def test_a_departure_is_said_once_per_segment_at_its_first_sample():
    _, records = run(SHORT)
    start = records[0]
    comparison = Comparison('paper')
    comparison.anchor(start)
    # |0.4 w_model - w_model| / |0.4 w_model| = 1.5 > DEPARTURE (1) from sample 25 on
    scale = np.where(np.arange(50) < 25, 1.0, 0.4)
    first = comparison.compare(synthetic_block(comparison, start, 0, 50, scale))
    (said,) = first.departures
    t = comparison.grid.time(25)
    assert said.level == WARN and said.message == departure_text('paper', t)
    assert said.stamp_ns == 25 * comparison.grid.interval_ns
    assert first.relative[25] == pytest.approx(1.5) and first.relative[:25].max() < 1e-12
    again = comparison.compare(synthetic_block(comparison, start, 50, 10, np.full(10, 0.4)))
    assert again.departures == () and again.compared.all()
    # the live path says it once too
    one = Comparison('paper')
    one.anchor(start)
    block = synthetic_block(one, start, 0, 50, scale)
    said_live = [c.departure for c in (one.compare_one(s, w) for s, w in
                                       zip(block.stamps.tolist(), block.omega.tolist()))
                 if c is not None and c.departure is not None]
    assert said_live == [said]


def _same_blocks(a, b):
    """Assert two comparison blocks hold the same bits and say the same departures."""
    for name in ('stamps', 'compared', 'model', 'error', 'norm', 'relative'):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
    assert a.departures == b.departures


def test_an_in_order_comparison_gives_the_same_blocks_and_forgets_the_segments_behind():
    # the offline recording's: a segment per impact, blocks in time order
    sc = SHORT.replace(impacts=tuple(Impact(0.004 * k + 0.001, 3e-7, (0.0, 2e5, 1e5))
                                     for k in range(1, 45)))
    _, records = run(sc, batch=9)
    kept, forgetting = Comparison('paper'), Comparison('paper', in_order=True)
    for record in records:
        if isinstance(record, SegmentStart):
            assert kept.anchor(record) == forgetting.anchor(record)
        elif isinstance(record, SampleBlock):
            _same_blocks(kept.compare(record), forgetting.compare(record))
            # only the segment of the block's last sample is left (none starts after it)
            assert [s.start for s in forgetting._segments] == [kept._segments[-1].start]
    assert len(kept._segments) == 45
    # departures, in segments anchored one after the other (synthetic samples)
    start = records[0]
    kept, forgetting = Comparison('paper'), Comparison('paper', in_order=True)
    said = []
    for j, k0 in enumerate((0, 20, 40, 60)):
        later = SegmentStart(start.run_id, start.parameters_yaml, 1.0, j, kept.grid.time(k0)
                             if kept.grid else 0.0, k0 * 2_000_000, start.omega,
                             start.quaternion)
        kept.anchor(later)
        forgetting.anchor(later)
        scale = np.where(np.arange(20) % 7 < 3, 1.0, 0.4)
        block = synthetic_block(kept, start, k0, 20, scale)
        a = kept.compare(block)
        _same_blocks(a, forgetting.compare(block))
        said += a.departures
    assert len(said) == 4


def test_samples_before_a_segment_or_without_a_model_are_not_compared():
    _, records = run(SHORT)
    start, block = records[0], next(r for r in records if isinstance(r, SampleBlock))
    comparison = Comparison('paper')
    assert comparison.compare_one(0, (1.0, 2.0, 3.0)) is None
    # anchored later than the block's first samples: those are not compared
    late = SegmentStart(start.run_id, start.parameters_yaml, 1.0, 0, 0.006, 6_000_000,
                        start.omega, start.quaternion)
    comparison.anchor(late)
    result = comparison.compare(block)
    assert result.compared.tolist() == [False] * 3 + [True] * 4
    assert not result.model[:3].any() and not result.error[:3].any()
    # a model that does not apply: a WARN status, nothing compared
    status = comparison.set_model('no such model')
    assert status is not None and status.level == WARN
    assert not comparison.compare(block).compared.any()
    assert math.isfinite(block.omega.sum())


def test_a_restart_forgets_the_previous_runs_segments():
    _, records = run(SHORT)
    start = records[0]
    comparison = Comparison('paper')
    comparison.anchor(start)
    later = SegmentStart('r1', start.parameters_yaml, 1.0, 1, 0.1, 100_000_000, start.omega,
                         start.quaternion)
    comparison.anchor(later)
    assert comparison.compare_one(2_000_000, start.omega) is not None   # first segment kept
    comparison.anchor(SegmentStart('r2', start.parameters_yaml, 1.0, 0, 0.1, 100_000_000,
                                   start.omega, start.quaternion))
    assert comparison.compare_one(2_000_000, start.omega) is None       # a new run: forgotten


def test_the_session_and_the_comparison_load_no_ros():
    _assert_loads_none('import tumble_ros.runs.session, tumble_ros.runs.comparison, '
                       'tumble_ros.runs.records',
                       ('rclpy', 'rosidl', 'tumble_ros_interfaces', 'geometry_msgs',
                        'diagnostic_msgs', 'tumble_ros.nodes'))


def test_the_records_states_and_levels_are_the_messages_values():
    from diagnostic_msgs.msg import DiagnosticStatus
    from tumble_ros.runs import records
    from tumble_ros_interfaces.msg import SimStatus

    assert (records.RUNNING, records.PAUSED, records.FINISHED, records.DIVERGED) == (
        SimStatus.RUNNING, SimStatus.PAUSED, SimStatus.FINISHED, SimStatus.DIVERGED)
    assert (records.OK, records.WARN, records.ERROR) == (
        DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR)


# -- many impacts: linear in their number ---------------------------------------------------------
def _many_impacts(n, duration, seed=11):
    rng = np.random.default_rng(seed)
    return [Impact(float(s), 3e-7, tuple(rng.normal(size=3) * 1e2),
                   'orbital' if k % 3 == 0 else 'body')
            for k, s in enumerate(rng.uniform(0.0, duration - 0.01, n))]


def test_impacts_requested_in_any_order_and_batches_give_the_scenarios_run_bit_for_bit():
    impacts = _many_impacts(120, 2.0)
    scenario = Scenario(duration=2.0, output_interval=0.004, impacts=tuple(impacts))
    _, ref = run(scenario, batch=97)
    rng = np.random.default_rng(2)
    free = scenario.replace(impacts=())
    session = SimulationSession(free, output_grid(free, TimeBase()), run_id='r1')
    records = session.start()
    order = rng.permutation(len(impacts))
    for batch in np.split(order, [7, 40, 41, 90]):   # before the first batch of samples
        for k in batch:
            session.request_impact(impacts[k])
        session._schedule_pending()
    while session.state == RUNNING:
        records += session.advance(session.samples + 96)
    got, want = blocks(records), blocks(ref)
    for name in want:
        assert np.array_equal(got[name], want[name]), name
    ended = [r for r in records if isinstance(r, ImpactEnded)]
    assert [(e.impact, e.stamp_ns, e.delta_omega) for e in ended] == [
        (e.impact, e.stamp_ns, e.delta_omega) for e in ref if isinstance(e, ImpactEnded)]
    # every impact reported once, in the order of their ends (distinct starts, equal lengths)
    assert [e.impact for e in ended] == sorted(impacts, key=lambda i: i.start)


def test_descriptions_do_not_repeat_the_scheduled_impacts_and_are_parsed_once(monkeypatch):
    """
    Only the first description carries the scheduled impacts; each text is parsed once.

    The later descriptions are the scenario without its impacts (each would otherwise carry
    every impact: quadratic), and the comparison parses each distinct text once, not once per
    segment.
    """
    from tumble_ros.core import parse_scenario
    from tumble_ros.runs import comparison as comparison_module

    impacts = _many_impacts(60, 2.0)
    scenario = Scenario(duration=2.0, output_interval=0.004, impacts=tuple(impacts))
    _, records = run(scenario, batch=50)
    starts = [r for r in records if isinstance(r, SegmentStart)]
    assert [s.revision for s in starts] == list(range(61))
    assert parse_scenario(starts[0].parameters_yaml) == scenario
    assert parse_scenario(starts[1].parameters_yaml) == scenario.replace(impacts=())
    assert len({s.parameters_yaml for s in starts[1:]}) == 1
    assert len(starts[1].parameters_yaml) < len(starts[0].parameters_yaml) / 5
    parsed = []

    def counting(text):
        parsed.append(text)
        return parse_scenario(text)

    monkeypatch.setattr(comparison_module, 'parse_scenario', counting)
    comparison = Comparison('paper')
    statuses = [comparison.anchor(s) for s in starts]
    assert all(s.level == OK for s in statuses), statuses[0]
    assert len(parsed) == 2


def test_the_norms_of_rows_are_each_rows_norms_bit_for_bit():
    """error_norms_of_rows (the offline comparison's) against error_norms (the live one's)."""
    rng = np.random.default_rng(4)
    numeric = rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-300, 300, size=(500, 1))
    error = rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-300, 300, size=(500, 1))
    numeric[:3] = 0.0                                    # |numeric| = 0: relative inf
    numeric[3] = [np.nan, 1.0, 2.0]
    error[4] = [np.inf, 0.0, 0.0]
    norm, relative = error_norms_of_rows(numeric, error)
    each = [error_norms(a, b) for a, b in zip(numeric.tolist(), error.tolist())]
    assert norm.tolist() == [n for n, _ in each]
    assert np.array_equal(relative, [r for _, r in each], equal_nan=True)
    assert np.isinf(relative[:3]).all() and np.isinf(relative[3])
    empty = error_norms_of_rows(np.empty((0, 3)), np.empty((0, 3)))
    assert empty[0].shape == empty[1].shape == (0,)


def test_the_described_scenarios_are_what_their_texts_parse_to():
    """
    An in-process comparison takes SimulationSession.described instead of parsing the text.

    Each text its segment starts carry must parse to the scenario given for it, and a
    Comparison given them anchors exactly as one that parses (the offline run's shortcut).
    """
    from tumble_ros.core import parse_scenario

    scenario = SHORT.replace(impacts=(IMPACT,))
    session, records = run(scenario)
    starts = [r for r in records if isinstance(r, SegmentStart)]
    assert len({s.parameters_yaml for s in starts}) == 2 == len(session.described)
    for text, described in session.described.items():
        assert parse_scenario(text) == described
    assert {s.parameters_yaml for s in starts} == set(session.described)
    told, parsing = Comparison('paper', described=session.described), Comparison('paper')
    for start in starts:
        assert told.anchor(start) == parsing.anchor(start)
    assert told._parsed is None and parsing._parsed is not None   # told parsed nothing


def test_the_sample_gate_takes_the_runs_samples_and_drops_the_rest():
    """SampleGate: finite, strictly later, within the run's end; the rest counted by reason."""
    gate = SampleGate()
    assert gate.admit(0, (0.0, 0.0, 30.0), end_ns=100) is None
    assert gate.admit(10, (math.nan, 0.0, 30.0), end_ns=100) == 'not finite'
    assert gate.admit(10, (math.inf, 0.0, 30.0)) == 'not finite'
    assert gate.admit(0, (0.0, 0.0, 30.0)) == 'not after the last sample'
    assert gate.admit(101, (0.0, 0.0, 30.0), end_ns=100) == "after the run's end"
    assert gate.admit(100, (0.0, 0.0, 30.0), end_ns=100) is None
    assert gate.dropped == 4 and gate.text().startswith('dropped 4 samples')
    assert '2 not finite' in gate.text()
    gate.reset()
    assert gate.dropped == 0 and gate.text() == '' and gate.admit(0, (1.0, 2.0, 3.0)) is None

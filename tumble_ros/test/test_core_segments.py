"""
The one segment builder: cuts at every pulse edge, sums the pulses active on each segment.

And the one compiled stepper kept across a body's segments (the same trajectory as new ones).
"""
import numpy as np
import pytest

from tumble_ros.core import Impact, IntegratorSettings, kernels, Propagator, Scenario
from tumble_ros.core.integrators import INTEGRATORS, SegmentProblem
from tumble_ros.core.integrators.compiled import CompiledStepper
from tumble_ros.core.propagation import segments
from tumble_ros.core.propagation.segments import segment_torques, split_at_impacts


def test_overlapping_pulses_are_cut_at_every_edge_and_summed():
    a = Impact(0.1, 0.2, (1.0, 0.0, 0.0), 'body')
    b = Impact(0.2, 0.3, (0.0, 2.0, 0.0), 'orbital')
    c = Impact(0.15, 0.1, (0.0, 0.0, 4.0), 'body')
    segs = split_at_impacts(1.0, [c, b, a])  # any order in
    edges = [0.0, a.start, c.start, b.start, c.end, a.end, b.end, 1.0]  # 0.1 0.15 0.2 0.25 0.3 0.5
    assert [(s.t0, s.t1) for s in segs] == list(zip(edges[:-1], edges[1:]))
    assert segs[0].torque_body == (0.0, 0.0, 0.0)
    assert segs[2].torque_body == (1.0, 0.0, 4.0)                         # a and c
    assert segs[3].torque_body == (1.0, 0.0, 4.0) and segs[3].torque_orbital == (0.0, 2.0, 0.0)
    assert segs[4].torque_body == (1.0, 0.0, 0.0)                         # c ended at 0.25
    assert segs[5].torque_body == (0.0, 0.0, 0.0) and segs[5].torque_orbital == (0.0, 2.0, 0.0)
    assert segs[-1].torque_body == segs[-1].torque_orbital == (0.0, 0.0, 0.0)


def test_the_sweep_equals_a_scan_of_every_impact_bit_for_bit():
    rng = np.random.default_rng(3)
    impacts = [Impact(float(s), float(d), tuple(rng.normal(size=3) * 1e6), 'body')
               for s, d in zip(rng.uniform(0, 0.9, 200), rng.uniform(1e-7, 0.05, 200))]
    ordered = sorted(impacts, key=lambda i: i.start)
    for seg in split_at_impacts(1.0, impacts):
        assert (seg.torque_body, seg.torque_orbital) == segment_torques(ordered, seg.t0, seg.t1)


# -- impacts scheduled late: the segments re-split where they fall, the same bits -----------------
def _pulses(n, seed=5):
    """Return n pulses over [0, 1000] yr: short ones and a few long ones (overlapping many)."""
    rng = np.random.default_rng(seed)
    starts = rng.uniform(0.0, 990.0, n)
    durations = np.where(rng.uniform(size=n) < 0.05, rng.uniform(1.0, 8.0, n), 3e-7)
    frames = np.where(rng.uniform(size=n) < 0.3, 'orbital', 'body')
    return [Impact(float(s), float(d), tuple(rng.normal(size=3) * 1e3), str(f))
            for s, d, f in zip(starts, durations, frames)]


def test_impacts_scheduled_in_any_order_and_batches_give_the_single_batch_segments():
    pulses = _pulses(300)
    scenario = Scenario(duration=1000.0, output_interval=1.0, impacts=tuple(pulses))
    whole = Propagator(scenario).segments
    assert len(whole) > 2 * 300 - 10   # every pulse cuts (a few edges shared or at 0)
    # the reference: split_at_impacts over every pulse at once
    assert whole == tuple(split_at_impacts(1000.0, pulses))
    rng = np.random.default_rng(7)
    for trial in range(4):
        order = rng.permutation(len(pulses))
        cuts = np.sort(rng.choice(np.arange(1, len(pulses)), size=trial * 3, replace=False))
        prop = Propagator(scenario.replace(impacts=()))
        for batch in np.split(order, cuts):
            prop.schedule_many([pulses[k] for k in batch])
        # the same segments, bit for bit (distinct starts: the order of summation is by start)
        assert prop.segments == whole
    one_by_one = Propagator(scenario.replace(impacts=()))
    for k in rng.permutation(len(pulses)):
        one_by_one.schedule(pulses[k])
    assert one_by_one.segments == whole


def test_scheduling_impacts_one_by_one_builds_segments_linearly(monkeypatch):
    """
    Work counted, not timed: the Segment tuples built while scheduling n pulses one at a time.

    Re-splitting the whole run per impact (what the propagator did) built ~n^2 of them:
    80,000 for n = 200; the span re-split builds a few per impact.
    """
    built = []

    class Counted(segments.Segment):
        def __new__(cls, *args):
            built.append(1)
            return super().__new__(cls, *args)

    monkeypatch.setattr(segments, 'Segment', Counted)
    counts = {}
    for n in (200, 800):
        pulses = [p for p in _pulses(n, seed=n) if p.duration < 1.0]   # short pulses only
        prop = Propagator(Scenario(duration=1000.0, output_interval=1.0))
        built.clear()
        for pulse in pulses:
            prop.schedule(pulse)
        counts[n] = len(built) / len(pulses)
        assert len(prop.segments) == 2 * len(pulses) + 1
    # each short pulse re-splits the segment it falls in into three
    assert counts[200] <= 4 and counts[800] <= 4, counts


# -- one compiled stepper kept across a body's segments: the same trajectory bit for bit ----------
_SETTINGS = {'rk4': {'step': 1e-3}, 'dop853': {'rtol': 1e-10, 'atol': 1e-12},
             'splitting4': {'step': 2e-3}}
_needs_numba = pytest.mark.skipif(not kernels.COMPILED, reason='numba not available')


def _sampled(scenario, late, budget):
    """Sample the run on its output grid in budget-cut calls, ``late`` scheduled half-way."""
    prop = Propagator(scenario, fast=True)
    times = scenario.output_times
    half = len(times) // 2
    parts, k = [], 0
    while k < len(times):
        if k >= half and late:
            prop.schedule_many(late)
            late = ()
        stop = half if k < half else len(times)
        done, arrays, message = prop.sample_many(times[k:stop], budget=budget)
        assert not message
        parts.append(np.concatenate([arrays[name][:done].reshape(done, arrays[name][0].size)
                                     for name in ('omega', 'quaternion', 'euler', 'matrix')],
                                    axis=1))
        k += done
    return np.concatenate(parts), (prop.nfev, prop.n_steps, len(prop.segments))


@_needs_numba
@pytest.mark.parametrize('method', sorted(_SETTINGS))
def test_a_stepper_kept_across_segments_gives_fresh_steppers_trajectory_bit_for_bit(
        method, monkeypatch):
    # 40 pulses over 100 yr (some long, overlapping others), 10 of them scheduled half-way
    pulses = [Impact(p.start / 10.0, min(p.duration, 0.5), tuple(np.multiply(p.torque, 0.01)),
                     p.frame) for p in _pulses(40, seed=11)]
    scenario = Scenario(duration=100.0, output_interval=0.25, impacts=tuple(pulses[:30]),
                        integrator=IntegratorSettings(method=method, **_SETTINGS[method]))
    late = [Impact(p.start * 0.5 + 50.0, p.duration, p.torque, p.frame) for p in pulses[30:]]
    built = []
    counted = CompiledStepper.__init__

    def counting(self, *args, **kwargs):
        built.append(1)
        counted(self, *args, **kwargs)

    monkeypatch.setattr(CompiledStepper, '__init__', counting)
    kept, kept_counts = _sampled(scenario, late, budget=300)
    assert len(built) == 1    # one stepper for the whole run (2 per pulse restarted)
    monkeypatch.setattr(CompiledStepper, 'is_same_body', lambda self, problem: False)
    built.clear()
    fresh, fresh_counts = _sampled(scenario, late, budget=300)
    assert len(built) >= 2 * len(pulses)   # a new one per segment
    assert kept.tobytes() == fresh.tobytes()
    assert kept_counts == fresh_counts


@_needs_numba
def test_a_restarted_stepper_holds_what_a_new_one_holds():
    settings = IntegratorSettings(method='dop853', rtol=1e-10, atol=1e-12)
    first = SegmentProblem((1.0, 1.0, 4.0), 1.0, (1e3, 0.0, 0.0), (0.0, 0.0, 0.0))
    y0 = np.array([0.1, 0.1, 30.0, 1.0, 0.0, 0.0, 0.0])
    stepper = CompiledStepper(INTEGRATORS['dop853'], None, 0.0, y0, 0.5, settings, problem=first)
    stepper.advance(0.5, np.zeros(3))
    assert stepper.status == 'finished' and stepper.nfev > 0
    second = SegmentProblem((1.0, 1.0, 4.0), 1.0, (0.0, 0.0, 0.0), (0.0, 2e3, -1.0))
    y = stepper.y.copy()
    stepper.restart(0.5, y, 0.75, second)
    new = CompiledStepper(INTEGRATORS['dop853'], None, 0.5, y, 0.75, settings, problem=second)
    for name in ('_p', '_st', '_cfg', 'y'):
        assert getattr(stepper, name).tobytes() == getattr(new, name).tobytes(), name
    for name in ('t', 't0', 't_bound', 'tau', 'tau_bound', 't_old', 'status', 'message',
                 'n_steps', 'problem', 'nfev', '_budget', '_window_t', '_window_steps'):
        assert getattr(stepper, name) == getattr(new, name), name
    track_a, track_b = np.zeros(3), np.zeros(3)
    assert stepper.advance(0.75, track_a) == new.advance(0.75, track_b)
    assert stepper._st.tobytes() == new._st.tobytes() and track_a.tobytes() == track_b.tobytes()
    other_body = SegmentProblem((1.0, 2.0, 4.0), 1.0)
    with pytest.raises(ValueError, match='differs in more than its pulse torques'):
        stepper.restart(0.75, y, 1.0, other_body)

"""The one segment builder: cuts at every pulse edge, sums the pulses active on each segment."""
import numpy as np

from tumble_ros.core import Impact, Propagator, Scenario
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

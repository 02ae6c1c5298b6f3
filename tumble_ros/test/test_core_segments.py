"""The one segment builder: cuts at every pulse edge, sums the pulses active on each segment."""
import numpy as np

from tumble_ros.core import Impact
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

"""Simulated years <-> ROS stamps: exact recovery, int32 limits."""
import numpy as np
import pytest

from tumble_ros.core.model.timebase import MAX_STAMP_NS, TimeBase


@pytest.mark.parametrize('spy', [1.0, 0.001, 3600.0, 31557600.0 / 1e4])
def test_time_recovered_exactly_from_sec_nanosec(spy):
    tb = TimeBase(spy)
    interval_ns, n = tb.sample_grid(0.002, 10.0)
    for k in (0, 1, 7, n // 3, n - 1):
        ns = k * interval_ns
        sec, nanosec = divmod(ns, 1_000_000_000)
        assert tb.to_years(tb.stamp_ns(sec, nanosec)) == tb.to_years(ns)
        assert tb.to_ns(tb.to_years(ns)) == ns


def test_ten_thousand_years_fit_in_int32_seconds():
    tb = TimeBase(1.0)
    interval_ns, n = tb.sample_grid(0.01, 10_000.0)
    last = (n - 1) * interval_ns
    assert tb.to_years(last) == pytest.approx(10_000.0)
    assert last // 1_000_000_000 < 2**31
    assert last < 2**53  # integer ns still exact in float64


def test_span_past_int32_is_refused_with_a_reason():
    with pytest.raises(ValueError, match='int32'):
        TimeBase(3.15576e7).check_span(10_000.0)  # real seconds per year: 3e11 s
    TimeBase(1.0).check_span(MAX_STAMP_NS / 1e9)


@pytest.mark.parametrize('bad', [0.0, -1.0, float('nan'), float('inf'), True])
def test_bad_scale_refused(bad):
    with pytest.raises(ValueError, match='seconds_per_year'):
        TimeBase(bad)


def test_grid_is_rounded_to_whole_nanoseconds():
    interval_ns, n = TimeBase(1.0).sample_grid(1.4e-9, 1e-8)
    assert interval_ns == 1 and n == 11
    assert np.isclose(TimeBase(2.0).sample_grid(0.5, 2.0)[0], 1e9)
    with pytest.raises(ValueError, match='^output_interval:.*1 ns'):  # below a nanosecond: refused
        TimeBase(1.0).sample_grid(1e-10, 1e-8)


# (seconds_per_year = 0.01: 1e-7 yr is 1 ns, and a grid over 0.3 yr has 3e6 samples, within
# MAX_SAMPLES)
@pytest.mark.parametrize('duration', [0.3, 0.29999999999999999, 0.1 + 0.2, 2.0 / 3.0, 1e-7 * 7])
def test_grid_never_passes_the_end(duration):
    tb = TimeBase(0.01)
    interval_ns, n = tb.sample_grid(1e-7, duration)
    assert interval_ns == 1
    assert tb.to_years((n - 1) * interval_ns) <= duration < tb.to_years(n * interval_ns)


@pytest.mark.parametrize('spy', [1.0, 3.0, 0.01])
def test_the_grid_object_gives_the_stamps_times_of_sample_grid(spy):
    tb = TimeBase(spy)
    interval_ns, n = tb.sample_grid(0.0013, 0.7)
    grid = tb.grid(0.0013, 0.7)
    assert (grid.interval_ns, grid.count) == (interval_ns, n)
    times = grid.times()
    assert times.tolist() == [tb.to_years(k * interval_ns) for k in range(n)]  # bit for bit
    assert grid.times(3, 7).tolist() == times[3:7].tolist()
    assert grid.time(n - 1) == times[-1] <= 0.7
    assert grid.index_of(grid.stamp(5)) == 5
    assert grid.index_of(grid.stamp(5) + 1) is None and grid.index_of(grid.stamp(n)) is None


def test_scenario_output_times_are_the_node_grid_at_one_second_per_year():
    """simulate()'s default grid is the one the sim node publishes (one grid, not two)."""
    from tumble_ros.core import Scenario

    for interval, duration in [(0.002, 2.0), (0.01, 2000.0), (1e-4, 0.3), (0.1 + 0.2, 0.9)]:
        sc = Scenario(output_interval=interval, duration=duration)
        grid = TimeBase(1.0).grid(interval, duration)
        assert sc.output_times.tolist() == grid.times().tolist()
        assert sc.output_times[-1] <= duration


def test_a_core_output_interval_below_a_nanosecond_is_refused_naming_t_eval():
    from tumble_ros.core import Scenario, ScenarioError

    with pytest.raises(ScenarioError, match=r'^output_interval:.*1 ns.*t_eval'):
        Scenario(duration=1e-6, output_interval=1e-10)

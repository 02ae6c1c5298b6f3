"""
A recording read as a viewer reads it: its timeline, each channel's log times, the markers.

A viewer (Foxglove, Lichtblick, ``ros2 bag play``) places, plays and seeks messages by their
log time and shows a topic's rate as its count over the timeline, which runs from the first log
time to the last (the summary's statistics). :func:`check_timeline` asserts what the
recordings promise (runs/offline.py, nodes/recorder.py): the timeline is the simulated span on
the ROS clock (the ``seconds_per_year`` mapping of the recording's own ``scenario``), every
channel's log times are non-decreasing, each message is logged at the stamp of the sample it
belongs to, and the scenes (``markers``) are spread over the whole timeline.
"""
from __future__ import annotations

from dataclasses import dataclass

from mcap.reader import make_reader
import numpy as np

from tumble_ros import topics
from tumble_ros.core import TimeBase
from tumble_ros.io import read_messages

#: Topics whose messages carry the stamp of their sample in ``header.stamp``.
STAMPED = [topics.in_namespace('/', t) for t in (
    *topics.PER_SAMPLE, topics.PERTURBER, topics.SCENARIO, topics.IMPACT_EVENTS, topics.STATUS)]
MARKERS = '/' + topics.MARKERS
CLOCK = topics.CLOCK


@dataclass
class Timeline:
    """What a viewer shows of a recording's time: the span and each topic's log times [ns]."""

    start: int
    end: int
    log_times: dict[str, np.ndarray]
    stamps: dict[str, np.ndarray]       # the stamp each message carries (see STAMPED)
    seconds_per_year: float

    def rate(self, topic: str) -> float:
        """Return the topic's rate as a viewer shows it [Hz of the timeline]."""
        return len(self.log_times[topic]) / ((self.end - self.start) / 1e9)


def _stamp(message) -> int | None:
    if hasattr(message, 'header'):
        return TimeBase.stamp_ns(message.header.stamp.sec, message.header.stamp.nanosec)
    if hasattr(message, 'clock'):
        return TimeBase.stamp_ns(message.clock.sec, message.clock.nanosec)
    if hasattr(message, 'markers'):
        stamps = {TimeBase.stamp_ns(m.header.stamp.sec, m.header.stamp.nanosec)
                  for m in message.markers}
        assert len(stamps) == 1, stamps    # one scene, one sample
        return stamps.pop()
    return None


def timeline(path) -> Timeline:
    """Read ``path``'s timeline from its summary and its messages in file order."""
    with open(path, 'rb') as f:
        statistics = make_reader(f).get_summary().statistics
    log_times: dict[str, list[int]] = {}
    stamps: dict[str, list[int]] = {}
    seconds_per_year = None
    for m in read_messages(path):
        log_times.setdefault(m.topic, []).append(m.log_time_ns)
        stamp = _stamp(m.message)
        if stamp is not None:
            stamps.setdefault(m.topic, []).append(stamp)
        if m.topic == '/' + topics.SCENARIO:
            seconds_per_year = m.message.seconds_per_year
    return Timeline(statistics.message_start_time, statistics.message_end_time,
                    {t: np.array(v, dtype=np.int64) for t, v in log_times.items()},
                    {t: np.array(v, dtype=np.int64) for t, v in stamps.items()},
                    seconds_per_year)


def check_timeline(path, duration: float, interval: float,
                   seconds_per_year: float = 1.0) -> Timeline:
    """
    Assert that ``path`` plays in simulated time; return its timeline.

    ``path``: a run of ``duration`` years with samples every ``interval`` years, stamped at
    ``seconds_per_year`` ROS seconds a year.
    """
    t = timeline(path)
    assert t.seconds_per_year == seconds_per_year
    grid = TimeBase(seconds_per_year).grid(interval, duration)
    # the timeline: sample 0 to the last sample (ROS time), within one sample
    assert t.start == 0
    assert abs(t.end - grid.stamp(grid.count - 1)) <= grid.interval_ns, (t.end, grid)
    for topic, times in t.log_times.items():
        assert np.all(np.diff(times) >= 0), f'{topic}: log times go back'
    for topic in STAMPED + [CLOCK, MARKERS]:
        if topic in t.log_times:
            np.testing.assert_array_equal(t.log_times[topic], t.stamps[topic], err_msg=topic)
    for topic in (topics.in_namespace('/', name) for name in topics.SIM_PER_SAMPLE):
        np.testing.assert_array_equal(
            t.log_times[topic], np.arange(grid.count, dtype=np.int64) * grid.interval_ns)
    # the scenes: from the first sample to the last, none further apart than the decimation
    scenes = t.log_times[MARKERS]
    assert scenes[0] == 0 and scenes[-1] == t.end
    assert np.diff(scenes).max() <= (t.end - t.start) / 100
    return t

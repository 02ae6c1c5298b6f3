"""
Offline recordings read as a viewer reads them: they play in the run's own time.

The default run (``make run``) and the Apophis flyby (hours: one ROS second per hour) written
by ``bringup --offline``; the run with an impact, live and offline, is in test_offline.py, live
runs at another ``seconds_per_year`` and with ``log_time:=receive`` in test_node_recorder.py.
"""
from pathlib import Path

import numpy as np
import pytest

from tumble_ros import topics
from tumble_ros.core import load_scenario
from tumble_ros.nodes.bringup import run_bringup
from viewer_checks import check_timeline

CONFIG = Path(__file__).resolve().parents[1] / 'config'
OMEGA = '/' + topics.ANGULAR_VELOCITY


def test_the_default_run_plays_two_seconds_one_a_year(tmp_path):
    result = run_bringup(str(CONFIG / 'default.yaml'), str(tmp_path / 'default.mcap'),
                         progress=None, offline=True)
    assert result.ok and result.samples == 1001
    t = check_timeline(result.output, 2.0, 0.002)
    # the viewer's numbers: a 2 s timeline, 1,001 samples at 500 Hz (one every 2 ms = 0.002 yr)
    assert t.end - t.start == 2_000_000_000
    assert t.rate(OMEGA) == pytest.approx(500.5)
    status = t.log_times['/' + topics.STATUS]
    assert status[0] == 0 and status[-1] == t.end      # 'started', then 'finished' at the end


def test_the_flyby_plays_144_seconds_one_an_hour(tmp_path):
    scenario = load_scenario(CONFIG / 'apophis_2029.yaml')
    hours = 8766.0        # the file's time_unit h: one ROS second per hour (seconds_per_year 0)
    result = run_bringup(str(CONFIG / 'apophis_2029.yaml'), str(tmp_path / 'flyby.mcap'),
                         progress=None, offline=True)
    assert result.ok and result.samples == 2881
    t = check_timeline(result.output, scenario.duration, scenario.output_interval, hours)
    assert t.end - t.start == 144 * 10**9
    np.testing.assert_array_equal(t.log_times['/' + topics.PERTURBER], t.log_times[OMEGA])

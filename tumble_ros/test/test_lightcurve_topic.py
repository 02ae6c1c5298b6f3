"""
The ``lightcurve`` topic: published live, written offline, decoded, alike.

The live simulator publishes what a telescope sees at each sample, the offline writer records
the same messages, the columnar reader decodes them; the three agree with each other and with
``core.photometry.synthetic_lightcurve`` on ``simulate()``'s attitudes, computed here. A body
that no mass distribution has, and a run with ``lightcurve.enabled`` false, publish no
lightcurve and have no such channel.
"""
import numpy as np

from tumble_ros import topics
from tumble_ros.core import Scenario, simulate
from tumble_ros.core.photometry import LightcurveSettings, synthetic_lightcurve
from tumble_ros.io import read_columns, sample_values
from tumble_ros.nodes.sim import SimNode
from tumble_ros.runs.offline import record_offline
from tumble_ros_interfaces.msg import Lightcurve, SimStatus

SHORT = {'duration': 0.2, 'output_interval': 0.002}
COUNT = 101                       # 0, 0.002, ..., 0.2 yr
LIGHTCURVE = topics.sample_topic(topics.LIGHTCURVE)
FIELDS = LIGHTCURVE.fields


def _values(msgs) -> np.ndarray:
    return np.array([[getattr(m, name) for name in FIELDS] for m in msgs])


def _stamps(msgs) -> np.ndarray:
    return np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
                     for m in msgs], dtype=np.int64)


def test_the_lightcurve_is_published_live_written_offline_and_decoded_alike(ros, tmp_path):
    params = {'lightcurve.law': 'lambert', 'lightcurve.observer': [0.0, 0.0, 1.0]}
    live = ros.collect(Lightcurve, topics.LIGHTCURVE)
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = ros.start(SimNode, real_time_factor=0.0, **SHORT, **params)
    assert topics.LIGHTCURVE in sim.per_sample_topics
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)
    assert ros.spin_until(lambda: len(live) == COUNT, 5.0), len(live)
    assert {m.header.frame_id for m in live} == {topics.FRAME_BODY}
    scenario = Scenario.from_parameters({**SHORT, **params})
    path = tmp_path / 'offline.mcap'
    result = record_offline(scenario, path, markers=False)
    assert result.state == SimStatus.FINISHED and result.counts[f'/{topics.LIGHTCURVE}'] == COUNT
    columns, _ = read_columns(path, [f'/{topics.LIGHTCURVE}'])
    table = columns[f'/{topics.LIGHTCURVE}']
    assert table.type_name == LIGHTCURVE.type_name and table.columnar == COUNT
    stamps, decoded = sample_values(table, LIGHTCURVE)
    np.testing.assert_array_equal(_stamps(live), stamps)
    np.testing.assert_array_equal(_values(live), decoded)
    # what the core computes on simulate()'s attitudes at the same times
    run = simulate(scenario)
    record = synthetic_lightcurve(scenario, run.t, run.quaternion,
                                  LightcurveSettings(law='lambert', observer=(0.0, 0.0, 1.0)))
    expected = np.column_stack([record.brightness, record.magnitude, record.phase_angle,
                                record.sun_aspect, record.observer_aspect, record.light_time])
    np.testing.assert_allclose(decoded, expected, rtol=1e-9, atol=1e-12)
    # the Sun turns in the orbit plane, the observer sits on its pole: phase 90 deg
    np.testing.assert_allclose(decoded[:, 2], np.pi / 2.0, rtol=1e-12)
    assert np.ptp(decoded[:, 0]) > 0.01 * decoded[:, 0].max()    # the body turns


def test_no_body_or_no_lightcurve_wanted_means_no_topic(tmp_path):
    for name, scenario in (
            ('unphysical', Scenario(inertia=(1.0, 1.0, 3.0), allow_unphysical_inertia=True,
                                    **SHORT)),
            ('disabled', Scenario(lightcurve=LightcurveSettings(enabled=False), **SHORT))):
        result = record_offline(scenario, tmp_path / f'{name}.mcap', markers=False)
        assert result.state == SimStatus.FINISHED
        assert f'/{topics.LIGHTCURVE}' not in result.counts, name
        assert result.counts[f'/{topics.ANGULAR_VELOCITY}'] == COUNT


def test_the_unphysical_body_publishes_no_lightcurve_live(ros):
    status = ros.collect(SimStatus, topics.STATUS, latched=True)
    sim = ros.start(SimNode, real_time_factor=0.0, inertia=[1.0, 1.0, 3.0],
                    allow_unphysical_inertia=True, **SHORT)
    assert topics.LIGHTCURVE not in sim.per_sample_topics
    assert topics.ANGULAR_VELOCITY in sim.per_sample_topics
    assert ros.spin_until(lambda: status and status[-1].state == SimStatus.FINISHED, 20.0)

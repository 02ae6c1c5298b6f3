"""
The accepted solutions through the 2029 flyby (tumble_ros.inversion.flyby; issue 49).

A model carried torque-free to the Apophis scenario's start keeps its periods and L (conserved
without torque: an independent check of the carrying), and the flyby then changes them.
"""
import math

import numpy as np
import pytest

from tumble_ros.core.model.rotation import euler_to_quaternion
from tumble_ros.core.model.scenario import load_scenario
from tumble_ros.core.model.shipped import shipped_scenario
from tumble_ros.core.model.spinstate import spin_state
from tumble_ros.core.propagation.ensemble import simulate_ensemble
from tumble_ros.core.units import HOURS_PER_YEAR
from tumble_ros.inversion.flyby import flyby_ensemble, state_at
from tumble_ros.inversion.model import ModelError, TumblerParameters

NOMINAL = TumblerParameters.of('SAM', 27.38, 263.0, (0.64, 0.97),
                               (math.radians(246.8), math.radians(-59.3)), (0.5, 1.0))
OTHER = TumblerParameters.of('SAM', 27.40, 265.0, (0.62, 0.965),
                             (math.radians(250.0), math.radians(-55.0)), (1.5, 2.0))
EPOCH = 2462237.4069444444 - 30.0          # 30 d before the scenario's start


def test_a_state_carried_torque_free_keeps_its_periods_and_l():
    inertia, omega, euler = state_at(NOMINAL, EPOCH, EPOCH + 30.0)
    state = spin_state(omega, inertia, euler_to_quaternion(*euler))
    assert state.precession_period * HOURS_PER_YEAR == pytest.approx(27.38, rel=1e-8)
    assert state.rotation_period * HOURS_PER_YEAR == pytest.approx(263.0, rel=1e-8)
    assert state.pole_longitude % (2 * math.pi) == pytest.approx(math.radians(246.8), abs=1e-8)
    assert state.pole_latitude == pytest.approx(math.radians(-59.3), abs=1e-8)
    with pytest.raises(ModelError, match='start_jd'):
        state_at(NOMINAL, EPOCH, EPOCH - 1.0)


def test_the_flyby_changes_the_spin_state_of_every_model():
    scenario = load_scenario(shipped_scenario('apophis_2029'))
    calls = []

    def run(body, **kwargs):
        calls.append(kwargs['omega0'].shape[0])
        return simulate_ensemble(body, **kwargs)
    outcome = flyby_ensemble(scenario, [NOMINAL, OTHER], EPOCH, run=run)
    assert outcome.success.all() and sorted(calls) == [1, 1]      # two inertias, two groups
    for model, before, after in zip(outcome.models, outcome.before, outcome.after):
        p_phi = model.spin.precession_period
        assert before.precession_period == pytest.approx(p_phi, rel=1e-7)
        # the Earth's tidal torque at 38,000 km: the periods move by far more than 1e-7
        assert abs(after.precession_period / before.precession_period - 1.0) > 1e-4
        assert np.isfinite(after.rotation_period)

"""Failures stop the integration with a status; no NaN is ever returned."""
import numpy as np
import pytest

from tumble_ros.core import (Impact, IntegrationError, IntegratorSettings, Propagator, Scenario,
                             simulate)

pytestmark = pytest.mark.filterwarnings('ignore::RuntimeWarning')  # overflow is the point here


#: An absurd torque pulse (|omega0| is bounded, impact torques need only be finite): the state
#: overflows within the first step.
KICK = (Impact(0.0, 0.5, (1e300, 1e300, 1e300)),)


def test_step_size_collapse_is_reported():
    # A state overflowing with a tolerance it cannot meet in float64: the step control gives up.
    sc = Scenario(inertia=(1.0, 1.6, 2.2), impacts=KICK, duration=1.0,
                  integrator=IntegratorSettings(method='rk45', rtol=1e-13, atol=1e-300))
    r = simulate(sc, t_eval=[0.0, 0.5, 1.0])
    assert not r.success and r.message
    assert np.all(np.isfinite(r.omega))


def test_overflow_is_reported_by_a_fixed_step_method():
    sc = Scenario(inertia=(1.0, 1.6, 2.2), impacts=KICK, duration=1.0,
                  integrator=IntegratorSettings(method='rk4', step=0.1))
    r = simulate(sc, t_eval=[0.0, 0.5, 1.0])
    assert not r.success and 'non-finite' in r.message
    assert len(r.t) >= 1 and np.all(np.isfinite(r.omega))


def test_failed_propagator_stays_failed():
    sc = Scenario(inertia=(1.0, 1.6, 2.2), impacts=KICK, duration=1.0,
                  integrator=IntegratorSettings(method='rk4', step=0.1))
    prop = Propagator(sc)
    with pytest.raises(IntegrationError):
        prop.advance_to(1.0)
    assert prop.status == 'failed'
    with pytest.raises(IntegrationError):
        prop.advance_to(1.0)

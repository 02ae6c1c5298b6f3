"""The integrator interface, the registry and rk4's order of convergence."""
import numpy as np
import pytest

from tumble_ros.core import IntegratorSettings, METHODS, Scenario, simulate
from tumble_ros.core.integrators import FAILED, FINISHED, Stepper


def test_registry_names_and_capabilities():
    assert set(METHODS) == {'rk4', 'rk45', 'dop853', 'radau', 'bdf', 'lsoda', 'adams'}
    for name, cls in METHODS.items():
        assert issubclass(cls, Stepper) and cls.name == name
    assert METHODS['rk4'].adaptive is False
    assert all(METHODS[n].adaptive for n in METHODS if n != 'rk4')


@pytest.mark.parametrize('method', sorted(METHODS))
def test_stepper_lands_on_t_bound_and_dense_output_is_accurate(method):
    settings = IntegratorSettings(method=method, rtol=1e-10, atol=1e-12, step=1e-3)
    st = METHODS[method](lambda t, y: np.array([y[1], -y[0]]), 0.0, [1.0, 0.0], 2.345, settings)
    errors = []
    while st.status != FINISHED:
        st.step()
        for s in np.linspace(st.t_old, st.t, 4):
            errors.append(abs(st.state_at(s)[0] - np.cos(s)))
    assert st.t == 2.345
    assert max(errors) < 1e-7
    assert st.nfev > 0


@pytest.mark.parametrize('method', ['rk4', 'dop853', 'adams'])
def test_nonfinite_state_is_a_failure_not_output(method):
    settings = IntegratorSettings(method=method, step=1e-2)
    with np.errstate(over='ignore', invalid='ignore'):
        st = METHODS[method](lambda t, y: y * y, 0.0, [1.0], 2.0, settings)  # blows up at t = 1
        while st.status not in (FAILED, FINISHED):
            st.step()
    assert st.status == FAILED and st.message
    assert 0.9 < st.t < 1.1 and np.all(np.isfinite(st.y))


def test_rk4_converges_at_fourth_order():
    sc = Scenario(inertia=(1.0, 1.2, 1.5), omega0=(0.5, 1.0, 10.0), euler0=(0.5, 0.0, 0.5),
                  duration=1.0, output_interval=1.0)
    ref = simulate(sc.replace(integrator=IntegratorSettings(method='dop853', rtol=1e-13,
                                                            atol=1e-14)))
    errors = []
    for step in (4e-3, 2e-3, 1e-3):
        r = simulate(sc.replace(integrator=IntegratorSettings(method='rk4', step=step)))
        errors.append(np.linalg.norm(r.omega[-1] - ref.omega[-1]))
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(12.0 < q < 20.0 for q in ratios), (errors, ratios)

"""
The registry of compiled methods (core/kernels/methods.py): a new method is one module, one line.

An extra method (the explicit midpoint rule, tumble_ros/test/midpoint_kernel.py) registered
with the one line of ``kernels.KERNELS`` runs through simulate()'s compiled loop and the
ensemble loop, converges with its order 2 against the closed form of the torque-free
symmetric top, and gives the numbers of its reference stepper (a plain numpy midpoint rule).
"""
import midpoint_kernel
import numpy as np
import pytest
from test_core_free_body import symmetric_top_omega  # the closed form, written once

from tumble_ros.core import (IntegratorSettings, kernels, Propagator, Scenario, simulate,
                             simulate_ensemble)
from tumble_ros.core.integrators import INTEGRATORS
from tumble_ros.core.integrators.fixed_step import RK4

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')
INERTIA = (1.0, 1.0, 1.5)
OMEGA0 = (0.3, 1.0, 3.0)


class Midpoint(RK4):
    """The explicit midpoint rule: the reference path of the test's compiled method."""

    name = 'midpoint'
    order = 2
    kernel = 'midpoint'

    def _step_impl(self):
        h, tau, y = self._h, self.tau, self.y
        k1 = self.local_fun(tau, y)
        k2 = self.local_fun(tau + 0.5 * h, y + (0.5 * h) * k1)
        self._nfev += 2
        self._y_old, self.y = y, y + h * k2
        self.tau_old = tau
        self.tau = (self.tau_bound if self.n_steps + 1 >= self._n_total
                    else (self.n_steps + 1) * h)
        return True, ''

    def _state_at_impl(self, tau):
        s = (tau - self.tau_old) / (self.tau - self.tau_old)
        return (1.0 - s) * self._y_old + s * self.y


@pytest.fixture
def midpoint(monkeypatch):
    """Register the midpoint method: its kernel (the one registry line) and its Stepper."""
    monkeypatch.setitem(kernels.KERNELS, 'midpoint', midpoint_kernel)  # the registry line
    monkeypatch.setitem(INTEGRATORS, 'midpoint', Midpoint)
    return 'midpoint'


def top(method, step):
    return Scenario(inertia=INERTIA, orbit_rate=0.0, omega0=OMEGA0, euler0=(0.5, 0.2, 0.7),
                    duration=2.0, output_interval=0.25,
                    integrator=IntegratorSettings(method=method, step=step))


def error(result):
    assert result.success, result.message
    return np.max(np.abs(result.omega - symmetric_top_omega(result.t, INERTIA, OMEGA0)))


def observed_order(errors, steps):
    return np.log(errors[0] / errors[1]) / np.log(steps[0] / steps[1])


@needs_numba
def test_a_registered_method_runs_compiled_with_its_order(midpoint):
    steps = (2e-3, 1e-3)
    assert Propagator(top(midpoint, steps[0])).fast  # the compiled loop, not the reference
    errors = [error(simulate(top(midpoint, h))) for h in steps]
    assert 1.9 <= observed_order(errors, steps) <= 2.1, errors
    # the same for rk4 (order 4) through the same loops: each method gets its own step
    rk4 = [error(simulate(top('rk4', h))) for h in (2e-2, 1e-2)]
    assert 3.8 <= observed_order(rk4, (2e-2, 1e-2)) <= 4.2, rk4
    assert kernels.loops(midpoint).advance.signatures  # its own loop was compiled


@needs_numba
def test_a_registered_method_gives_its_reference_steppers_numbers(midpoint):
    sc = top(midpoint, 1e-3)
    fast, ref = simulate(sc), simulate(sc, fast=False)
    assert fast.success and ref.success
    assert fast.n_steps == ref.n_steps == 2000
    np.testing.assert_allclose(fast.omega, ref.omega, rtol=0, atol=1e-13)
    np.testing.assert_allclose(fast.quaternion, ref.quaternion, rtol=0, atol=1e-13)


@needs_numba
def test_a_registered_method_runs_in_the_ensemble_loop(midpoint):
    sc = top(midpoint, 1e-3)
    single = simulate(sc)
    many = simulate_ensemble(sc, n_bodies=3)
    assert many.success.all()
    for b in range(3):
        np.testing.assert_array_equal(many.omega[b], single.omega)
    assert kernels.loops(midpoint).ensemble_advance.signatures


def test_the_registry_numbers_its_methods_and_refuses_others():
    assert list(kernels.KERNELS) == ['rk4', 'dop853', 'splitting']
    assert [kernels.kernel_id(k) for k in kernels.KERNELS] == [1, 2, 3]
    cfg = kernels.config_array('dop853', IntegratorSettings(method='dop853'))
    assert kernels.kernel_name(cfg) == 'dop853'
    with pytest.raises(KeyError, match="no compiled method 'midpoint'"):
        kernels.kernel_id('midpoint')

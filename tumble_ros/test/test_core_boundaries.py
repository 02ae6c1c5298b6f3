"""
Inputs at and beyond the validated ranges, and the bounded work of every call.

Out-of-range fields are refused at the boundary (Scenario, IntegratorSettings, Impact,
TimeBase) with a ScenarioError naming the field; inputs that used to hang the simulator
(a NaN step size, a step far too long for the spin, a run of 1e10 steps sampled in one call)
now end, each in a subprocess with a timeout so that a regression fails instead of hanging
pytest. ``Propagator.sample_many`` returns early with partial progress (message "") when its
work budget is spent, and calling again gives the same samples, bit for bit.
"""
import json
import math
import os
import re
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from tumble_ros.core import (Impact, IntegratorSettings, kernels, Propagator, Scenario,
                             ScenarioError, simulate, TimeBase)
from tumble_ros.core.model.scenario import time_resolution
from tumble_ros.core.propagation.propagator import FAST_WORK_BUDGET, REFERENCE_WORK_BUDGET

needs_numba = pytest.mark.skipif(not kernels.COMPILED,
                                 reason='numba not available: only the reference path runs')
#: Generous: a subprocess imports numpy/scipy and may load the compiled loops (~1 s, or ~15 s
#: when numba recompiles them); the computations themselves take well under a second.
TIMEOUT = 300


def run_python(code: str, *args: str) -> dict:
    """
    Run ``code`` in a fresh interpreter and return its last stdout line, as JSON.

    A computation that does not end fails the test after TIMEOUT seconds instead of hanging it.
    """
    try:
        done = subprocess.run([sys.executable, '-c', code, *args], capture_output=True,
                              text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f'did not return within {TIMEOUT} s (a computation that never ends)')
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


# -- validated ranges ---------------------------------------------------------------------
REFUSED = [
    # 3 ws^2 = inf: the right-hand side was NaN and dop853's step-size loop never ended
    ({'orbit_rate': 1e300}, 'orbit_rate'),
    ({'orbit_rate': 2e6}, 'orbit_rate'),
    ({'orbit_rate': 1e-12}, 'orbit_rate'),
    ({'omega0': (0.0, 0.0, 2e10)}, 'omega0'),
    ({'duration': 1e300}, 'duration'),
    ({'duration': 2e9, 'output_interval': 1e3}, 'duration'),
    ({'omega0': (0.0, 0.0, 1e9), 'duration': 100.0, 'output_interval': 1.0},
     'duration'),  # 1e11 rad
    ({'orbit_rate': 1e6, 'duration': 1e5, 'output_interval': 100.0}, 'duration'),
    ({'duration': 1e4, 'output_interval': 1e-4}, 'output_interval'),  # 1e8 samples
    # below the float64 resolution: numba's step count wrapped round to one step over the run
    ({'integrator': IntegratorSettings(method='rk4', step=1e-20)}, 'integrator.step'),
    ({'integrator': IntegratorSettings(method='splitting6', step=1e-11)},
     'integrator.step'),  # 2e11 steps
    # 1e9 steps, but a step from t = 0 is measured against ulp(1) by the collapse test: this run
    # failed with "step size collapsed" at its first step
    ({'duration': 1e-6, 'output_interval': 1e-6,
      'integrator': IntegratorSettings(method='rk4', step=1e-15)}, 'integrator.step'),
    ({'integrator': IntegratorSettings(method='dop853', max_step=1e-20)}, 'integrator.max_step'),
]


@pytest.mark.parametrize('changes,field', REFUSED)
def test_out_of_range_scenario_fields_are_refused_naming_them(changes, field):
    with pytest.raises(ScenarioError, match=f'^{re.escape(field)}:'):
        Scenario(**changes)
    with pytest.raises(ScenarioError, match=f'^{re.escape(field)}:'):  # as ROS parameters too
        params = Scenario().to_parameters()
        for key, value in changes.items():
            if key == 'integrator':
                params.update({f'integrator.{k}': getattr(value, k)
                               for k in ('method', 'step', 'max_step')})
            else:
                params[key] = list(value) if isinstance(value, tuple) else value
        Scenario.from_parameters(params)


def test_the_bounds_themselves_are_accepted_and_just_beyond_refused():
    for ws in (0.0, 1e-9, 1e6):
        Scenario(orbit_rate=ws)
    Scenario(omega0=(0.0, 0.0, 1e10), duration=1.0, output_interval=0.5)  # 1e10 rad exactly
    Scenario(duration=1.0, output_interval=0.5,
             integrator=IntegratorSettings(method='rk4', step=1e-10))  # 1e10 steps exactly
    # a fixed step that an adaptive method ignores is not checked
    Scenario(integrator=IntegratorSettings(method='dop853', step=1e-20))
    Scenario(duration=1e9, output_interval=1e3, orbit_rate=1.0, omega0=(0.0, 0.0, 1.0))
    IntegratorSettings(atol=0.1)
    for atol in (1e300, 0.11):
        with pytest.raises(ScenarioError, match='^integrator.atol:'):
            IntegratorSettings(atol=atol)
    with pytest.raises(ScenarioError, match='^omega0:'):
        Scenario(omega0=(0.0, 0.0, 1.0000001e10), duration=1.0, output_interval=0.5)


def test_an_impact_shorter_than_the_time_resolution_is_refused():
    # start + 1e-17 == start in float64: accepted before, and applied as no pulse (delta w = 0)
    assert 1.0 + 1e-17 == 1.0
    with pytest.raises(ScenarioError, match='^impact.duration:.*resolution'):
        Impact(1.0, 1e-17, (1e9, 0.0, 0.0))
    with pytest.raises(ScenarioError, match=r'^impacts\[0\]\.duration:'):
        Scenario.from_parameters({'impacts.start': [1.0], 'impacts.duration': [1e-17],
                                  'impacts.torque': [1e9, 0.0, 0.0]})
    with pytest.raises(ScenarioError, match='^impact.duration:'):  # the resolution grows with t
        Impact(1000.0, 1e-12, (1.0, 0.0, 0.0))
    # just above the resolution the pulse is applied in full: delta w = M dt / I
    dt = 2 * time_resolution(1.0)
    sc = Scenario(orbit_rate=0.0, omega0=(0.0, 0.0, 1.0), duration=2.0, output_interval=1.0,
                  impacts=(Impact(1.0, dt, (0.0, 0.0, 1e12)),))
    r = simulate(sc, t_eval=[0.0, 2.0])
    dt_float = (1.0 + dt) - 1.0  # the pulse as float64 edges carry it
    assert r.success and r.omega[-1, 2] - 1.0 == pytest.approx(1e12 * dt_float / 1.5, rel=1e-6)


def test_timebase_refuses_grids_that_ros_stamps_cannot_carry():
    # 1e300 yr has no integer stamp: this was an OverflowError traceback at start-up
    with pytest.raises(ScenarioError, match='^duration:.*int32'):
        TimeBase(1.0).check_span(1e300)
    with pytest.raises(ScenarioError, match='^duration:'):
        TimeBase(1.0).sample_grid(0.002, math.inf)
    assert issubclass(ScenarioError, ValueError)  # the nodes' runner reports it, no traceback
    # below 1 ns of ROS time: was silently rounded to 1 ns (ten times the requested interval)
    with pytest.raises(ScenarioError, match='^output_interval:.*1 ns'):
        TimeBase(1.0).sample_grid(1e-10, 1e-8)
    # the same interval in years is fine or not depending on seconds_per_year
    assert TimeBase(1.0).sample_grid(1e-7, 0.5) == (100, 5_000_001)
    with pytest.raises(ScenarioError, match='^output_interval:.*seconds_per_year = 0.001'):
        TimeBase(1e-3).sample_grid(1e-7, 0.5)
    with pytest.raises(ScenarioError, match='^output_interval:.*samples'):  # 1e8 samples
        TimeBase(1.0).sample_grid(1e-6, 100.0)


# -- no call runs unbounded -----------------------------------------------------------------
_NAN_STEP = r"""
import json
import numpy as np
from tumble_ros.core import IntegratorSettings, kernels
from tumble_ros.core.model.dynamics import ATTITUDE_MODELS
from tumble_ros.core.integrators import INTEGRATORS, SegmentProblem
from tumble_ros.core.integrators.compiled import CompiledStepper
# Below the Scenario's validation: ws = 1e300 makes 3 ws^2 infinite and the right-hand side
# NaN, so the adaptive methods' first step size is NaN.
inertia, ws = (1.0, 1.0, 1.5), 1e300
y0 = np.array([0.0, 1.0, 30.0, 0.96, 0.05, 0.0, 0.27])
out = {}
with np.errstate(all="ignore"):
    for name in ("rk45", "dop853", "radau", "bdf", "lsoda"):
        rhs = ATTITUDE_MODELS["quaternion"].make_rhs(inertia, ws)
        st = INTEGRATORS[name](rhs, 0.0, y0, 1.0, IntegratorSettings(method=name))
        for _ in range(100):
            if st.status != "running":
                break
            st.step()
        out[name] = [st.status, st.message]
    if kernels.COMPILED:
        st = CompiledStepper(INTEGRATORS["dop853"], None, 0.0, y0, 1.0, IntegratorSettings(),
                             problem=SegmentProblem(inertia, ws))
        st.advance(1.0, np.zeros(3))
        out["compiled dop853"] = [st.status, st.message]
print(json.dumps(out))
"""


def test_a_nan_step_size_fails_instead_of_looping_for_ever():
    """
    Fail on a NaN step size: the root cause of the orbit_rate = 1e300 hang.

    With a NaN step size every comparison in the step-size loop is False, so it neither
    accepted nor failed (compiled dop853 and scipy's solvers alike).
    """
    out = run_python(_NAN_STEP)
    for name, (status, message) in out.items():
        assert status == 'failed' and message, (name, message)
    assert 'not a number' in out['dop853'][1] and 'not a number' in out['rk45'][1]
    if 'compiled dop853' in out:
        assert out['compiled dop853'][1] == out['dop853'][1]


_LONG_STEPS = r"""
import json, warnings
import numpy as np
from tumble_ros.core import IntegratorSettings, Scenario, simulate
warnings.simplefilter("ignore")
cases = {
    # one RK4 step of 1 yr at |w| = 1e9 rad/yr: the Euler-angle tracking cut it into
    # |w| h / max(0.1, sin theta) = 1e10 pieces (an hour compiled, for ever in Python)
    "long step": Scenario(omega0=(0.0, 0.0, 1e9), duration=1.0, output_interval=0.5,
                          integrator=IntegratorSettings(method="rk4", step=1.0)),
    # the same, the state running away to 1e121 (finite) and then to inf
    "runaway": Scenario(inertia=(1.0, 1.6, 2.2), omega0=(1e9, 2e9, 1e9), duration=1.0,
                        output_interval=0.05,
                        integrator=IntegratorSettings(method="rk4", step=0.1)),
}
out = {}
for name, sc in cases.items():
    for fast in (True, False):
        r = simulate(sc, fast=fast)
        finite = all(bool(np.all(np.isfinite(a))) for a in (r.omega, r.euler, r.quaternion))
        out[f"{name} {fast}"] = [bool(r.success), r.message, len(r.t), finite]
print(json.dumps(out))
"""


def test_a_step_far_too_long_for_the_spin_ends_in_bounded_work():
    out = run_python(_LONG_STEPS)
    for name in ('long step', 'runaway'):
        fast, ref = out[f'{name} True'], out[f'{name} False']
        assert fast == ref, (name, fast, ref)
        assert fast[3], 'NaN handed out'
    assert out['long step True'][0]  # garbage (h |w| = 1e9) but finite: a fixed step is that
    assert not out['runaway True'][0] and 'non-finite' in out['runaway True'][1]


_ONE_CALL = r"""
import json, sys
from tumble_ros.core import IntegratorSettings, Propagator, Scenario
# 1e10 RK4 steps (the most a scenario may ask for) between two samples
sc = Scenario(duration=100.0, output_interval=100.0,
              integrator=IntegratorSettings(method="rk4", step=1e-8))
prop = Propagator(sc, fast=sys.argv[1] == "fast")
calls = []
for times in ([0.0, 100.0], [100.0], [100.0]):
    done, arrays, message = prop.sample_many(times)
    calls.append([done, message, prop.n_steps, prop.t])
print(json.dumps({"calls": calls, "fast": prop.fast}))
"""


@pytest.mark.parametrize('path', ['fast', 'reference'])
def test_one_sample_many_call_does_bounded_work_and_reports_partial_progress(path):
    """
    Return after the budget with the samples done so far and no failure; go on when called again.

    The call would take 1e10 steps (40 min compiled, a day in Python).
    """
    if path == 'fast' and not kernels.COMPILED:
        pytest.skip('numba not available')
    out = run_python(_ONE_CALL, path)
    budget = FAST_WORK_BUDGET if out['fast'] else REFERENCE_WORK_BUDGET
    (done1, msg1, steps1, t1), (done2, msg2, steps2, t2), (done3, msg3, steps3, _) = \
        out['calls']
    assert (done1, msg1, t1) == (1, '', 0.0)  # t = 0 sampled, then the budget ran out: partial
    assert (done2, msg2, t2) == (0, '', 0.0)  # more progress, still partial, not a failure
    assert (done3, msg3) == (0, '')
    assert 0 < steps1 <= budget and 0 < steps2 - steps1 <= budget and steps3 > steps2


def _sample_in_pieces(prop, times, budget, schedule=None):
    """
    Call sample_many with the given budget until every time is sampled.

    Every call either completes or makes partial progress (message ''). ``schedule = (t,
    impact)``: schedule the impact once every sample before t is out (after first running the
    stepper past the last sample with a call that the budget cuts short, unless it is inf).
    """
    out = {key: [] for key in ('omega', 'euler', 'quaternion')}
    k, partial = 0, 0
    while k < len(times):
        stop = len(times)
        if schedule is not None:
            stop = int(np.searchsorted(times, schedule[0]))
            if k == stop:
                if budget != math.inf:
                    done, _, message = prop.sample_many(times[k:], budget=budget)
                    assert (done, message) == (0, ''), 'the budget should not reach a sample'
                    assert prop._stepper.t > prop.t + 0.2  # far past the last sample
                prop.schedule(schedule[1])
                schedule = None
                continue
        done, arrays, message = prop.sample_many(times[k:stop], budget=budget)
        assert message == '', message
        partial += done < stop - k
        for key in out:
            out[key].append(arrays[key][:done])
        k += done
    return {key: np.concatenate(v) for key, v in out.items()}, partial


@pytest.mark.parametrize('fast', [True, False])
def test_sampling_in_budgeted_calls_gives_the_same_samples_bit_for_bit(fast):
    if fast and not kernels.COMPILED:
        pytest.skip('numba not available')
    impacts = (Impact(0.5, 3e-7, (3e6, -1e6, 2e5)),
               Impact(1.2, 1e-3, (0.0, 1e3, 2e3), frame='orbital'))
    sc = Scenario(inertia=(1.0, 1.3, 1.9), omega0=(2.0, 1.0, 30.0), duration=2.0,
                  output_interval=0.01, impacts=impacts,
                  integrator=IntegratorSettings(method='rk4', step=1e-3))
    whole = simulate(sc, fast=fast)
    pieces, partial = _sample_in_pieces(Propagator(sc, fast=fast), sc.output_times, budget=37)
    assert partial > 10 and whole.success
    for key in ('omega', 'euler', 'quaternion'):
        np.testing.assert_array_equal(pieces[key], getattr(whole, key))


@pytest.mark.parametrize('fast', [True, False])
def test_an_impact_scheduled_after_partial_progress_restarts_from_the_last_sample(fast):
    """
    Restart from the last sample, Euler-angle track included, as after a complete call.

    After a call cut by its budget the stepper is far past the last sample handed out (here
    ~9 rad of spin) when the impact is scheduled.
    """
    if fast and not kernels.COMPILED:
        pytest.skip('numba not available')
    sc = Scenario(inertia=(1.0, 1.3, 1.9), omega0=(2.0, 1.0, 30.0), duration=2.0,
                  output_interval=0.5, integrator=IntegratorSettings(method='rk4', step=1e-3))
    kick = Impact(0.8, 1e-3, (0.0, 2e3, 0.0))
    runs = [_sample_in_pieces(Propagator(sc, fast=fast), sc.output_times, budget, (1.0, kick))[0]
            for budget in (math.inf, 300)]
    for key in ('omega', 'euler', 'quaternion'):
        np.testing.assert_array_equal(runs[1][key], runs[0][key])
    assert np.ptp(runs[0]['euler'][:, :2]) > 4 * math.pi  # phi, psi wind: a wrong track shows


_SIGINT = r"""
import signal
# Python turns SIGINT into KeyboardInterrupt only if it started with SIGINT at its default: a
# pytest started in the background by a shell without job control ignores SIGINT, and its
# children inherit that (the cause of this test's failures in backgrounded full suites).
signal.signal(signal.SIGINT, signal.default_int_handler)
from tumble_ros.core import IntegratorSettings, Scenario, simulate
sc = Scenario(duration=100.0, output_interval=100.0,
              integrator=IntegratorSettings(method="rk4", step=1e-8))
simulate(sc, t_eval=[0.0, 1e-6])  # load the compiled loops before saying ready
print("ready", flush=True)
simulate(sc)  # 1e10 steps: ~40 min
print("finished", flush=True)
"""


@needs_numba
def test_a_long_simulate_serves_sigint_between_its_compiled_calls():
    """
    Serve SIGINT during a long simulate().

    simulate() used to run a whole grid in one compiled call, deaf to signals; now each call
    does bounded work and Python sees the KeyboardInterrupt in between.
    """
    proc = subprocess.Popen([sys.executable, '-c', _SIGINT], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stdout], [], [], TIMEOUT)
        if not ready:
            pytest.fail(f'the subprocess was not ready within {TIMEOUT} s')
        assert proc.stdout.readline().strip() == 'ready', proc.communicate()[1][-2000:]
        time.sleep(1.0)  # well inside the long run
        proc.send_signal(signal.SIGINT)
        try:   # the whole run is ~40 min: an unbounded compiled call is far beyond 300 s
            proc.wait(timeout=300)   # (60 s was once too short in a loaded full suite)
        except subprocess.TimeoutExpired:
            pytest.fail('SIGINT not served within 300 s: a compiled call runs unbounded')
        rest, err = proc.communicate()
        assert 'finished' not in rest and 'KeyboardInterrupt' in err, err[-2000:]
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()

"""
From the data to a flyby: the states the photometry allows, run through an encounter scenario.

Each model (the accepted solutions, a posterior sample: :class:`~.model.TumblerParameters`) is
a spin state at the fit's epoch. It is carried torque-free to the flyby scenario's t = 0
(``start_jd`` [JD TDB]; for ``config/apophis_2029.yaml`` :data:`APOPHIS_2029_START_JD`, 72 h
before perigee), its (inertia, omega0, euler0) replace the scenario's, and the bodies of one
inertia run as one ensemble (``simulate_ensemble``, or ``run``: the Dask path,
``functools.partial(tumble_ros.ensembles.run_ensemble, client=client)``, the same results).
The spin state before and after (``spin_state`` at the first and last samples) gives the spread
of the post-flyby state beside the nominal (the first model). The scenario's orbital frame must
be ecliptic J2000, the fit's (true of the Apophis scenario). No torque acts between the epoch
and t = 0 in this model (YORP over years is not in it: the drift of the phases then grows with
the time carried, a limit stated in docs/inversion.md).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from tumble_ros.core.model.rotation import matrix_to_euler, quaternion_to_matrix
from tumble_ros.core.model.scenario import Scenario
from tumble_ros.core.model.spinstate import spin_state, SpinState
from tumble_ros.core.propagation.ensemble import simulate_ensemble
from tumble_ros.core.propagation.simulate import simulate
from tumble_ros.inversion.model import DAYS_PER_YEAR, ModelError, TumblerParameters

__all__ = ['FlybyOutcome', 'flyby_ensemble', 'state_at', 'APOPHIS_2029_START_JD']

#: t = 0 of config/apophis_2029.yaml: 2029-04-10 21:46 TDB (72 h before perigee) [JD TDB]
APOPHIS_2029_START_JD = 2462237.4069444444


@dataclass(frozen=True, eq=False)
class FlybyOutcome:
    """Each model's spin state at the scenario's start and end (``before``, ``after``)."""

    models: tuple[TumblerParameters, ...]
    before: tuple[SpinState, ...]
    after: tuple[SpinState, ...]
    success: np.ndarray


def state_at(params: TumblerParameters, epoch_jd: float, start_jd: float
             ) -> tuple[tuple[float, ...], np.ndarray, tuple[float, float, float]]:
    """
    Return (inertia, omega [rad/yr] body axes, euler0 [rad]) of the state at ``start_jd``.

    The torque-free motion from ``epoch_jd`` (the fit's t = 0), by the runs' own
    propagation (``simulate``, the scenario's default DOP853). ModelError for a start before
    the epoch or a failed run.
    """
    years = (start_jd - epoch_jd) / DAYS_PER_YEAR
    if not years >= 0.0:
        raise ModelError(f"start_jd: {start_jd} is before the fit's epoch {epoch_jd}")
    fields = params.spin.scenario_fields()
    if years == 0.0:
        return fields['inertia'], np.asarray(fields['omega0']), fields['euler0']
    scenario = Scenario(**fields, orbit_rate=0.0, duration=years, output_interval=years)
    run = simulate(scenario, np.array([years]))
    if not run.success:
        raise ModelError(f'the propagation to start_jd failed: {run.message}')
    body_to_orbital = quaternion_to_matrix(run.quaternion[-1])
    return fields['inertia'], run.omega[-1], matrix_to_euler(body_to_orbital.T)


def flyby_ensemble(scenario: Scenario, models: Sequence[TumblerParameters], epoch_jd: float,
                   start_jd: float = APOPHIS_2029_START_JD,
                   run: Callable[..., Any] = simulate_ensemble) -> FlybyOutcome:
    """
    Run every model through ``scenario`` (module docstring) and return its states before/after.

    ``scenario``: the flyby (its body is replaced by each model's inertia: a scenario with a
    mass model of other moments is refused, ModelError). ``run`` as ``simulate_ensemble``.
    """
    if scenario.body.inertia is not None:
        raise ModelError('scenario: has a mass model (body.model); the fitted inertia ratios '
                         'cannot replace it')
    states = [state_at(m, epoch_jd, start_jd) for m in models]
    before: list[SpinState | None] = [None] * len(models)
    after: list[SpinState | None] = [None] * len(models)
    success = np.zeros(len(models), dtype=bool)
    groups: dict[tuple[float, ...], list[int]] = {}
    for k, (inertia, _, _) in enumerate(states):
        groups.setdefault(tuple(inertia), []).append(k)
    for inertia, members in groups.items():
        body = scenario.replace(inertia=inertia)
        result = run(body, omega0=np.array([states[k][1] for k in members]),
                     euler0=np.array([states[k][2] for k in members]))
        for j, k in enumerate(members):
            success[k] = bool(result.success[j])
            before[k] = spin_state(result.omega[j, 0], inertia, result.quaternion[j, 0])
            after[k] = spin_state(result.omega[j, -1], inertia, result.quaternion[j, -1])
    return FlybyOutcome(tuple(models), tuple(s for s in before if s is not None),
                        tuple(s for s in after if s is not None), success)

"""tumble_ros.core: the numerical core, plain numpy/scipy, no ROS.

Quick start::

    from tumble_ros.core import Scenario, simulate
    result = simulate(Scenario(), t_eval=[0.0, 1.0, 2.0])
    result.omega   # (3, 3) angular velocity [rad/yr], body axes

Modules: ``rotation`` (Euler angles, matrices, quaternions), ``torque`` (gravity
gradient), ``dynamics`` (equations of motion, invariants), ``integrators`` (one
interface, name registries, the Lie-Poisson splitting methods), ``kernels`` (the
compiled loops of the fast path, numba), ``scenario`` (validated inputs), ``propagator``
(incremental integration split at impacts), ``simulate`` (batch runs), ``ensemble`` (N
bodies at once), ``analytic`` (the paper's approximate solution, better linearisations,
exact torque-free motion), ``timebase`` (simulated years <-> ROS stamps).
Performance and long runs: docs/performance.md.
"""
from .analytic import MODELS as ANALYTIC_MODELS
from .analytic import AnalyticModel, AnchorState, ModelNotApplicable, applicability, make_model
from .dynamics import ATTITUDE_MODELS, angular_momentum_orbital, jacobi_integral, kinetic_energy
from .integrators import INTEGRATORS, METHODS, SPLITTING_METHODS, SegmentProblem
from .propagator import IntegrationError, Propagator, Sample
from .scenario import (
    PARAMETER_DOCS,
    Impact,
    ImpactLimits,
    IntegratorSettings,
    Scenario,
    ScenarioError,
    dump_scenario,
    load_scenario,
    parse_scenario,
)
from .timebase import TimeBase
from .simulate import SimulationResult, simulate
from .ensemble import EnsembleResult, ensemble_scenarios, random_impacts, simulate_ensemble

__all__ = [
    "ANALYTIC_MODELS",
    "AnalyticModel",
    "AnchorState",
    "ModelNotApplicable",
    "applicability",
    "make_model",
    "ATTITUDE_MODELS",
    "METHODS",
    "SPLITTING_METHODS",
    "INTEGRATORS",
    "SegmentProblem",
    "EnsembleResult",
    "ensemble_scenarios",
    "random_impacts",
    "simulate_ensemble",
    "PARAMETER_DOCS",
    "Impact",
    "ImpactLimits",
    "IntegrationError",
    "IntegratorSettings",
    "Propagator",
    "Sample",
    "Scenario",
    "ScenarioError",
    "SimulationResult",
    "TimeBase",
    "angular_momentum_orbital",
    "jacobi_integral",
    "kinetic_energy",
    "dump_scenario",
    "load_scenario",
    "parse_scenario",
    "simulate",
]

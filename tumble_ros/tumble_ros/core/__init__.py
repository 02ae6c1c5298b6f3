"""
tumble_ros.core: the numerical core, plain numpy/scipy, no ROS.

Quick start::

    from tumble_ros.core import Scenario, simulate
    result = simulate(Scenario(), t_eval=[0.0, 1.0, 2.0])
    result.omega   # (3, 3) angular velocity [rad/yr], body axes

Modules: ``rotation`` (Euler angles, matrices, quaternions), ``torques`` (the torques as
components: gravity gradient, impact pulses, and :class:`TorqueComponent` for torques
defined outside core), ``dynamics`` (equations of motion, invariants), ``integrators`` (one
interface, name registries, the Lie-Poisson splitting methods), ``jit`` (the numba switch)
and ``kernels`` (the physics every path runs and the compiled loops), ``scenario``
(validated inputs), ``propagator``
(incremental integration split at impacts), ``simulate`` (batch runs), ``ensemble`` (N
bodies at once, and the chunks of bigger runs; where chunks run, Dask included, is the run
layer's: ``tumble_ros.runs.ensembles``),
``analytic`` (the paper's approximate solution, better linearisations, exact torque-free
motion), ``timebase`` (simulated years <-> ROS stamps).
Performance and long runs: docs/performance.md.
"""
from .analytic import (AnalyticModel, AnchorState, applicability, characteristic_frequencies,
                       DEPARTURE, departure_text, Frequency, make_model, ModelNotApplicable)
from .analytic import MODELS as ANALYTIC_MODELS
from .dynamics import angular_momentum_orbital, ATTITUDE_MODELS, jacobi_integral, kinetic_energy
from .ensemble import (body_rng, ChunkResult, concatenate_results, ensemble_scenarios,
                       EnsembleResult, GaussianSpread, iter_chunks, random_impacts,
                       RandomImpacts, simulate_ensemble)
from .integrators import INTEGRATORS, METHODS, SegmentProblem, SPLITTING_METHODS
from .params_file import check_params_file
from .propagator import IntegrationError, Propagator, Sample
from .scenario import (
    dump_scenario,
    Impact,
    ImpactLimits,
    IntegratorSettings,
    load_scenario,
    PARAMETER_DOCS,
    parse_scenario,
    Scenario,
    ScenarioError,
)
from .simulate import simulate, SimulationResult
from .timebase import TimeBase
from .torques import torque_function, TorqueComponent

__all__ = [
    'ANALYTIC_MODELS',
    'AnalyticModel',
    'characteristic_frequencies',
    'DEPARTURE',
    'departure_text',
    'Frequency',
    'AnchorState',
    'ModelNotApplicable',
    'applicability',
    'make_model',
    'ATTITUDE_MODELS',
    'METHODS',
    'SPLITTING_METHODS',
    'INTEGRATORS',
    'SegmentProblem',
    'EnsembleResult',
    'ensemble_scenarios',
    'random_impacts',
    'RandomImpacts',
    'GaussianSpread',
    'body_rng',
    'concatenate_results',
    'ChunkResult',
    'iter_chunks',
    'simulate_ensemble',
    'PARAMETER_DOCS',
    'Impact',
    'ImpactLimits',
    'IntegrationError',
    'IntegratorSettings',
    'Propagator',
    'Sample',
    'Scenario',
    'ScenarioError',
    'SimulationResult',
    'TimeBase',
    'TorqueComponent',
    'torque_function',
    'angular_momentum_orbital',
    'jacobi_integral',
    'kinetic_energy',
    'dump_scenario',
    'load_scenario',
    'check_params_file',
    'parse_scenario',
    'simulate',
]

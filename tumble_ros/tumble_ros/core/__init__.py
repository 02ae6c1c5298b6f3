"""
tumble_ros.core: the numerical core, plain numpy/scipy, no ROS.

Quick start::

    from tumble_ros.core import Scenario, simulate
    result = simulate(Scenario(), t_eval=[0.0, 1.0, 2.0])
    result.omega   # (3, 3) angular velocity [rad/yr], body axes

Rooms, bottom up (each imports only those below it: tumble_ros/test/test_architecture.py,
``CORE_ROOMS``): ``compiling`` (the compile machinery: ``jit``, the numba switch and the one
cache stamp of the compiled sources; numba's adjustments; the user's cache folder), the facts
``array_types`` and ``units``, ``trig`` (sin/cos/atan2 the loops inline), ``torques`` (the
torques as components: gravity gradient, impact pulses, and :class:`TorqueComponent` for
torques defined outside core), ``kernels`` (the physics every path runs and the compiled loops,
one registry of compiled methods), ``integrators`` (one interface, name registries, the
Lie-Poisson splitting methods), ``model`` (the body and its inputs: ``scenario`` validated,
``shape``, ``spinstate``, ``observables`` (the spin state as the literature gives it),
``rotation`` (Euler angles, matrices, quaternions), ``dynamics`` (equations of motion,
invariants), ``limits``, ``timebase`` (simulated years <-> ROS stamps), ``user_files``,
``scattering`` and ``lightcurve_settings``, ``shipped`` (the shipped scenario files and shapes,
found in the source tree or a pip install)), ``photometry`` (what a telescope sees: the body's
convex mesh, disk-integrated brightness, synthetic lightcurves), ``propagation``
(``propagator``: incremental integration split at impacts; ``simulate``: batch runs;
``ensemble``: N bodies at once), ``analytic`` (the paper's approximate solution, better
linearisations, exact torque-free motion). The old paths of moved modules (``core.jit``,
``core.model.units``, ``core.propagation.timebase``, ...) still import. The Dask engine is not
numerics: it is in the run layer (:mod:`tumble_ros.runs.ensembles`).
Performance and long runs: docs/performance.md.
"""
from tumble_ros.core.analytic import (AnalyticModel, AnchorState, applicability,
                                      characteristic_frequencies, DEPARTURE, departure_text,
                                      Frequency, make_model, ModelNotApplicable)
from tumble_ros.core.analytic import MODELS as ANALYTIC_MODELS
from tumble_ros.core.integrators import INTEGRATORS, METHODS, SegmentProblem, SPLITTING_METHODS
from tumble_ros.core.model.dynamics import (angular_momentum_orbital, ATTITUDE_MODELS,
                                            jacobi_integral, kinetic_energy)
from tumble_ros.core.model.params_file import check_params_file
from tumble_ros.core.model.scenario import (dump_scenario, Impact, ImpactLimits,
                                            IntegratorSettings, load_scenario, PARAMETER_DOCS,
                                            parse_scenario, Scenario, ScenarioError)
from tumble_ros.core.model.shipped import shipped_scenario, shipped_scenarios
from tumble_ros.core.model.timebase import TimeBase
from tumble_ros.core.propagation.ensemble import (body_rng, ChunkResult, concatenate_results,
                                                  ensemble_scenarios, EnsembleResult,
                                                  GaussianSpread, iter_chunks, random_impacts,
                                                  RandomImpacts, simulate_ensemble)
from tumble_ros.core.propagation.propagator import IntegrationError, Propagator, Sample
from tumble_ros.core.propagation.simulate import simulate, SimulationResult
from tumble_ros.core.torques import torque_function, TorqueComponent

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
    'shipped_scenario',
    'shipped_scenarios',
    'check_params_file',
    'parse_scenario',
    'simulate',
]

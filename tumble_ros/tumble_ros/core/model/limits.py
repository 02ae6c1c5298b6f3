"""
The validated ranges of every input, and the error that reports a value outside them.

One home for the bounds (docs/physics.md, "Validated ranges"): ``scenario`` checks its fields
against them, ``timebase`` its output grids, ``ensemble`` its per-body values.
"""
from __future__ import annotations

import math

from tumble_ros.core.kernels.checks import MIN_STEP_ULPS
# The bounds of the perturbers' inputs live beside the code that reads them, each with its
# reason (core.torques sits below this module: it may not import it); named here too.
from tumble_ros.core.torques.ephemeris import (MAX_EPHEMERIS_BYTES, MAX_INTERPOLATION_ERROR,
                                               MAX_KNOTS, MIN_KNOTS)
from tumble_ros.core.torques.orbits import (MAX_ECCENTRICITY, MAX_GM, MAX_PERICENTRE_SPEED,
                                            MAX_SEMI_MAJOR_AXIS)
from tumble_ros.errors import CoreError

__all__ = ['ScenarioError', 'MIN_RTOL', 'MAX_RTOL', 'MIN_ORBIT_RATE', 'MAX_ORBIT_RATE',
           'MAX_OMEGA', 'MAX_ATOL', 'MAX_DURATION', 'MAX_STEPS', 'MAX_SAMPLES', 'MAX_ROTATION',
           'RESOLUTION_ULPS', 'MAX_PARAMS_FILE_BYTES', 'MAX_IMPACTS', 'MIN_WINDOW_STEPS',
           'STEPS_PER_RADIAN', 'step_budget', 'MAX_SHAPE_FILE_BYTES',
           'MAX_FACETS', 'MIN_BODY_SIZE', 'MAX_BODY_SIZE', 'MAX_DEGREE', 'MAX_EPHEMERIS_BYTES',
           'MAX_INTERPOLATION_ERROR', 'MAX_KNOTS', 'MIN_KNOTS', 'MAX_ECCENTRICITY', 'MAX_GM',
           'MAX_PERICENTRE_SPEED', 'MAX_SEMI_MAJOR_AXIS']


class ScenarioError(CoreError, ValueError):
    """An invalid scenario field; the message starts with the field's name."""


MIN_RTOL, MAX_RTOL = 100 * 2.220446049250313e-16, 0.1  # scipy raises smaller rtol to 100 eps

# -- Validated ranges (docs/physics.md, "Validated ranges"). Every bound keeps a run physically
# meaningful and its work finite; none is near a value the paper or a real asteroid needs.

#: Orbital rate ws [rad/yr]: 0 (no torque) or within [MIN, MAX]. Real heliocentric circular
#: orbits: 2 pi / P, from ~2e-7 rad/yr (Oort cloud, 1e5 AU, P ~ 3e7 yr) to ~2e4 rad/yr (an orbit
#: grazing the Sun's surface, P ~ 2.8 h); the bounds leave two orders of magnitude on each side.
#: ws = 1e300 made 3 ws^2 infinite and the right-hand side NaN.
MIN_ORBIT_RATE, MAX_ORBIT_RATE = 1e-9, 1e6
#: Largest |omega0| [rad/yr]. The fastest known asteroids spin in a few seconds (~1e8 rad/yr);
#: 1e10 rad/yr (a period of 0.02 s) leaves 100x. Every method needs at least a step per
#: radian or so of rotation, so the work per simulated year grows with |omega|.
MAX_OMEGA = 1e10
#: Largest absolute tolerance: the state holds the unit quaternion (components <= 1), so an
#: atol of 0.1 already accepts errors of a tenth of the attitude itself (as MAX_RTOL does for
#: every component). atol = 1e300 accepted any step: the state ran away.
MAX_ATOL = 0.1
#: Longest run [yr]: the model (rigid body, fixed circular orbit, no YORP, no orbital
#: evolution) means nothing over a fraction of the solar system's age (4.6e9 yr); at
#: t = 1e9 yr float64 still resolves 1.2e-7 yr, below the paper's 3e-7-yr pulses.
MAX_DURATION = 1e9
#: Most integration steps of a fixed-step run (duration / step) and smallest duration /
#: max_step of an adaptive one: 1e10 steps take ~40 min (rk4) to ~4 h (splitting6) compiled and
#: weeks on the reference path; more is a typo, not a simulation.
MAX_STEPS = 10**10
#: Most output samples (duration / output_interval + 1): simulate() keeps ~230 bytes per
#: sample (2.3 GB at the bound) and the ROS node publishes ~2,000 samples/s (1.4 h).
MAX_SAMPLES = 10**7
#: Largest max(|omega0|, orbit_rate) * duration [rad]: φ and ψ are followed at least every
#: radian of rotation (Propagator._track_euler) and the torque turns with the orbit, so a run
#: costs at least this many units of work; 1e10 matches MAX_STEPS.
MAX_ROTATION = 1e10
#: An interval (a step, an impact pulse) must span at least this many units in the last place
#: of the time it ends at: shorter ones are what the integrators' step-collapse test refuses
#: (kernels.checks), and t + dt rounds to t for dt < 1/2 ulp.
RESOLUTION_ULPS = int(MIN_STEP_ULPS)
#: Largest params file [bytes] (a scenario file, a ``--params-file``): the paper's scenarios are
#: under 2 kB and 10,000 scheduled impacts under 1 MB; YAML holds ~20x a file's size while it
#: parses (a 60-MB ``omega0`` list took 1.2 GB), so a bigger file is refused before it is read.
MAX_PARAMS_FILE_BYTES = 4 * 1024 * 1024
#: Most scheduled impacts in a scenario (``impacts.start``): each is a segment of the run, and
#: 10**6 of them took 3.9 GB before the first step; the paper uses a handful.
MAX_IMPACTS = 10_000

# -- Shapes and mass models (docs/physics.md, "Mass models"). A shape file's work grows with its
# facets (parsing, the closed-surface and convexity checks, the mass moments: O(F log F); the
# gravity field: O(F N^3 N^2)), so it is bounded before any of it is done.

#: Most facets of a polyhedron (a shape file or ``Polyhedron``): the radar shape models of the
#: PDS (EAR-A-5-DDR-RADARSHAPE-MODELS) hold 2,000 to ~150,000 facets (146,688 the largest the
#: issue names), the spacecraft models are published decimated to that size as well; twice
#: the largest leaves room. A 1,000,000-facet file took 300 s before the first output.
MAX_FACETS = 300_000
#: Largest shape file [bytes]: ~40 bytes a vertex line and ~25 a facet line give ~20 MB at
#: MAX_FACETS (half as many vertices as facets); 64 MiB leaves room for comments and 17-digit
#: coordinates. Checked before the file is read (its text is held while it parses).
MAX_SHAPE_FILE_BYTES = 64 * 1024 * 1024
#: Smallest and largest size of a body [km] (an ellipsoid's semi-axes, a polyhedron's extent
#: along x, y and z): the smallest asteroids observed are metres across (2008 TC3, ~4 m), the
#: largest small body (Ceres) ~1,000 km; two orders of magnitude either side. Semi-axes of
#: 1e-300 km made the mass 0 (a ZeroDivisionError), vertices at 1e200 km an OverflowError.
MIN_BODY_SIZE, MAX_BODY_SIZE = 1e-5, 1e5
#: Highest degree of a gravity field (``gravity.degree``, a mass model's Stokes coefficients):
#: the multipole torque costs ~N^2 per step and a polyhedron's coefficients (N/2 + 1)^3 points
#: a facet; the flybys studied need N <= 4-8. Stokes coefficients of degree 100,000 asked for a
#: 74.5-GiB array before any check.
MAX_DEGREE = 30

# -- The work budget of the adaptive methods (docs/physics.md, "Work budget"). A fixed-step run
# takes duration / step steps, checked above (MAX_STEPS); an adaptive method chooses its steps,
# and a motion that becomes far faster than the scenario's own rates (a spin-up next to a
# point-mass perturber, a near-singular torque, a diverging solution) makes it take ever more:
# e = 1.000001 at a = 1.496e8 km about a solar mass of radius 1 km spins the paper's body up to
# ~1e8 rad/yr, and every output_interval then takes ~3e5 steps. So no adaptive run may take
# more than the budget below within one output_interval of simulated time; it only counts steps
# (no step of a run it does not stop changes) and stops the run as FAILED (the node: DIVERGED)
# with the reason.

#: Fewest steps the budget allows per output_interval. Accepted runs take ~1-100 (the output grid
#: resolves the motion: a sample every radian or so), a perigee passage a few hundred, a run
#: chasing rounding noise at the tightest tolerances near a parabola ~3e4 (rtol 1e-13); 1e5
#: dop853 steps turn a body by ~1e5 rad between two samples, and take ~0.1-0.3 s compiled,
#: ~10-50 s on the reference path.
MIN_WINDOW_STEPS = 100_000
#: Steps per radian of the scenario's own rotation in one output_interval the budget allows on
#: top (the methods take ~0.1-10 per radian: dop853 at rtol 1e-10 ~0.3, rk45 at 1e-13 ~10).
STEPS_PER_RADIAN = 1000.0


def step_budget(output_interval: float, rate: float, max_step: float) -> tuple[float, float]:
    """
    Return (window [yr], most steps within it): the work budget of an adaptive method.

    The window is one ``output_interval`` [yr]; the steps are the most of
    :data:`MIN_WINDOW_STEPS`, :data:`STEPS_PER_RADIAN` per radian the scenario turns by in a
    window at its own ``rate`` [rad/yr] (:attr:`Scenario.step_budget`: max(|omega0|,
    orbit_rate, the Kepler orbit's mean motion)), and 4 windows / ``max_step`` (when > 0: the
    steps a user's max_step asks for).
    """
    steps = max(float(MIN_WINDOW_STEPS), STEPS_PER_RADIAN * rate * output_interval)
    if max_step > 0.0:
        steps = max(steps, 4.0 * output_interval / max_step)
    return float(output_interval), float(math.ceil(steps))

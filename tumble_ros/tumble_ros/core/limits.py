"""
The validated ranges of every input, and the error that reports a value outside them.

One home for the bounds (docs/physics.md, "Validated ranges"): ``scenario`` checks its fields
against them, ``timebase`` its output grids, ``ensemble`` its per-body values.
"""
from __future__ import annotations

from tumble_ros.errors import CoreError

from .kernels.checks import MIN_STEP_ULPS

__all__ = ['ScenarioError', 'MIN_RTOL', 'MAX_RTOL', 'MIN_ORBIT_RATE', 'MAX_ORBIT_RATE',
           'MAX_OMEGA', 'MAX_ATOL', 'MAX_DURATION', 'MAX_STEPS', 'MAX_SAMPLES', 'MAX_ROTATION',
           'RESOLUTION_ULPS', 'MAX_PARAMS_FILE_BYTES', 'MAX_IMPACTS']


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

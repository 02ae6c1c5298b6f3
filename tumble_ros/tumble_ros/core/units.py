"""
Units at the boundary: a scenario may state its times in years, days, hours, minutes or seconds.

Inside, everything is in years (times), rad/yr (rates) and I rad/yr^2 (torques). A scenario
file or parameter set with ``time_unit: h`` states every time-like value in hours instead:
``duration``, ``output_interval``, ``integrator.step``, ``integrator.max_step``,
``impacts.start``, ``impacts.duration``, ``orbit.t_p``, ``spin.precession_period``,
``spin.rotation_period``, ``lightcurve.night_length``, ``lightcurve.night_every``,
``lightcurve.night_start`` [h]; ``omega0``, ``orbit_rate`` [rad/h];
``impacts.torque`` [I rad/h^2]. :func:`to_years` converts them once, when the scenario is read;
the scenario, the recordings and the analysis then compute in years. The scenario remembers its
unit (``Scenario.time_unit``): its output grid is one ROS second per unit, and what a person
reads (progress lines, logs, the analysis' text and figures) is in that unit
(:func:`from_years`), periods also in hours. A year is the Julian year, 365.25 days.

The orbit of the torquing body (``orbit.*``) is stated in the astrodynamics units every table
uses, whatever ``time_unit``: GM [km^3/s^2], distances [km], speeds [km/s]; only its time of
pericentre follows ``time_unit``. :data:`GM_SUN`, :data:`GM_EARTH` and :data:`GM_MOON` are the
standard values, :data:`PERTURBER_RADII` the radii a Kepler orbit's perturber takes by default.
"""
from __future__ import annotations

import math
import re
from typing import Any, Mapping

__all__ = ['TIME_UNITS', 'HOURS_PER_YEAR', 'SECONDS_PER_YEAR', 'to_years', 'TIME_POWERS',
           'seconds_per_year_of', 'from_years', 'in_unit', 'parse_time', 'time_parts',
           'TIME_INPUT_HELP',
           'GM_SUN', 'GM_EARTH', 'GM_MOON', 'KM_PER_AU', 'PERTURBER_RADII']

HOURS_PER_YEAR = 365.25 * 24.0
SECONDS_PER_YEAR = HOURS_PER_YEAR * 3600.0
#: The Sun's GM [km^3/s^2] (IAU 2015 Resolution B3, nominal solar mass parameter
#: 1.3271244e20 m^3/s^2).
GM_SUN = 1.3271244e11
#: The Earth's GM [km^3/s^2], including the atmosphere (IERS Conventions 2010, Petit & Luzum,
#: IERS Technical Note 36, Table 1.1: 3.986004418e14 m^3/s^2).
GM_EARTH = 398600.4418
#: The Moon's GM [km^3/s^2] (JPL DE430, Folkner et al. 2014, IPN Progress Report 42-196).
GM_MOON = 4902.800066
#: The bodies whose radius [km] a Kepler orbit's perturber takes when its GM matches theirs
#: (``torques.orbits.perturber_radius``): name -> (GM [km^3/s^2], radius [km]). The Sun: IAU 2015
#: Resolution B3 nominal radius; the Earth: its equatorial radius (IERS Conventions 2010,
#: 6,378.137 km: the larger one, so that no perigee below the equator's surface is accepted);
#: the Moon: its mean radius (IAU WGCCRE 2015, 1,737.4 km).
PERTURBER_RADII = {
    'Sun': (GM_SUN, 695700.0),
    'Earth': (GM_EARTH, 6378.137),
    'Moon': (GM_MOON, 1737.4),
}
#: The astronomical unit [km] (IAU 2012 Resolution B2: 149,597,870,700 m exactly).
KM_PER_AU = 149597870.7
#: Years per unit of each accepted ``time_unit``.
TIME_UNITS = {
    'yr': 1.0,
    'd': 1.0 / 365.25,
    'h': 1.0 / HOURS_PER_YEAR,
    'min': 1.0 / (HOURS_PER_YEAR * 60.0),
    's': 1.0 / (HOURS_PER_YEAR * 3600.0),
}
#: The power of time in each time-like scenario parameter's unit.
TIME_POWERS = {
    'duration': 1, 'output_interval': 1, 'integrator.step': 1, 'integrator.max_step': 1,
    'impacts.start': 1, 'impacts.duration': 1, 'orbit.t_p': 1,
    'spin.precession_period': 1, 'spin.rotation_period': 1,
    'lightcurve.night_length': 1, 'lightcurve.night_every': 1, 'lightcurve.night_start': 1,
    'omega0': -1, 'orbit_rate': -1,
    'impacts.torque': -2,
}


def _scaled(value: Any, factor: float) -> Any:
    """Return value * factor for a number or a list of numbers; anything else unchanged."""
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        return value * factor
    if isinstance(value, (list, tuple)) and all(isinstance(v, (int, float))
                                                and not isinstance(v, bool) for v in value):
        return [v * factor for v in value]
    return value   # (the scenario's validation names the field and says what is wrong)


def from_years(years: float, unit: str) -> float:
    """Return a time [yr] in ``unit`` (a key of :data:`TIME_UNITS`): what a person reads."""
    return years / TIME_UNITS[unit]


def seconds_per_year_of(unit: str) -> float:
    """Return the ROS seconds per simulated year that make one ROS second one ``unit``."""
    return 1.0 / TIME_UNITS[unit]


def to_years(params: Mapping[str, Any], unit: str) -> dict[str, Any]:
    """Return ``params`` with every time-like value converted from ``unit`` to years."""
    return _converted(params, TIME_UNITS[unit])


def in_unit(params: Mapping[str, Any], unit: str) -> dict[str, Any]:
    """
    Return ``params`` [yr] with every time-like value stated in ``unit``.

    :func:`to_years`' inverse, to an ulp: the defaults a node declares for a scenario in
    ``unit`` (``nodes.parameters``), so that what it lists is what it runs.
    """
    return _converted(params, 1.0 / TIME_UNITS[unit])


def _converted(params: Mapping[str, Any], factor: float) -> dict[str, Any]:
    """Return ``params`` with each time-like value times ``factor`` to its power of time."""
    out = dict(params)
    if factor == 1.0:
        return out
    for name, power in TIME_POWERS.items():
        if name in out:
            out[name] = _scaled(out[name], factor ** power)
    return out


#: How a time is typed at a command line or a service (:func:`parse_time`), for help texts.
TIME_INPUT_HELP = ("a number in the scenario's time_unit, or with a unit: 12h, 3d, 30min, 90s, "
                   '2yr')
_TIME_INPUT = re.compile(r'\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*('
                         + '|'.join(sorted(TIME_UNITS, key=len, reverse=True)) + r')?\s*')


def parse_time(text: str | float, unit: str, name: str = 'time') -> float:
    """
    Return the time ``text`` in years: a number in ``unit``, or a number and its own unit.

    ``unit`` is the scenario's ``time_unit`` (a key of :data:`TIME_UNITS`), the unit of a bare
    number; ``12h``, ``3d``, ``30min``, ``90s`` or ``2yr`` state theirs. ValueError naming
    ``name`` (an option, a field) for anything else, a value that is not finite included.
    """
    number, stated = time_parts(text, name, unit)
    return number * TIME_UNITS[stated or unit]


def time_parts(text: str | float, name: str = 'time', unit: str = '') -> tuple[float, str]:
    """
    Return (the number, its unit or '') of a time as :func:`parse_time` reads it.

    For a check before the scenario's unit is known (``unit`` '': the message says "the
    run's time_unit"); ValueError as :func:`parse_time`.
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        number, stated = float(text), ''
    else:
        match = _TIME_INPUT.fullmatch(str(text))
        if match is None:
            where = f"{unit} (the scenario's time_unit)" if unit else "the run's time_unit"
            raise ValueError(f'{name}: {text!r} is not a time: a number in {where} or a number '
                             f"and its unit, one of {', '.join(TIME_UNITS)}: 12h, 3d, 30min, "
                             '90s, 2yr')
        number, stated = float(match.group(1)), match.group(2) or ''
    if not math.isfinite(number):
        raise ValueError(f'{name}: must be a finite time, got {text!r}')
    return number, stated

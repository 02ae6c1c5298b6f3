"""
The units and the frame the analysis shows a recording in: chosen once, used by text and figures.

Inside, the analysis computes in years [yr], rad/yr and radians (``core.units``). What it
prints and draws is in the units of the field, chosen here from the run's span and its scenario:

* times, periods and rates in one time unit: the scenario's ``time_unit`` when it states one
  (d, h, min, s: a 1190-d run in d and rad/d, the 144-h flyby in h and rad/h); for a scenario
  in years (the default) or none, years for a run of a year or more (the paper's runs: t in
  yr, w in rad/yr), otherwise the largest of d, h, min, s that the run spans at least
  :data:`~.timeaxis.DISPLAY_MIN_UNITS` times (:func:`~.timeaxis.display_unit`); periods in
  that unit with hours beside (:meth:`DisplayUnits.period_text`);
* directions (the pole of L) in degrees, longitude in [0, 360) (:func:`longitude_degrees`),
  always with the frame named (:func:`frame_name`):
  ``ecliptic J2000`` for a scenario with a Kepler orbit or a flyby (its ``orbit.*`` elements
  are stated in the ephemeris' frame, ecliptic J2000 by the project's convention: JPL Horizons
  elements, docs/physics.md "Apophis 2029"), otherwise the paper's ``orbital frame`` (Z' the
  orbit normal).

    units = recording_units(rec)      # or display_units(span_yr, scenario)
    units.time_text(t)                # '72 h'
    units.rate_text(w)                # '0.2022 rad/h'
    units.period_text(p)              # '262.2 h'
    units.direction_text(lon, lat)    # 'lon 275.00 deg, lat -85.00 deg (ecliptic J2000)'
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import re
from typing import Any, TYPE_CHECKING

import numpy as np

from tumble_ros.core.units import HOURS_PER_YEAR, TIME_UNITS

from .timeaxis import display_unit

if TYPE_CHECKING:
    from tumble_ros.core import Scenario

    from .recording import Recording

__all__ = ['DisplayUnits', 'display_units', 'recording_units', 'run_time_unit', 'frame_name',
           'is_flyby',
           'longitude_degrees', 'ORBITAL_FRAME', 'ELEMENTS_FRAME']

#: The frame of a circular-orbit run (the paper's X'Y'Z': Z' the orbit normal).
ORBITAL_FRAME = 'orbital frame'
#: The frame of a Kepler orbit's or a flyby's elements (``orbit.*``), by convention.
ELEMENTS_FRAME = 'ecliptic J2000'


def is_flyby(scenario: Scenario | None) -> bool:
    """Return whether the torquing body passes on a hyperbola (``orbit.kind: flyby``)."""
    orbit = getattr(scenario, 'orbit', None)
    return orbit is not None and orbit.e > 1.0


def frame_name(scenario: Scenario | None) -> str:
    """Return the name of the frame the scenario's directions (attitude, pole) are in."""
    return ELEMENTS_FRAME if getattr(scenario, 'orbit', None) is not None else ORBITAL_FRAME


def longitude_degrees(longitude: Any) -> Any:
    """Return a longitude [rad] (a number or an array) in degrees in [0, 360): the convention."""
    return np.mod(np.degrees(longitude), 360.0)


_NUMBER = r'[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?'
#: A time [yr] or a rate [rad/yr] as the nodes and the computing code write them in text:
#: ``t = 0.5 yr``, ``period 0.0104 yr``, ``606.4 rad/yr`` (not ``rad/yr^2``, not ``/yr per``).
_IN_YEARS = re.compile(rf'(?<![\w.])({_NUMBER}) (yr|rad/yr)(?![\w^/])')
#: An interval of times [yr]: ``[0.1, 0.1000003] yr``.
_INTERVAL_IN_YEARS = re.compile(rf'\[({_NUMBER}), ({_NUMBER})\] yr(?![\w^/])')


@dataclass(frozen=True)
class DisplayUnits:
    """One time unit for times, periods and rates; degrees and a named frame for directions."""

    time: str                 # 'yr', 'd', 'h', 'min' or 's'
    years_per_time: float     # years in one ``time``
    frame: str                # the frame of directions, e.g. 'ecliptic J2000'

    @property
    def rate(self) -> str:
        """Return the unit of an angular rate, e.g. 'rad/h'."""
        return f'rad/{self.time}'

    def t(self, years: float) -> float:
        """Return a time or a period [yr] in :attr:`time`."""
        return years / self.years_per_time

    def w(self, rad_per_year: Any) -> Any:
        """Return a rate [rad/yr] (a number or an array) in :attr:`rate`."""
        return rad_per_year * self.years_per_time

    def torque(self, per_year2: Any) -> Any:
        """Return a torque [I rad/yr^2] (a number or an array) in :attr:`torque_unit`."""
        return per_year2 * self.years_per_time ** 2

    @property
    def torque_unit(self) -> str:
        """Return the unit of a torque per unit inertia, e.g. 'I rad/h^2'."""
        return f'I rad/{self.time}^2'

    def time_text(self, years: float | None, digits: int = 6) -> str:
        """Write a time [yr] in :attr:`time`, with its name."""
        return '-' if years is None else f'{self.t(years):.{digits}g} {self.time}'

    def rate_text(self, rad_per_year: float | None, digits: int = 6) -> str:
        """Write a rate [rad/yr] in :attr:`rate`, with its name."""
        return '-' if rad_per_year is None else f'{self.w(rad_per_year):.{digits}g} {self.rate}'

    def period_text(self, years: float, digits: int = 4) -> str:
        """Write a period [yr] in :attr:`time`, and in hours beside unless that is hours."""
        if not math.isfinite(years):
            return 'inf'
        text = self.time_text(years, 6 if self.time == 'yr' else digits)
        return text if self.time == 'h' else f'{text} ({years * HOURS_PER_YEAR:.4g} h)'

    def retime(self, text: str) -> str:
        """
        Rewrite the times '<x> yr', '[<a>, <b>] yr' and rates '<x> rad/yr' of text in our units.

        Text written in years by code that knows no display unit (a node's status, the
        theory's basis, a warning) reads in :attr:`time` and :attr:`rate`, 6 digits.
        """
        if self.time == 'yr':
            return text
        text = _INTERVAL_IN_YEARS.sub(
            lambda m: f'[{self.t(float(m.group(1))):.6g}, {self.t(float(m.group(2))):.6g}] '
                      f'{self.time}', text)
        return _IN_YEARS.sub(
            lambda m: (self.time_text if m.group(2) == 'yr' else self.rate_text)(
                float(m.group(1))), text)

    def direction_text(self, longitude: float, latitude: float) -> str:
        """Write a direction given by longitude and latitude [rad] in degrees, frame named."""
        return (f'lon {longitude_degrees(longitude):.2f} deg, '
                f'lat {math.degrees(latitude):.2f} deg ({self.frame})')


def display_units(span: float, scenario: Scenario | None = None) -> DisplayUnits:
    """
    Return the units of a run spanning ``span`` [yr] of ``scenario``.

    The scenario's ``time_unit`` unless it is years (the default), else the span's unit.
    """
    unit = getattr(scenario, 'time_unit', 'yr')
    name, years = (unit, TIME_UNITS[unit]) if unit != 'yr' else display_unit(span)
    return DisplayUnits(name, years, frame_name(scenario))


def run_time_unit(rec: Recording) -> str:
    """Return the recording's scenario ``time_unit`` (yr without a scenario): its inputs' unit."""
    return getattr(rec.scenario, 'time_unit', None) or 'yr'


def recording_units(rec: Recording) -> DisplayUnits:
    """Return the units a recording is shown in (its ``/angular_velocity`` span, its scenario)."""
    return display_units(float(rec.t[-1] - rec.t[0]) if rec.n else 0.0, rec.scenario)

"""
The units and the frame the analysis shows a recording in: chosen once, used by text and figures.

Inside, the analysis computes in years [yr], rad/yr and radians (``core.model.units``). What it
prints and draws is in the units of the field, chosen here from the run's span and its scenario:

* times, periods and rates in one time unit: years for a run of a year or more (the paper's
  runs: t in yr, w in rad/yr, periods in yr with hours or days beside), otherwise the largest
  of d, h, min, s that the run spans at least :data:`~.timeaxis.DISPLAY_MIN_UNITS` times
  (:func:`~.timeaxis.display_unit`): a 144-h flyby in h, rad/h and periods in h;
* directions (the pole of L) in degrees, always with the frame named (:func:`frame_name`):
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

from tumble_ros.core.model.units import HOURS_PER_YEAR

from .timeaxis import display_unit

if TYPE_CHECKING:
    from tumble_ros.core import Scenario

    from .recording import Recording

__all__ = ['DisplayUnits', 'display_units', 'recording_units', 'frame_name', 'is_flyby',
           'ORBITAL_FRAME', 'ELEMENTS_FRAME']

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


#: A time in years as the nodes write it in their messages.
_YEARS = re.compile(r't = ([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?) yr\b')


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
        """
        Write a period [yr] in :attr:`time`.

        In years (the paper's runs) the period is also given in hours (below 48 h) or days.
        """
        if not math.isfinite(years):
            return 'inf'
        if self.time != 'yr':
            return f'{self.t(years):.{digits}g} {self.time}'
        hours = years * HOURS_PER_YEAR
        other = f'{hours:.4g} h' if hours < 48 else f'{hours / 24:.4g} d'
        return f'{years:.6g} yr ({other})'

    def retime(self, text: str) -> str:
        """Rewrite the times 't = <x> yr' of a node's message (a status) in :attr:`time`."""
        if self.time == 'yr':
            return text
        return _YEARS.sub(lambda m: f't = {self.time_text(float(m.group(1)))}', text)

    def direction_text(self, longitude: float, latitude: float) -> str:
        """Write a direction given by longitude and latitude [rad] in degrees, frame named."""
        return (f'lon {math.degrees(longitude) % 360.0:.2f} deg, '
                f'lat {math.degrees(latitude):.2f} deg ({self.frame})')


def display_units(span: float, scenario: Scenario | None = None) -> DisplayUnits:
    """Return the units of a run spanning ``span`` [yr] of ``scenario``."""
    name, years = display_unit(span)
    return DisplayUnits(name, years, frame_name(scenario))


def recording_units(rec: Recording) -> DisplayUnits:
    """Return the units a recording is shown in (its ``/angular_velocity`` span, its scenario)."""
    return display_units(float(rec.t[-1] - rec.t[0]) if rec.n else 0.0, rec.scenario)

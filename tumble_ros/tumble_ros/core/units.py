"""
Units at the boundary: a scenario may state its times in years, days, hours, minutes or seconds.

Inside, everything is in years (times), rad/yr (rates), I rad/yr^2 (torques) and L^3/yr^2
(GM). A scenario file or parameter set with ``time_unit: h`` states every time-like value in
hours instead: ``duration``, ``output_interval``, ``integrator.step``, ``integrator.max_step``,
``impacts.start``, ``impacts.duration``, ``orbit.t_p`` [h]; ``omega0``, ``orbit_rate`` [rad/h];
``impacts.torque`` [I rad/h^2]; ``orbit.gm`` [L^3/h^2]. :func:`to_years` converts them once,
when the scenario is read; the scenario, the recordings and the analysis then speak years (the
analysis also prints periods in hours or days). A year is the Julian year, 365.25 days.
"""
from __future__ import annotations

from typing import Any, Mapping

__all__ = ['TIME_UNITS', 'HOURS_PER_YEAR', 'to_years', 'TIME_POWERS']

HOURS_PER_YEAR = 365.25 * 24.0
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
    'omega0': -1, 'orbit_rate': -1,
    'impacts.torque': -2, 'orbit.gm': -2,
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


def to_years(params: Mapping[str, Any], unit: str) -> dict[str, Any]:
    """Return ``params`` with every time-like value converted from ``unit`` to years."""
    years_per_unit = TIME_UNITS[unit]
    out = dict(params)
    if unit == 'yr':
        return out
    for name, power in TIME_POWERS.items():
        if name in out:
            out[name] = _scaled(out[name], years_per_unit ** power)
    return out

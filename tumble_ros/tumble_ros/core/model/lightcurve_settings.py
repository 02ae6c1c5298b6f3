"""
What a synthetic lightcurve assumes: the ``lightcurve.*`` parameters of a scenario.

A frozen :class:`LightcurveSettings`, validated once (a ScenarioError names the field, its value
and what is allowed), read from and written to the flat parameters like the rest of the scenario
(``Scenario.lightcurve``). The geometry it sets is described in ``photometry.lightcurve``.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Mapping

import numpy as np
import numpy.typing as npt

from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.scattering import LAWS

__all__ = ['LightcurveSettings', 'LIGHTCURVE_PARAMETER_DOCS', 'DEFAULT_SUBDIVISIONS',
           'MAX_SUBDIVISIONS']

#: Subdivisions of the icosphere of the body's mesh by default: 3, 1,280 facets (the accuracy
#: and the cost are measured in docs/analysis.md, "Lightcurves: what a telescope sees").
DEFAULT_SUBDIVISIONS = 3
#: Most subdivisions accepted: 7, 327,680 facets.
MAX_SUBDIVISIONS = 7


def _unit_or_zero(name: str, value: Any, zero_allowed: bool) -> tuple[float, float, float]:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = np.array([np.nan])
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ScenarioError(f'lightcurve.{name}: must be three finite numbers (a direction, '
                            f'orbital frame), got {value!r}')
    norm = float(np.linalg.norm(v))
    if norm == 0.0:
        if zero_allowed:
            return (0.0, 0.0, 0.0)
        raise ScenarioError(f'lightcurve.{name}: must be a non-zero direction, got {value!r}')
    return (float(v[0] / norm), float(v[1] / norm), float(v[2] / norm))


@dataclass(frozen=True)
class LightcurveSettings:
    """
    What the synthetic lightcurve assumes; validated once (a ScenarioError names the field).

    Attributes
    ----------
    enabled : bool
        Compute and publish the lightcurve (when the body is physical).
    law : str
        Scattering law, a name of ``scattering.LAWS`` (default ``kaasalainen``).
    observer : (x, y, z)
        Direction to the observer, orbital frame, used where the orbit places no observer
        (``lightcurve`` module docstring); normalised here; (0, 0, 0) (default): along the Sun.
    sun : (x, y, z)
        Direction to the Sun, orbital frame, used where the orbit does not give it (a flyby of
        the Earth, no orbit); normalised here; default +Y' (0, 1, 0).
    light_time : bool
        Label samples with their reception times t + delta / c (default False).
    subdivisions : int
        Icosphere subdivisions of the body's mesh, 0 to :data:`MAX_SUBDIVISIONS`.
    night_length, night_every, night_start : float
        A ground campaign's nights [yr]: the body is observed on [night_start + k night_every,
        night_start + k night_every + night_length) for every integer k, and a sample outside
        them carries NaN brightness and magnitude (not observed; :meth:`observed`).
        ``night_length`` 0 (default): observed at every sample; ``night_every`` default one
        day (1 / 365.25 yr), ``night_start`` default 0.

    """

    enabled: bool = True
    law: str = 'kaasalainen'
    observer: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sun: tuple[float, float, float] = (0.0, 1.0, 0.0)
    light_time: bool = False
    subdivisions: int = DEFAULT_SUBDIVISIONS
    night_length: float = 0.0
    night_every: float = 1.0 / 365.25
    night_start: float = 0.0

    def __post_init__(self) -> None:
        for name in ('enabled', 'light_time'):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ScenarioError(f'lightcurve.{name}: must be true or false, got '
                                    f'{getattr(self, name)!r}')
            object.__setattr__(self, name, bool(getattr(self, name)))
        if self.law not in LAWS:
            raise ScenarioError(f"lightcurve.law: must be one of {', '.join(LAWS)}, got "
                                f'{self.law!r}')
        object.__setattr__(self, 'observer', _unit_or_zero('observer', self.observer, True))
        object.__setattr__(self, 'sun', _unit_or_zero('sun', self.sun, False))
        k = self.subdivisions
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) \
                or not 0 <= k <= MAX_SUBDIVISIONS:
            raise ScenarioError(f'lightcurve.subdivisions: must be an integer in [0, '
                                f'{MAX_SUBDIVISIONS}], got {k!r}')
        object.__setattr__(self, 'subdivisions', int(k))
        self._check_nights()

    def _check_nights(self) -> None:
        """Refuse nights that are not finite, a length < 0 or longer than their spacing."""
        for name in ('night_length', 'night_every', 'night_start'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
                    or not math.isfinite(value):
                raise ScenarioError(f'lightcurve.{name}: must be a finite time, got {value!r}')
            object.__setattr__(self, name, float(value))
        if not 0.0 < self.night_every:
            raise ScenarioError(f'lightcurve.night_every: must be > 0 (the spacing of the '
                                f'nights), got {self.night_every!r}')
        if not 0.0 <= self.night_length <= self.night_every:
            raise ScenarioError(f'lightcurve.night_length: must be in [0, night_every] (0: '
                                f'observed at every sample), got {self.night_length!r}')

    def observed(self, t: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Return whether each time ``t`` [yr] falls in a night (every one without nights)."""
        times = np.atleast_1d(np.asarray(t, dtype=float))
        if self.night_length == 0.0:
            return np.ones(times.shape, dtype=bool)
        return np.mod(times - self.night_start, self.night_every) < self.night_length

    def to_parameters(self) -> dict[str, Any]:
        """Return the flat ``lightcurve.*`` parameters."""
        return {'lightcurve.enabled': self.enabled, 'lightcurve.law': self.law,
                'lightcurve.observer': list(self.observer), 'lightcurve.sun': list(self.sun),
                'lightcurve.light_time': self.light_time,
                'lightcurve.subdivisions': self.subdivisions,
                'lightcurve.night_length': self.night_length,
                'lightcurve.night_every': self.night_every,
                'lightcurve.night_start': self.night_start}

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any]) -> 'LightcurveSettings':
        """Build from the ``lightcurve.*`` keys of a flat mapping (others are ignored)."""
        prefix = 'lightcurve.'
        values = {k[len(prefix):]: v for k, v in params.items() if k.startswith(prefix)}
        unknown = sorted(set(values) - set(cls.__dataclass_fields__))
        if unknown:
            raise ScenarioError(f'lightcurve.{unknown[0]}: unknown lightcurve parameter (known: '
                                f"{', '.join(LIGHTCURVE_PARAMETER_DOCS)})")
        for name in ('observer', 'sun'):
            if name in values:
                values[name] = tuple(values[name]) if isinstance(values[name], (list, tuple)) \
                    else values[name]
        return cls(**values)


#: Unit and meaning of every ``lightcurve.*`` parameter (docs/ros.md's table).
LIGHTCURVE_PARAMETER_DOCS: dict[str, tuple[str, str]] = {
    'lightcurve.enabled': ('', 'compute and publish the lightcurve topic (physical bodies only)'),
    'lightcurve.law': ('', 'scattering law: ' + ', '.join(LAWS)),
    'lightcurve.observer': ('', 'direction to the observer, orbital frame, where the orbit '
                            'places none; (0, 0, 0) = along the Sun (zero phase)'),
    'lightcurve.sun': ('', 'direction to the Sun, orbital frame, where the orbit does not give '
                       "it (a flyby of the Earth, no torque); default +Y'"),
    'lightcurve.light_time': ('', 'stamp samples at their reception time t + delta / c'),
    'lightcurve.subdivisions': ('', f'icosphere subdivisions of the body mesh, 0 to '
                                f'{MAX_SUBDIVISIONS} (20 4^k facets)'),
    'lightcurve.night_length': ('yr', "a ground campaign's nights: observed for night_length "
                                'every night_every from night_start, NaN brightness and '
                                'magnitude between them; 0 = observed at every sample'),
    'lightcurve.night_every': ('yr', 'spacing of the nights (default one day, 1/365.25 yr)'),
    'lightcurve.night_start': ('yr', 'start of the first night (default 0)'),
}

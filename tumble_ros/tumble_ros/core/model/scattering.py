"""
Scattering laws: how bright a lit, visible surface element is, S(mu0, mu).

mu0 = cos(incidence) (the Sun's direction against the outward normal), mu = cos(emergence)
(the observer's). :func:`~tumble_ros.core.photometry.brightness.brightness` calls a law on
cosines clipped at 0 (a facet not lit or not seen has mu0 = 0 or mu = 0), so every law must
vanish when either is 0 (each below does: S contains the factor mu0 mu). S is per unit area
and per unit of the incoming flux, up to a constant albedo factor (a lightcurve is relative):

- ``lambert``: S = mu0 mu (a perfectly diffusing surface; bright limbs dark, the disk darkens
  towards the limb);
- ``lommel_seeliger``: S = mu0 mu / (mu0 + mu) (single scattering in a dark, particulate
  regolith; no limb darkening at zero phase);
- ``kaasalainen``: S = mu0 mu / (mu0 + mu) + c mu0 mu with c = 0.1, the combination of the two
  Kaasalainen & Torppa (2001) and Kaasalainen et al. (2001) use for the inversion of asteroid
  lightcurves (the Lambert term weighted c ~ 0.1; docs/analysis.md cites them).

:data:`LAWS` is the registry (name -> :class:`ScatteringLaw`); :func:`law` looks one up and
refuses an unknown name. The law is a property of the body's surface, so it is part of the model
(a scenario's ``lightcurve.law`` names one); ``core.photometry`` computes what a telescope sees
with it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from tumble_ros.core.array_types import FloatArray

__all__ = ['ScatteringLaw', 'LAWS', 'law', 'lambert', 'lommel_seeliger', 'kaasalainen',
           'KAASALAINEN_LAMBERT_WEIGHT']

#: Weight c of the Lambert term of the ``kaasalainen`` law (Kaasalainen et al. 2001: 0.1).
KAASALAINEN_LAMBERT_WEIGHT = 0.1


def lambert(mu0: FloatArray, mu: FloatArray) -> FloatArray:
    """Return S = mu0 mu (Lambert)."""
    out: FloatArray = mu0 * mu
    return out


def lommel_seeliger(mu0: FloatArray, mu: FloatArray) -> FloatArray:
    """Return S = mu0 mu / (mu0 + mu) (Lommel-Seeliger); 0 where mu0 + mu = 0."""
    total = mu0 + mu
    out: FloatArray = np.divide(mu0 * mu, total, out=np.zeros_like(total), where=total > 0.0)
    return out


def kaasalainen(mu0: FloatArray, mu: FloatArray) -> FloatArray:
    """Return S = LS + c Lambert, c = :data:`KAASALAINEN_LAMBERT_WEIGHT`."""
    out: FloatArray = lommel_seeliger(mu0, mu) + KAASALAINEN_LAMBERT_WEIGHT * mu0 * mu
    return out


@dataclass(frozen=True)
class ScatteringLaw:
    """A named law S(mu0, mu) on arrays of one shape (both >= 0, S = 0 if either is 0)."""

    name: str
    function: Callable[[FloatArray, FloatArray], FloatArray]
    note: str

    def __call__(self, mu0: FloatArray, mu: FloatArray) -> FloatArray:
        """Return S(mu0, mu) elementwise."""
        return self.function(mu0, mu)


#: The scattering laws by name.
LAWS: dict[str, ScatteringLaw] = {
    item.name: item for item in (
        ScatteringLaw('lambert', lambert, 'S = mu0 mu: a diffusing surface'),
        ScatteringLaw('lommel_seeliger', lommel_seeliger,
                      'S = mu0 mu / (mu0 + mu): single scattering, dark regolith'),
        ScatteringLaw('kaasalainen', kaasalainen,
                      'S = mu0 mu / (mu0 + mu) + 0.1 mu0 mu: Kaasalainen et al. 2001'),
    )
}


def law(name: str | ScatteringLaw) -> ScatteringLaw:
    """Return the law called ``name`` (a law is returned as is); ValueError for others."""
    if isinstance(name, ScatteringLaw):
        return name
    if name not in LAWS:
        raise ValueError(f"lightcurve.law: must be one of {', '.join(LAWS)}, got {name!r}")
    return LAWS[name]

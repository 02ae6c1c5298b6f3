"""
The compiled facet sum of the disk-integrated brightness: one pass, two laws.

For n pairs of unit directions (the Sun's, the observer's) in body axes and a convex mesh's
outward normals (F, 3) and areas (F,), :func:`scattering_sums` writes per sample

    out[i, 0] = sum over facets with mu0 > 0 and mu > 0 of area mu0 mu / (mu0 + mu)
    out[i, 1] = sum over the same facets of area mu0 mu

the Lommel-Seeliger and the Lambert sums (``scattering``); every law of the registry is a
weighted sum of the two (``ScatteringLaw.weights``), so :func:`~.brightness.brightness_in_body`
gives any of them, and a fit its Lambert weight, from one pass. Each sample is summed facet
by facet in the mesh's order, whatever the number of samples in the call (a live batch and an
offline block give the same bits). ~20x faster than the numpy blocks it replaces (numpy builds
four (samples x facets) arrays), which makes a lightcurve fit possible (docs/inversion.md).

Compiled by numba (``core.jit``; cached in numba's own ``__pycache__``: this file is not one of
the loops' shared sources and imports none of them); without numba the caller uses numpy.
"""
from __future__ import annotations

import numpy as np

from tumble_ros.core.compiling.jit import COMPILED, jit

__all__ = ['scattering_sums', 'COMPILED']


@jit
def scattering_sums(sun: np.ndarray, observer: np.ndarray, normals: np.ndarray,
                    areas: np.ndarray, out: np.ndarray) -> None:
    """Write the Lommel-Seeliger and Lambert sums (n, 2) of (n, 3) body directions to ``out``."""
    facets = areas.shape[0]
    for i in range(sun.shape[0]):
        sx, sy, sz = sun[i, 0], sun[i, 1], sun[i, 2]
        ox, oy, oz = observer[i, 0], observer[i, 1], observer[i, 2]
        lommel = 0.0
        lambert = 0.0
        for f in range(facets):
            nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
            mu0 = sx * nx + sy * ny + sz * nz
            if mu0 <= 0.0:
                continue
            mu = ox * nx + oy * ny + oz * nz
            if mu <= 0.0:
                continue
            product = mu0 * mu * areas[f]
            lambert += product
            lommel += product / (mu0 + mu)
        out[i, 0] = lommel
        out[i, 1] = lambert

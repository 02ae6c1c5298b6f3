"""
Type aliases shared by the typed modules (numpy.typing), one place.

``FloatArray``: a float64 array of any shape; ``Vector3``: three floats (x, y, z) in the
frame the caller names. The compiled bottom of core (torques, kernels, limits) spells
``npt.NDArray[np.float64]`` itself, since it imports nothing above the numba switch and units.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import numpy.typing as npt

__all__ = ['FloatArray', 'ArrayLike', 'Vector3', 'FloatSequence']

#: A float64 array of any shape.
FloatArray = npt.NDArray[np.float64]
#: Anything numpy turns into an array (lists, tuples, arrays, scalars).
ArrayLike = npt.ArrayLike
#: Three floats, e.g. a vector in body axes.
Vector3 = tuple[float, float, float]
#: A short vector given as a sequence of floats or as an array (a quaternion, three angles).
FloatSequence = Sequence[float] | npt.NDArray[np.float64]

"""
What a 3D view of the asteroid needs, as plain numpy: its shape, and where the torquing body is.

The inertia of a scenario is normalised (only the ratios of the principal moments matter), so
the body is drawn at a display scale: its longest semi-axis is 1 (the viewer's length unit, a
metre in RViz and Foxglove). Both the live markers (``runs.messages.markers``) and the offline
animation (``analysis.animation``) take the shape from here.

A uniform-density ellipsoid of semi-axes (a, b, c) and mass m has the principal moments
Ix = m (b^2 + c^2) / 5, Iy = m (a^2 + c^2) / 5, Iz = m (a^2 + b^2) / 5, so::

    a^2 = 5/(2m) (Iy + Iz - Ix),   b^2 = 5/(2m) (Ix + Iz - Iy),   c^2 = 5/(2m) (Ix + Iy - Iz)

(a uniform box of half-edges (a, b, c) has the same formulas with 3 / (2 m): the same
proportions). Every mass distribution satisfies the triangle inequality (each moment at most
the sum of the other two); the paper's Figs 3 and 6-10 break it (``allow_unphysical_inertia``),
and then no ellipsoid, no box, no body at all has these moments: a square in the formulas
above is negative. For such moments the view draws a *box* instead of an ellipsoid (so that the
picture says it is a stand-in): the half-edges of the formulas where their squares are
positive, and a thin plate (:data:`MIN_THICKNESS` of the longest) where they are not. The same
minimum applies to a flat but physical body (Iz = Ix + Iy), which a viewer could not show.
"""
from __future__ import annotations

from dataclasses import dataclass

from typing import TYPE_CHECKING

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray

if TYPE_CHECKING:
    from tumble_ros.core.model.scenario import Scenario

__all__ = ['BodyShape', 'ELLIPSOID', 'BOX', 'POLYHEDRON', 'MIN_THICKNESS', 'body_shape',
           'polyhedron_triangles', 'display_scale',
           'torquing_body_direction', 'torquing_body_directions', 'AXIS_LENGTH',
           'MOMENTUM_LENGTH', 'PERTURBER_LENGTH', 'COLORS']

#: Shape kinds.
ELLIPSOID = 'ellipsoid'
BOX = 'box'
POLYHEDRON = 'polyhedron'
#: Smallest semi-axis drawn, relative to the longest one.
MIN_THICKNESS = 0.05
#: Arrow lengths of a scene [display units; the body's longest semi-axis is 1]: the body axes,
#: the angular momentum's direction, the torquing body's direction.
AXIS_LENGTH = 1.5
MOMENTUM_LENGTH = 2.0
PERTURBER_LENGTH = 2.5
#: Colours (r, g, b, a) of a scene: the live markers and the offline still and animation.
COLORS = {
    ELLIPSOID: (0.62, 0.57, 0.52, 0.85),
    BOX: (0.9, 0.55, 0.25, 0.6),
    POLYHEDRON: (0.62, 0.57, 0.52, 0.85),
    'x': (0.9, 0.15, 0.15, 1.0),
    'y': (0.15, 0.75, 0.15, 1.0),
    'z': (0.2, 0.35, 0.95, 1.0),
    'momentum': (0.8, 0.2, 0.8, 1.0),
    'torquing_body': (1.0, 0.8, 0.1, 1.0),
}


@dataclass(frozen=True)
class BodyShape:
    """
    The drawn body: ``kind`` (:data:`ELLIPSOID` or :data:`BOX`) and its semi-axes.

    ``semi_axes``: along the body's principal axes x, y, z [display units; the longest is 1]
    (for a box: half its edges). ``physical``: the moments satisfy the triangle inequality (an
    ellipsoid of exactly these moments exists, up to :data:`MIN_THICKNESS`).
    """

    kind: str
    semi_axes: tuple[float, float, float]
    physical: bool

    @property
    def note(self) -> str:
        """Say in one line what is drawn."""
        axes = ', '.join(f'{v:.3g}' for v in self.semi_axes)
        if self.physical:
            return f'uniform ellipsoid of the principal moments, semi-axes ({axes})'
        return (f'box ({axes} half-edges): the moments break the triangle inequality, '
                'no body has them')


def body_shape(inertia: ArrayLike) -> BodyShape:
    """
    Return the shape drawn for the principal moments ``inertia`` (Ix, Iy, Iz) [normalised].

    ValueError for moments that are not three positive finite numbers.
    """
    moments = np.asarray(inertia, dtype=float)
    if moments.shape != (3,) or not np.all(np.isfinite(moments)) or np.any(moments <= 0):
        raise ValueError(f'inertia: three positive finite moments needed, got {inertia!r}')
    squares = moments.sum() - 2.0 * moments      # (Iy + Iz - Ix, Ix + Iz - Iy, Ix + Iy - Iz)
    physical = bool(np.all(squares >= -1e-12 * moments.sum()))
    semi = np.sqrt(np.clip(squares, 0.0, None))
    semi = semi / semi.max()
    semi = np.maximum(semi, MIN_THICKNESS)
    return BodyShape(ELLIPSOID if physical else BOX,
                     (float(semi[0]), float(semi[1]), float(semi[2])), physical)


def display_scale(vertices: ArrayLike) -> float:
    """
    Return the display units per km of a polyhedron's drawing: 1 / its farthest vertex [1/km].

    ``vertices`` (n, 3) [km] about the centre of mass: the farthest is drawn at 1, the longest
    semi-axis of the ellipsoid (:func:`body_shape`).
    """
    return float(1.0 / np.linalg.norm(np.asarray(vertices, dtype=float), axis=1).max())


def polyhedron_triangles(vertices: ArrayLike, facets: ArrayLike) -> FloatArray:
    """
    Return the corners of every facet, (3 m, 3), at the display scale: a triangle list.

    ``vertices`` (n, 3) [km] in the body's centre-of-mass principal axes, ``facets`` (m, 3)
    0-based, outward. Scaled so that the farthest vertex from the centre is at 1 (the
    ellipsoid's longest semi-axis, :func:`body_shape`); corner order kept (outward normals).
    """
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(facets, dtype=np.int64)
    corners: FloatArray = v[f].reshape(-1, 3) * display_scale(v)
    return corners


def torquing_body_direction(scenario: Scenario, t: ArrayLike) -> FloatArray | None:
    """
    Return the unit direction from the asteroid to the torquing body, orbital frame: (n, 3).

    The Sun of the circular orbit (``orbit_rate``), or the first perturber (``scenario.orbit``,
    else the first of ``scenario.perturbers``) at the times ``t`` [yr]: the direction of
    :meth:`~tumble_ros.core.Scenario.perturber_position`. None when nothing torques
    (``orbit_rate`` 0 and no perturber).
    """
    if not scenario.all_perturbers and scenario.orbit_rate == 0.0:
        return None
    position = scenario.perturber_position(np.atleast_1d(np.asarray(t, dtype=float)))
    direction: FloatArray = position / np.linalg.norm(position, axis=-1, keepdims=True)
    return direction


def torquing_body_directions(scenario: Scenario, t: ArrayLike) -> list[FloatArray]:
    """
    Return the unit direction to each torquing body, orbital frame: one (n, 3) per body.

    Each of :attr:`~tumble_ros.core.Scenario.all_perturbers`, or the circular orbit's Sun; an
    empty list when nothing torques.
    """
    times = np.atleast_1d(np.asarray(t, dtype=float))
    if not scenario.all_perturbers:
        first = torquing_body_direction(scenario, times)
        return [] if first is None else [first]
    return [p / np.linalg.norm(p, axis=-1, keepdims=True)
            for p in scenario.perturber_positions(times).values()]

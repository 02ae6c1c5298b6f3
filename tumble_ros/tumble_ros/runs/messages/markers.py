"""
The asteroid's 3D scene as ``visualization_msgs/MarkerArray`` messages, built in one place.

The simulator publishes them on ``markers`` (:data:`tumble_ros.topics.MARKERS`) and the offline
recorder writes them, both through :class:`MarkerScene`: one MarkerArray per shown sample, every
marker in the frame ``orbital`` and stamped with the sample's stamp, so that RViz and Foxglove
(fixed frame ``orbital``) show the body tumbling. Namespaces (``ns``) and ids:

* ``body`` 0: the body (:func:`tumble_ros.core.model.shape.body_shape`): a SPHERE scaled to the
  uniform ellipsoid of the principal moments (scale = 2 x semi-axes, the longest semi-axis 1),
  or a CUBE when the moments break the triangle inequality (no body has them), or, for a
  polyhedron mass model (``body.model: polyhedron``), a TRIANGLE_LIST of its facets in its
  principal axes (:func:`tumble_ros.core.model.shape.polyhedron_triangles`: the farthest vertex
  at 1, scale 1); position 0, orientation = the attitude quaternion (body -> orbital) of the
  sample;
* ``axes`` 0, 1, 2: ARROWs along the body's principal axes x, y, z (red, green, blue),
  ``AXIS_LENGTH`` long (lengths and colours: :mod:`tumble_ros.core.model.shape`): orientation = the
  attitude times the fixed rotation taking +x onto the axis (:data:`AXIS_ROTATIONS`);
* ``angular_momentum`` 0: an ARROW from 0 to L / |L| * ``MOMENTUM_LENGTH`` (``points``),
  L = C(q) I w in the orbital frame (its direction; |L| is in the recording's w);
* ``sun`` 0 (circular orbit) or ``perturber`` 0, 1, ... (one per perturber, in the order of
  ``Scenario.all_perturbers``: the Kepler orbit, then ``perturbers``): an ARROW from 0 towards
  the torquing body, ``PERTURBER_LENGTH`` long; absent when nothing torques (``orbit_rate`` 0).

Every array of one run has the same markers, strings and sequence lengths, so its CDR differs
from sample to sample only in numbers: :class:`~tumble_ros.io.MessageTemplate` writes them
from numpy columns (~1 us a message, where building and serialising a MarkerArray in Python
takes ~1 ms), and the live simulator publishes those bytes too: live and offline recordings
hold the same messages. Lengths are display units (the viewer's metres), not physical sizes:
the inertia is normalised.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

from geometry_msgs.msg import Point
import numpy as np
from rclpy.serialization import serialize_message
from std_msgs.msg import ColorRGBA
from tumble_ros import topics
from tumble_ros.core import Scenario
from tumble_ros.core.model.dynamics import angular_momentum_orbital
from tumble_ros.core.model.mass_models import Polyhedron
from tumble_ros.core.model.rotation import quaternions_to_matrices
from tumble_ros.core.model.shape import (AXIS_LENGTH, body_shape, BOX, COLORS, MOMENTUM_LENGTH,
                                         PERTURBER_LENGTH, POLYHEDRON, polyhedron_triangles,
                                         torquing_body_direction, torquing_body_directions)
from tumble_ros.core.model.timebase import SampleGrid
from tumble_ros.io import message_definition, MessageTemplate
from visualization_msgs.msg import Marker, MarkerArray

__all__ = ['MarkerScene', 'marker_every', 'marker_samples', 'MARKER_FRAMES', 'AXIS_ROTATIONS',
           'NS_BODY', 'NS_AXES', 'NS_MOMENTUM', 'NS_SUN', 'NS_PERTURBER']

#: Auto decimation (``marker_decimation`` 0): at most about this many scenes per run.
MARKER_FRAMES = topics.MARKER_FRAMES
#: Namespaces of the markers (:mod:`tumble_ros.topics`).
NS_BODY, NS_AXES, NS_MOMENTUM = topics.MARKER_BODY, topics.MARKER_AXES, topics.MARKER_MOMENTUM
NS_SUN, NS_PERTURBER = topics.MARKER_SUN, topics.MARKER_PERTURBER
_H = math.sqrt(0.5)
#: Quaternions (w, x, y, z) turning an arrow along +x onto the body's x, y and z axes.
AXIS_ROTATIONS = ((1.0, 0.0, 0.0, 0.0), (_H, 0.0, 0.0, _H), (_H, 0.0, -_H, 0.0))


def marker_every(decimation: int, samples: int) -> int:
    """
    Return k: a scene is shown every k-th sample (``decimation``; 0 = auto).

    Auto: every sample up to :data:`MARKER_FRAMES` samples, else ceil(samples / MARKER_FRAMES).
    """
    if decimation > 0:
        return decimation
    return max(1, -(-samples // MARKER_FRAMES))


def marker_samples(k0: int, k1: int, every: int, count: int) -> np.ndarray:
    """Return the grid indices in [k0, k1) that get a scene: k % every == 0, and the last one."""
    k = np.arange(k0, k1, dtype=np.int64)
    chosen: np.ndarray = k[(k % every == 0) | (k == count - 1)]
    return chosen


def _color(rgba: Sequence[float]) -> ColorRGBA:
    r, g, b, a = rgba
    return ColorRGBA(r=float(r), g=float(g), b=float(b), a=float(a))


def _quaternion_products(q: np.ndarray, r: Any) -> np.ndarray:
    """Return the Hamilton products q * r of (n, 4) quaternions with one r, (n, 4)."""
    q0, q1, q2, q3 = q.T
    r0, r1, r2, r3 = r
    return np.stack([q0 * r0 - q1 * r1 - q2 * r2 - q3 * r3,
                     q0 * r1 + q1 * r0 + q2 * r3 - q3 * r2,
                     q0 * r2 - q1 * r3 + q2 * r0 + q3 * r1,
                     q0 * r3 + q1 * r2 - q2 * r1 + q3 * r0], axis=-1)


class MarkerScene:
    """The markers of one scenario's body; :meth:`encode` writes them for samples."""

    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        self.shape = body_shape(scenario.inertia)
        self.perturber_ns = (None if torquing_body_direction(scenario, 0.0) is None
                             else NS_PERTURBER if scenario.all_perturbers else NS_SUN)
        self.perturbers = max(1, len(scenario.all_perturbers))
        self.message = self._template()
        self.encoder = MessageTemplate(topics.TYPES[topics.MARKERS],
                                       message_definition(topics.TYPES[topics.MARKERS]),
                                       serialize_message(self.message))

    def _template(self) -> MarkerArray:
        """Return the scene with every number that does not change from sample to sample."""
        markers = []

        def add(ns: str, marker_id: int, kind: int, scale: Any, color: ColorRGBA,
                points: int = 0, at: Any = None) -> None:
            m = Marker(ns=ns, id=marker_id, type=kind, action=Marker.ADD, color=color)
            m.header.frame_id = topics.FRAME_ORBITAL
            m.pose.orientation.w = 1.0
            m.scale.x, m.scale.y, m.scale.z = (float(v) for v in scale)
            m.points = ([Point() for _ in range(points)] if at is None else
                        [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in at])
            markers.append(m)

        model = self.scenario.body.mass_model
        if isinstance(model, Polyhedron):
            add(NS_BODY, 0, Marker.TRIANGLE_LIST, (1.0, 1.0, 1.0), _color(COLORS[POLYHEDRON]),
                at=polyhedron_triangles(model.vertices, model.facets))
        else:
            add(NS_BODY, 0, Marker.CUBE if self.shape.kind == BOX else Marker.SPHERE,
                [2.0 * v for v in self.shape.semi_axes], _color(COLORS[self.shape.kind]))
        for i, axis in enumerate('xyz'):
            add(NS_AXES, i, Marker.ARROW, (AXIS_LENGTH, 0.04, 0.08), _color(COLORS[axis]))
        # ARROW with points: scale = (shaft diameter, head diameter, head length)
        add(NS_MOMENTUM, 0, Marker.ARROW, (0.05, 0.1, 0.2), _color(COLORS['momentum']),
            points=2)
        if self.perturber_ns is not None:
            for j in range(self.perturbers):
                add(self.perturber_ns, j, Marker.ARROW, (0.05, 0.1, 0.2),
                    _color(COLORS['torquing_body']), points=2)
        return MarkerArray(markers=markers)

    @property
    def markers(self) -> int:
        """Count the markers of one scene."""
        return len(self.message.markers)

    def columns(self, stamp_ns: np.ndarray, t: np.ndarray, quaternion: np.ndarray,
                omega: np.ndarray) -> dict[str, np.ndarray]:
        """
        Return the numbers of n scenes: field path -> (n,) column.

        ``stamp_ns`` (n,) [ns of ROS time], ``t`` (n,) [yr], ``quaternion`` (n, 4) (w, x, y,
        z, body -> orbital), ``omega`` (n, 3) [rad/yr, body axes]: the samples shown.
        """
        stamp_ns = np.asarray(stamp_ns, dtype=np.int64)
        quaternion = np.asarray(quaternion, dtype=float)
        values: dict[str, np.ndarray] = {}
        sec, nanosec = stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000
        for j in range(self.markers):
            values[f'markers[{j}].header.stamp.sec'] = sec
            values[f'markers[{j}].header.stamp.nanosec'] = nanosec

        def orient(j: int, q: np.ndarray) -> None:
            for name, column in zip('wxyz', q.T):
                values[f'markers[{j}].pose.orientation.{name}'] = column

        def arrow(j: int, vector: np.ndarray, length: float) -> None:
            norm = np.linalg.norm(vector, axis=1, keepdims=True)
            tip = np.divide(vector, norm, out=np.zeros_like(vector), where=norm > 0) * length
            for name, column in zip('xyz', tip.T):
                values[f'markers[{j}].points[1].{name}'] = column

        orient(0, quaternion)
        for i, rotation in enumerate(AXIS_ROTATIONS):
            orient(1 + i, _quaternion_products(quaternion, rotation))
        momentum = angular_momentum_orbital(np.asarray(omega, dtype=float),
                                            quaternions_to_matrices(quaternion),
                                            self.scenario.inertia)
        arrow(4, momentum, MOMENTUM_LENGTH)
        for j, direction in enumerate(torquing_body_directions(self.scenario, t)):
            arrow(5 + j, direction, PERTURBER_LENGTH)
        return values

    def encode(self, stamp_ns: np.ndarray, t: np.ndarray, quaternion: np.ndarray,
               omega: np.ndarray) -> np.ndarray:
        """Return n scenes (see :meth:`columns`) as CDR messages, one (n, size) uint8 row each."""
        return self.encoder.encode(len(stamp_ns), self.columns(stamp_ns, t, quaternion, omega))

    def encode_samples(self, grid: SampleGrid, every: int, k0: int, n: int,
                       arrays: dict[str, np.ndarray]) -> np.ndarray:
        """
        Return the scenes of the grid samples k0 .. k0 + n - 1 that get one, as CDR rows.

        ``arrays``: the propagator's ``omega`` and ``quaternion`` of those n samples; a sample
        gets a scene every ``every``-th one and the last of the grid (:func:`marker_samples`).
        The live simulator and the offline writer both take their scenes from here.
        """
        k = marker_samples(k0, k0 + n, every, grid.count)
        if not len(k):
            return np.empty((0, 0), dtype=np.uint8)
        j = k - k0
        return self.encode(k * grid.interval_ns, grid.times(k0, k0 + n)[j],
                           arrays['quaternion'][j], arrays['omega'][j])

"""
The body's attitude as TF (``tf2_msgs/TFMessage``), built in one place.

The simulator publishes them and the offline recording writes them, through
:class:`TransformEncoder` (docs/ros.md, "TF"):

* ``/tf``, one message per sample: the transform from the parent frame ``orbital`` to the child
  frame ``body`` at the sample's stamp, translation 0, rotation = the attitude quaternion
  (body -> orbital: it maps a vector's body components to its orbital ones, as tf2's
  transform from a parent to a child maps the child's coordinates into the parent's), the
  recorded ``attitude`` bit for bit;
* ``/tf_static``, once, at the run's start: ``body`` -> ``body_as_given``, the frame the body
  was given in (a shape file's vertices; the identity for an ellipsoid or given moments), from
  the mass model's :class:`~tumble_ros.core.model.mass_models.Reference`
  (``r_principal = rotation @ (r_given - offset)``): rotation = ``rotation``, translation =
  ``-rotation @ offset`` in the markers' display units (the farthest vertex at 1:
  :func:`~tumble_ros.core.model.shape.display_scale`), so that the frame sits where it does on
  the drawn body.

Frame ids carry the node's namespace (:func:`tumble_ros.topics.frame_id`: ``ast1/body``), so
two asteroids on the shared ``/tf`` never collide. Like the markers, the per-sample messages
are written from numpy columns into one serialised template
(:class:`~tumble_ros.io.MessageTemplate`): the live and offline recordings hold the same bytes.
"""
from __future__ import annotations

from geometry_msgs.msg import TransformStamped
import numpy as np
from rclpy.serialization import serialize_message
from tf2_msgs.msg import TFMessage

from tumble_ros import topics
from tumble_ros.core import Scenario
from tumble_ros.core.model.mass_models import Polyhedron
from tumble_ros.core.model.rotation import matrix_to_quaternion
from tumble_ros.core.model.shape import display_scale
from tumble_ros.io import message_definition, MessageTemplate
from tumble_ros.runs.messages.builders import stamp

__all__ = ['TransformEncoder', 'given_frame_transform']

_PATH = 'transforms[0].'


def given_frame_transform(scenario: Scenario) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """
    Return ((x, y, z), (w, x, y, z)): the transform ``body`` -> ``body_as_given`` of tf2.

    Rotation: the mass model's ``reference.rotation`` (rows: the principal axes in the given
    frame) as a quaternion; translation: ``-rotation @ offset`` [display units]. The identity
    for a body given in its principal axes (the moments alone, an ellipsoid).
    """
    model = scenario.body.mass_model
    if model is None:    # (``body.model: inertia``: the moments alone, given in principal axes)
        return (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
    reference = model.reference
    rotation = np.asarray(reference.rotation, dtype=float)
    # (only a polyhedron is moved: an ellipsoid's or given moments' offset is 0)
    scale = display_scale(model.vertices) if isinstance(model, Polyhedron) else 1.0
    translation = -rotation @ np.asarray(reference.offset, dtype=float) * scale
    q = matrix_to_quaternion(rotation)
    return (tuple(float(v) for v in translation), tuple(float(v) for v in q))


def _transform(parent: str, child: str, stamp_ns: int, translation: tuple[float, ...],
               rotation: tuple[float, ...]) -> TransformStamped:
    """Return one TransformStamped; ``rotation`` (w, x, y, z)."""
    t = TransformStamped(child_frame_id=child)
    t.header.frame_id = parent
    t.header.stamp = stamp(stamp_ns)
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = \
        translation
    r = t.transform.rotation
    r.w, r.x, r.y, r.z = rotation
    return t


class TransformEncoder:
    """The TF messages of one run of ``scenario`` in a node's ``namespace`` ('' or '/': none)."""

    def __init__(self, scenario: Scenario, namespace: str = '') -> None:
        self.scenario = scenario
        self.orbital = topics.frame_id(namespace, topics.FRAME_ORBITAL)
        self.body = topics.frame_id(namespace, topics.FRAME_BODY)
        self.given = topics.frame_id(namespace, topics.FRAME_GIVEN)
        type_name = topics.TYPES[topics.TF]
        template = TFMessage(transforms=[_transform(self.orbital, self.body, 0, (0.0, 0.0, 0.0),
                                                    (1.0, 0.0, 0.0, 0.0))])
        self._template = MessageTemplate(type_name, message_definition(type_name),
                                         serialize_message(template))

    def encode(self, stamp_ns: np.ndarray, quaternion: np.ndarray) -> np.ndarray:
        """
        Return n ``/tf`` messages as (n, size) uint8 CDR rows.

        ``stamp_ns`` (n,) [ns of ROS time]; ``quaternion`` (n, 4) (w, x, y, z), body ->
        orbital: the samples' attitude, copied as it is.
        """
        stamp_ns = np.asarray(stamp_ns, dtype=np.int64)
        q = np.asarray(quaternion, dtype=float)
        values = {_PATH + 'header.stamp.sec': stamp_ns // 1_000_000_000,
                  _PATH + 'header.stamp.nanosec': stamp_ns % 1_000_000_000}
        for j, name in enumerate('wxyz'):
            values[_PATH + f'transform.rotation.{name}'] = q[:, j]
        return self._template.encode(len(stamp_ns), values)

    def static(self, stamp_ns: int) -> bytes:
        """Return the ``/tf_static`` message (``body`` -> ``body_as_given``) at ``stamp_ns``."""
        translation, rotation = given_frame_transform(self.scenario)
        msg = TFMessage(transforms=[_transform(self.body, self.given, stamp_ns, translation,
                                               rotation)])
        return bytes(serialize_message(msg))

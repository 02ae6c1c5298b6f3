"""
The ROS half of the run layer: the messages its records become, and what they are offered with.

- :mod:`.builders`: the ROS messages of a run (scenario descriptions, impact events, statuses,
  comparison statuses) and :class:`~.builders.SampleEncoder`, the per-sample topics' CDR rows
  built from numpy columns by their descriptions (:mod:`tumble_ros.topics`);
- :mod:`.records`: the run layer's records (:mod:`tumble_ros.runs.records`) as messages, and back;
- :mod:`.markers`: the 3D scene (visualization_msgs) of the live and the offline runs;
- :mod:`.qos`: the QoS profiles every topic is published with, and their recorded form.

Message classes and rclpy's serialisation only: no node, no executor. The live nodes
(:mod:`tumble_ros.nodes`) publish these messages; the offline recording
(:mod:`tumble_ros.runs.offline`) writes them.
"""

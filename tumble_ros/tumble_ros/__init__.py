"""
tumble_ros: rotation of a tumbling asteroid under the Sun's gravity-gradient torque (ROS 2 Jazzy).

Sub-packages:

- ``core``: the numerics (Euler-Liouville dynamics, torque, attitude, integrators, analytic
  solution, impacts); numpy/scipy only, no ROS import.
- ``nodes``: thin rclpy nodes that translate between ROS and ``core``.
- ``io``: MCAP writing/reading and message-definition lookup.
- ``analysis``: offline analysis of recorded MCAP files and the paper's figures.

Units throughout: time in years [yr], angular rates in rad/yr, inertia normalised.
"""

__version__ = '0.1.0'

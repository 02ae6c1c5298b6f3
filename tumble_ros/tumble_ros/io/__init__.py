"""MCAP writing and reading, and lookup of ROS message definitions.

Writes rosbag2-compatible MCAP (profile ``ros2``, ``ros2msg`` schemas with their dependencies
concatenated, ``cdr`` messages) and reads it back. Message definitions are looked up through the
ament index and, because sourcing install/setup.bash can drop the venv from AMENT_PREFIX_PATH,
also under ``sys.prefix``.
"""

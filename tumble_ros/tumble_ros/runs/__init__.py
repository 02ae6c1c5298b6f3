"""The run layer: what a run does, without ROS (plain data in, plain records out)."""

"""Offline analysis of recorded MCAP files and the paper's figures.

Reads the files written by ``tumble_ros.io`` and computes errors, periods and plots without a
ROS runtime: no rclpy, no running nodes, no sourced workspace needed.
"""

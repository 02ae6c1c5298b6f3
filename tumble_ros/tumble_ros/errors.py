"""
The errors tumble_ros raises on purpose: one root, one class per package.

Catch :class:`TumbleRosError` to handle anything the project refuses or reports (a bad scenario,
a damaged recording, a refused parameter) apart from bugs. Each package derives its own errors
from its class here (``core``: :class:`CoreError`, ``io``: :class:`IoError`, ``analysis``:
:class:`AnalysisError`, ``nodes``: :class:`NodeError`); the message of each says what is wrong
in one line. No imports: every package, ROS-free or not, can use it.
"""

__all__ = ['TumbleRosError', 'CoreError', 'IoError', 'AnalysisError', 'NodeError']


class TumbleRosError(Exception):
    """Root of every error tumble_ros raises on purpose."""


class CoreError(TumbleRosError):
    """An error of the numerical core (``tumble_ros.core``): scenario, integration, models."""


class IoError(TumbleRosError):
    """An error reading or writing recordings (``tumble_ros.io``)."""


class AnalysisError(TumbleRosError):
    """An error of the offline analysis (``tumble_ros.analysis``)."""


class NodeError(TumbleRosError, ValueError):
    """Input a node refuses at start-up (``tumble_ros.nodes``): params files, unknown names."""

"""
What a run produces, as plain records (no ROS types): the run layer's output.

The simulation session (:mod:`.session`) and the comparison (:mod:`.comparison`) return these;
the live nodes turn them into messages and publish them, the offline recording
(:mod:`.offline`) writes the same messages to a file. Units as on the topics: times [yr],
stamps [ns] of ROS time carrying simulated time, angular velocity [rad/yr] in body axes,
attitude quaternions body -> orbital (scalar first).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Final, NamedTuple, Sequence, Union

import numpy as np
import numpy.typing as npt

from tumble_ros.core import Impact
from tumble_ros.core.photometry import LightcurveRecord

__all__ = ['RUNNING', 'PAUSED', 'FINISHED', 'DIVERGED', 'OK', 'WARN', 'ERROR',
           'SampleBlock', 'SegmentStart', 'ImpactEnded', 'StatusChange', 'ComparisonStatus',
           'ComparedSample', 'ComparisonBlock', 'SessionRecord', 'Floats']

#: The simulator's states (the values of tumble_ros_interfaces/SimStatus).
RUNNING: Final = 0
PAUSED: Final = 1
FINISHED: Final = 2
DIVERGED: Final = 3

#: The comparator's status levels (the values of diagnostic_msgs/DiagnosticStatus).
OK: Final = b'\x00'
WARN: Final = b'\x01'
ERROR: Final = b'\x02'

Floats = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SampleBlock:
    """
    The samples ``start`` .. ``start + len - 1`` of the output grid (n of them).

    Attributes
    ----------
    start : int
        Grid index of the first sample.
    times : (n,) simulated times [yr] (``SampleGrid.times``).
    stamps : (n,) int64 stamps [ns] (``SampleGrid.stamp``).
    omega : (n, 3) angular velocity [rad/yr], body axes.
    quaternion : (n, 4) attitude, body -> orbital, scalar first (continuous in time).
    euler : (n, 3) the paper's continuous (phi, psi, theta) [rad].
    perturber : (n, 3) where the torquing body is [km] in body axes, or None (no Kepler orbit
        or flyby).
    lightcurve : what a telescope sees at these samples (``core.photometry``), or None (the
        body is unphysical, or ``lightcurve.enabled`` is false).

    """

    start: int
    times: Floats
    stamps: npt.NDArray[np.int64]
    omega: Floats
    quaternion: Floats
    euler: Floats
    perturber: Floats | None = None
    lightcurve: LightcurveRecord | None = None

    def __len__(self) -> int:
        """Count the samples."""
        return len(self.times)

    @property
    def stop(self) -> int:
        """Return the grid index after the last sample."""
        return self.start + len(self.times)

    @property
    def indices(self) -> npt.NDArray[np.int64]:
        """Return the samples' grid indices."""
        return np.arange(self.start, self.stop, dtype=np.int64)


@dataclass(frozen=True, slots=True)
class SegmentStart:
    """
    An integration segment's start: the run's description at it (a ``scenario`` message).

    Segments start at t = 0, at every impact's end and at a flyby's encounter window edges.
    The comparison anchors its model on it.

    Attributes
    ----------
    run_id : str
        The run's id (one per run, in every description).
    parameters_yaml : str
        The scenario as started (``dump_scenario``): at revision 0 with its scheduled impacts, at
        later revisions without them (the same text in all of these; an impact's end is on
        ``impact_events``), so a description's size does not grow with the impacts.
    seconds_per_year : float
        The run's time base (stamp [ns] = t [yr] * 1e9 * seconds_per_year).
    revision : int
        0, 1, 2, ... in the order of the segments.
    t0 : float
        The segment's start [yr].
    stamp_ns : int
        ``t0`` as a stamp [ns].
    omega : (3,) angular velocity at ``t0`` [rad/yr], body axes.
    quaternion : (4,) attitude at ``t0`` (w, x, y, z), body -> orbital.

    """

    run_id: str
    parameters_yaml: str
    seconds_per_year: float
    revision: int
    t0: float
    stamp_ns: int
    omega: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]


@dataclass(frozen=True, slots=True)
class ImpactEnded:
    """
    An impact whose pulse has ended.

    ``impact_id``: the id the simulator's service gave it (0 for the scenario's own impacts);
    ``stamp_ns``: its end [ns]; ``delta_omega``: the jump of omega it made [rad/yr], body axes.
    """

    impact: Impact
    impact_id: int
    stamp_ns: int
    delta_omega: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class StatusChange:
    """
    The simulator's state (:data:`RUNNING`, ...) at time ``t`` [yr], stamped ``stamp_ns``.

    ``t`` and ``stamp_ns`` are those of the last sample produced (0 before the first).
    """

    state: int
    t: float
    stamp_ns: int
    message: str


@dataclass(frozen=True, slots=True)
class ComparisonStatus:
    """The comparison's status: ``level`` (:data:`OK`, ...), a line, logged at ``stamp_ns``."""

    level: bytes
    message: str
    stamp_ns: int


class ComparedSample(NamedTuple):
    """
    One sample compared with the model (what the live comparator publishes for it).

    ``model`` and ``error`` (numeric - model) [rad/yr], body axes; ``norm`` = |error|,
    ``relative`` = |error| / |numeric| (inf for numeric 0); ``departure``: the status saying
    the model left the numeric solution here (once per segment), else None. A named tuple, not
    a frozen dataclass like the other records: one is made per sample on the live comparator's
    path, and a tuple is made in a third of the time.
    """

    stamp_ns: int
    model: Sequence[float]
    error: Sequence[float]
    norm: float
    relative: float
    departure: ComparisonStatus | None = None


@dataclass(frozen=True, eq=False)
class ComparisonBlock:
    """
    A block of n samples compared with the model.

    ``compared`` (n,) bool: the samples that have a model value (a model anchored on their
    segment, finite); ``model``, ``error`` (n, 3) [rad/yr] and ``norm``, ``relative`` (n,): as
    in :class:`ComparedSample`, 0 where not compared; ``departures``: the statuses saying a
    segment's model left the numeric solution (at its first such sample).
    """

    stamps: npt.NDArray[np.int64]
    compared: npt.NDArray[np.bool_]
    model: Floats
    error: Floats
    norm: Floats
    relative: Floats
    departures: tuple[ComparisonStatus, ...] = ()


#: What :meth:`.session.SimulationSession.advance` returns, in the order they are to go out.
SessionRecord = Union[ImpactEnded, SegmentStart, SampleBlock, StatusChange]

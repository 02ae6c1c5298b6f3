"""
The comparator node: ``ros2 run tumble_ros comparator``.

Subscribes to the simulator's ``angular_velocity`` and latched ``scenario``, evaluates an
analytic model (:mod:`tumble_ros.core.analytic`) at each sample's simulated time and
publishes, with the sample's own stamp and frame ``body``:

* ``comparison/model_angular_velocity`` (geometry_msgs/Vector3Stamped): the model's w [rad/yr];
* ``comparison/error`` (geometry_msgs/Vector3Stamped): w_numeric - w_model [rad/yr];
* ``comparison/error_norm`` (tumble_ros_interfaces/ErrorNorm): |error| and |error| / |w_numeric|;
* ``comparison/status`` (diagnostic_msgs/DiagnosticStatus, latched): whether the model applies,
  WARN from the first sample where the model left the numeric solution (relative error above
  :data:`tumble_ros.core.DEPARTURE`, once per segment), and ERROR when ``angular_velocity`` or
  ``scenario`` has more than one publisher (two runs mix), and at least WARN, with a count, once
  samples that are not the run's were dropped (:class:`~tumble_ros.runs.comparison.SampleGate`:
  not finite, not after the last sample, or after the run's end).

The model is anchored on the state the simulator's current integration segment starts from
(``scenario`` topic): at start-up, and again after every impact (the simulator re-publishes the
description with the post-impact state), so the error measures the model, not the impact. Each
sample is compared with the model of the segment its time falls in: the simulator publishes a
segment's description before the segment's first sample, and samples of the previous segment that
are still queued keep the previous model. A late start or a restart of either node recovers from
the latched topic. The comparator follows one run: the one ``run_id`` names (bringup passes its
simulator's), or the first whose description arrives. A description of another run (a second
simulator on the same topics) is ignored, with one warning per foreign run; a new run id is
taken as the simulator's restart only when ``scenario`` has a single publisher again and
``run_id`` was not given. Samples that arrive before any description are held (up to
``MAX_PENDING``) and compared ``SETTLE`` seconds after the first description arrives: on a late
join, DDS replays the latched description history and the sample history on separate topics in
no particular order, and the later descriptions (post-impact anchors) must be in before the held
samples are compared. The comparator reports its progress on ``consumer_progress`` so the
simulator never outruns it.

The samples are taken raw and read in place (:class:`~.messages.Vector3StampedReader`; bytes
that are not a Vector3Stamped are skipped with a warning), and the three comparison messages are
published as the CDR bytes of :class:`~.messages.SampleEncoder`, the encoder the offline
recording writes them with: ~40 us a sample less than through message objects. The anchoring
and the arithmetic are :class:`~tumble_ros.runs.comparison.Comparison`'s (the offline
recording's too); the node follows its run, holds the early samples and publishes the records.
"""
from __future__ import annotations

from collections import deque
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.timer import Timer

from tumble_ros import topics
from tumble_ros.core import ANALYTIC_MODELS
from tumble_ros.nodes.clocks import steady_timer
from tumble_ros.nodes.guarded import GuardedNode
from tumble_ros.nodes.parameters import declare_node_parameters
from tumble_ros.nodes.progress import ProgressReporter
from tumble_ros.nodes.runner import run_node
from tumble_ros.nodes.sources import SourceMonitor
from tumble_ros.runs.comparison import Comparison, SampleGate
from tumble_ros.runs.messages.builders import SampleEncoder, Vector3StampedReader
from tumble_ros.runs.messages.qos import DESCRIPTION_QOS, PUBLISHER_QOS, STATE_QOS
from tumble_ros.runs.messages.records import comparison_status_message, segment_start_of
from tumble_ros.runs.records import ComparedSample, ComparisonStatus, ERROR, OK, WARN
from tumble_ros_interfaces.msg import (  # type: ignore[attr-defined]  # rosidl-generated
    ErrorNorm, ScenarioDescription)

__all__ = ['ComparatorNode', 'main']

#: Samples held while waiting for the first scenario description.
MAX_PENDING = 10_000
#: Wall-clock seconds between the first description and comparing the held samples (the rest
#: of the latched description history arrives meanwhile).
SETTLE = 0.2

PARAMETERS = {
    'model': ('paper', '', 'analytic model: ' + ', '.join(ANALYTIC_MODELS), None, False),
    'decimation': (1, '', 'compare every k-th sample', (1, 1_000_000), False),
    'run_id': ('', '', "the simulator run to follow (its scenario descriptions' run_id); "
               'empty: the first run heard', None, True),
}


class ComparatorNode(GuardedNode):
    """Comparator node; see the module docstring."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('comparator', **kwargs)

    def _set_up(self) -> None:
        self.add_on_set_parameters_callback(self._on_set_parameters)
        params = declare_node_parameters(self, PARAMETERS)
        # the anchoring, the model values and the arithmetic; the segments kept for samples
        # that trail a description: as many as the description subscription holds
        self._comparison = Comparison(params['model'], history=DESCRIPTION_QOS.depth)
        self._decimation: int = params['decimation']
        self._pinned = bool(params['run_id'])   # the run was given, never switched
        self.run_id: str | None = params['run_id'] or None   # the run followed (None: none yet)
        self._foreign: set[str] = set()   # the other runs' ids, warned about once each
        self.foreign_descriptions = 0     # descriptions of other runs, ignored
        self._received = 0   # samples of the run taken (the decimation counts these)
        self._taken = 0      # samples taken from angular_velocity, the run's or dropped
        self._gate = SampleGate()   # drops the samples that are not the run's, counting them
        self.compared = 0  # comparisons published (each on the three comparison topics)
        # samples held before the first description: (stamp [ns], omega [rad/yr])
        self._pending: deque[tuple[int, tuple[float, float, float]]] = deque(
            maxlen=MAX_PENDING)
        self._read_sample = Vector3StampedReader()
        self._encoder = SampleEncoder()
        self._settle_timer: Timer | None = None
        qos = PUBLISHER_QOS
        self._pub_model = self.create_publisher(Vector3Stamped, topics.MODEL_ANGULAR_VELOCITY,
                                                qos[topics.MODEL_ANGULAR_VELOCITY])
        self._pub_error = self.create_publisher(Vector3Stamped, topics.ERROR, qos[topics.ERROR])
        self._pub_norm = self.create_publisher(ErrorNorm, topics.ERROR_NORM,
                                               qos[topics.ERROR_NORM])
        self._pub_status = self.create_publisher(DiagnosticStatus, topics.COMPARISON_STATUS,
                                                 qos[topics.COMPARISON_STATUS])
        # announced with the progress: a recorder of these holds until it has subscribed them
        self._progress = ProgressReporter(self, produces=[
            pub.topic_name for pub in (self._pub_model, self._pub_error, self._pub_norm)])
        self.create_subscription(ScenarioDescription, topics.SCENARIO, self._on_scenario,
                                 DESCRIPTION_QOS)
        # raw: the samples are read in place and the comparison published as bytes
        # (messages.SampleEncoder), ~40 us a sample less than through message objects
        self.create_subscription(Vector3Stamped, topics.ANGULAR_VELOCITY, self._on_omega,
                                 STATE_QOS, raw=True)
        self._status = self._comparison.waiting()
        self._report(self._status)
        self._sources = SourceMonitor(self, lambda: (topics.ANGULAR_VELOCITY, topics.SCENARIO),
                                      self._on_sources)

    # -- parameters ---------------------------------------------------------------------
    def _on_set_parameters(self, parameters: list[Any]) -> SetParametersResult:
        for p in parameters:
            if p.name == 'model' and p.value not in ANALYTIC_MODELS:
                known = ', '.join(ANALYTIC_MODELS)
                return SetParametersResult(
                    successful=False, reason=f'model: unknown model {p.value!r}; known: {known}')
        if hasattr(self, '_pub_status'):  # after start-up
            for p in parameters:
                if p.name == 'model':
                    status = self._comparison.set_model(p.value)
                    if status is not None:
                        self._anchored(status)
                elif p.name == 'decimation':
                    self._decimation = p.value
        return SetParametersResult(successful=True)

    # -- model anchoring ----------------------------------------------------------------
    def _follows(self, msg: ScenarioDescription) -> bool:
        """Return whether ``msg`` is a description of the run followed (taking it on if new)."""
        run = msg.run_id
        if self.run_id is None:
            self.run_id = run
            return True
        if run == self.run_id:
            return True
        if not self._pinned and self.count_publishers(topics.SCENARIO) <= 1:
            self.get_logger().info(f'following run {run!r}: the simulator of run '
                                   f'{self.run_id!r} left (restarted)')
            self.run_id = run
            self._gate.reset()
            return True
        self.foreign_descriptions += 1
        if run not in self._foreign:
            self._foreign.add(run)
            self.get_logger().warning(
                f'{self.resolve_topic_name(topics.SCENARIO)}: ignored the description of '
                f'another run ({run!r}): this comparator follows run {self.run_id!r}; another '
                'simulator publishes on these topics')
        return False

    def _on_scenario(self, msg: ScenarioDescription) -> None:
        if not self._follows(msg):
            return
        first = self._comparison.latest is None
        self._anchored(self._comparison.anchor(segment_start_of(msg)))
        if first and self._pending:
            self._settle_timer = steady_timer(self, SETTLE, self._compare_pending)

    def _compare_pending(self) -> None:
        """Compare the samples held before the description history came in (once)."""
        if self._settle_timer is not None:
            self.destroy_timer(self._settle_timer)
        self._settle_timer = None
        while self._pending:
            self._compare(self._pending.popleft())

    def _anchored(self, status: ComparisonStatus) -> None:
        """Log and report whether the model (re)built from the latest description applies."""
        if status.level == OK:
            self.get_logger().info(status.message)
        else:
            self.get_logger().warning(f'no comparison: {status.message}')
        self._report(status)

    def _on_sources(self, problem: str | None) -> None:
        """Report a second simulator on our inputs (ERROR), or restore the model's status."""
        if problem:
            self._report(ComparisonStatus(ERROR, problem, 0), keep=False)
        else:
            self._report(self._status)

    def _report(self, status: ComparisonStatus, keep: bool = True) -> None:
        """
        Publish ``comparison/status``.

        ``keep``: it is the model's status (restored after a second-source error clears).
        """
        if keep:
            self._status = status
            if getattr(self, '_sources', None) is not None and self._sources.current:
                return  # the second-source error stays on until it clears
            status = self._with_drops(status)
        self._pub_status.publish(comparison_status_message(
            status, self.get_fully_qualified_name(), self._comparison.model_name))

    def _with_drops(self, status: ComparisonStatus) -> ComparisonStatus:
        """Return ``status`` saying what the gate dropped (then at least WARN)."""
        dropped = self._gate.text()
        if not dropped:
            return status
        level = max(status.level, WARN)
        return ComparisonStatus(level, f'{status.message}; {dropped}', status.stamp_ns)

    def _dropped(self, stamp_ns: int, why: str) -> None:
        """Log and report a dropped sample (the status at a reason's first, and 1, 2, 4, ...)."""
        n = self._gate.dropped
        self.get_logger().warning(
            f'angular_velocity: dropped a sample stamped {stamp_ns} ns ({why}): not the '
            f"run's ({n} so far)", throttle_duration_sec=5.0)
        if n & (n - 1) == 0 or self._gate.counts[why] == 1:
            self._report(self._status)

    # -- comparison ---------------------------------------------------------------------
    def _on_omega(self, data: bytes) -> None:
        try:
            sample = self._read_sample(data)
        except ValueError as err:
            self.get_logger().warning(f'angular_velocity: sample skipped ({err})',
                                      throttle_duration_sec=5.0)
            return
        if self._comparison.latest is None or self._pending:  # held samples first, in order
            self._pending.append(sample)
            return
        self._compare(sample)

    def _compare(self, sample: tuple[int, tuple[float, float, float]]) -> None:
        stamp_ns, numeric = sample
        self._taken += 1
        grid = self._comparison.grid
        why = self._gate.admit(stamp_ns, numeric,
                               None if grid is None else grid.stamp(grid.count - 1))
        if why is not None:
            self._dropped(stamp_ns, why)
            return
        k, self._received = self._received, self._received + 1
        if k % self._decimation == 0:
            compared = self._comparison.compare_one(stamp_ns, numeric)
            if compared is not None:
                self._publish(compared)
                if compared.departure is not None:
                    self._report(compared.departure)
        self._progress.mark(stamp_ns)

    @property
    def described(self) -> bool:
        """Return whether a description of the run followed has come in."""
        return self._comparison.latest is not None

    @property
    def dropped_samples(self) -> int:
        """Count the samples dropped as not the run's (see :class:`SampleGate`)."""
        return self._gate.dropped

    @property
    def consumed(self) -> int:
        """Count the samples taken from angular_velocity and processed (compared, or dropped)."""
        return self._taken

    def _publish(self, compared: ComparedSample) -> None:
        """
        Publish the model, numeric - model and its norms (3-sequences of floats, rad/yr).

        Stamped with the sample's stamp, frame ``body``.
        """
        self.compared += 1
        model_cdr, error_cdr, norm_cdr = self._encoder.comparison(
            compared.stamp_ns, compared.model, compared.error, compared.norm, compared.relative,
            self._comparison.model_name)
        self._pub_model.publish(model_cdr)
        self._pub_error.publish(error_cdr)
        self._pub_norm.publish(norm_cdr)

    def close(self) -> None:
        """Tell the simulator this consumer leaves."""
        self._progress.close()


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run tumble_ros comparator``."""
    return run_node(ComparatorNode, args, 'comparator')


if __name__ == '__main__':
    raise SystemExit(main())

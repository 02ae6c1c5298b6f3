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
  ``scenario`` has more than one publisher (two runs mix).

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
recording writes them with: ~40 us a sample less than through message objects.
"""
from __future__ import annotations

from collections import deque
import math

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
import numpy as np
from rcl_interfaces.msg import SetParametersResult

from tumble_ros import topics
from tumble_ros.core import (ANALYTIC_MODELS, DEPARTURE, departure_text, make_model,
                             parse_scenario, ScenarioError, TimeBase)
from tumble_ros.nodes.clocks import steady_timer
from tumble_ros.nodes.guarded import GuardedNode
from tumble_ros.nodes.messages import (comparison_status, comparison_values, SampleEncoder,
                                       Vector3StampedReader)
from tumble_ros.nodes.parameters import declare_node_parameters
from tumble_ros.nodes.progress import ProgressReporter
from tumble_ros.nodes.qos import DESCRIPTION_QOS, PUBLISHER_QOS, STATE_QOS
from tumble_ros.nodes.runner import run_node
from tumble_ros.nodes.sources import SourceMonitor
from tumble_ros_interfaces.msg import ErrorNorm, ScenarioDescription

__all__ = ['ComparatorNode', 'main']

#: Samples held while waiting for the first scenario description.
MAX_PENDING = 10_000
#: Wall-clock seconds between the first description and comparing the held samples (the rest
#: of the latched description history arrives meanwhile).
SETTLE = 0.2
#: Grid samples whose model value is computed in one vectorised call: the model's fixed numpy
#: cost (~50 us a call) is then shared by this many samples.
LOOKAHEAD = 64

PARAMETERS = {
    'model': ('paper', '', 'analytic model: ' + ', '.join(ANALYTIC_MODELS), None, False),
    'decimation': (1, '', 'compare every k-th sample', (1, 1_000_000), False),
    'run_id': ('', '', "the simulator run to follow (its scenario descriptions' run_id); "
               'empty: the first run heard', None, True),
}


def anchor_model(model_name: str, description: ScenarioDescription):
    """
    Return (model, the simulator's output grid, a line saying so) for a scenario description.

    The model is anchored on the state the description's segment starts from. Raises
    ScenarioError or ValueError (ModelNotApplicable) when the model cannot be built.
    """
    msg = description
    scenario = parse_scenario(msg.parameters_yaml)
    grid = TimeBase(msg.seconds_per_year).grid(scenario.output_interval, scenario.duration)
    q = msg.attitude
    model = make_model(model_name, scenario, t0=msg.segment_start,
                       omega=(msg.omega.x, msg.omega.y, msg.omega.z),
                       quaternion=(q.w, q.x, q.y, q.z))
    text = (f'model {model_name!r} ({model.label}) anchored at t = '
            f'{msg.segment_start:.9g} yr (segment {msg.revision})')
    return model, grid, text


class GridModelValues:
    """A model's omega on the output grid, LOOKAHEAD samples computed at once."""

    def __init__(self) -> None:
        self._model, self._first, self._values = None, 0, []

    def at(self, model, grid, k: int) -> list[float]:
        """Return ``model``'s omega [rad/yr] at grid sample k."""
        if model is not self._model or not 0 <= k - self._first < len(self._values):
            times = grid.times(k, min(k + LOOKAHEAD, grid.count))
            self._model, self._first, self._values = model, k, model.omega(times).tolist()
        return self._values[k - self._first]

    def span(self, model, grid, k: int, stop: int) -> list[list[float]]:
        """Return ``model``'s omega at grid samples k .. stop - 1: what :meth:`at` gives each."""
        out: list[list[float]] = []
        while k < stop:
            self.at(model, grid, k)       # (re)fills the look-ahead from k if needed
            end = min(stop, self._first + len(self._values))
            out += self._values[k - self._first:end - self._first]
            k = end
        return out


class ComparatorNode(GuardedNode):
    """Comparator node; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__('comparator', **kwargs)

    def _set_up(self) -> None:
        self.add_on_set_parameters_callback(self._on_set_parameters)
        params = declare_node_parameters(self, PARAMETERS)
        self._model_name: str = params['model']
        self._decimation: int = params['decimation']
        self._pinned = bool(params['run_id'])   # the run was given, never switched
        self.run_id: str | None = params['run_id'] or None   # the run followed (None: none yet)
        self._foreign: set[str] = set()   # the other runs' ids, warned about once each
        self.foreign_descriptions = 0     # descriptions of other runs, ignored
        self._description: ScenarioDescription | None = None
        self._timebase = TimeBase()
        self._model = None  # anchored on the latest segment
        self._previous: list = []  # earlier segments' models, newest last: (segment_start, model)
        self._grid = None  # the simulator's output grid (None: unknown)
        self._ahead = GridModelValues()
        self._departed: list = []   # the models that left the numeric solution (said once each)
        self._received = 0
        self.compared = 0  # comparisons published (each on the three comparison topics)
        # samples held before the first description: (stamp [ns], omega [rad/yr])
        self._pending: deque[tuple[int, tuple]] = deque(maxlen=MAX_PENDING)
        self._read_sample = Vector3StampedReader()
        self._encoder = SampleEncoder()
        self._settle_timer = None
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
        self._status = (DiagnosticStatus.WARN, "waiting for the simulator's scenario description")
        self._report(*self._status)
        self._sources = SourceMonitor(self, lambda: (topics.ANGULAR_VELOCITY, topics.SCENARIO),
                                      self._on_sources)

    # -- parameters ---------------------------------------------------------------------
    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for p in parameters:
            if p.name == 'model' and p.value not in ANALYTIC_MODELS:
                known = ', '.join(ANALYTIC_MODELS)
                return SetParametersResult(
                    successful=False, reason=f'model: unknown model {p.value!r}; known: {known}')
        if hasattr(self, '_pub_status'):  # after start-up
            for p in parameters:
                if p.name == 'model':
                    self._model_name = p.value
                    self._anchor()
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
        old = self._description
        if (old is not None and msg.revision > old.revision
                and msg.segment_start > old.segment_start):
            # Samples of the previous segment may still be queued: keep its model for them.
            self._previous = [*self._previous[-(DESCRIPTION_QOS.depth - 1):],
                              (old.segment_start, self._model)]
        elif old is None or msg.revision <= old.revision:
            self._previous = []  # a new run (the simulator restarted)
        first = self._description is None
        self._description = msg
        self._timebase = TimeBase(msg.seconds_per_year)
        self._anchor()
        if first and self._pending:
            self._settle_timer = steady_timer(self, SETTLE, self._compare_pending)

    def _compare_pending(self) -> None:
        """Compare the samples held before the description history came in (once)."""
        self.destroy_timer(self._settle_timer)
        self._settle_timer = None
        while self._pending:
            self._compare(self._pending.popleft())

    def _anchor(self) -> None:
        """(Re)build the model from the latest description; report whether it applies."""
        msg = self._description
        if msg is None:
            return
        try:
            self._model, self._grid, text = anchor_model(self._model_name, msg)
        except (ScenarioError, ValueError) as err:
            self._model = None
            self.get_logger().warning(f'no comparison: {err}')
            self._report(DiagnosticStatus.WARN, str(err))
            return
        self.get_logger().info(text)
        self._report(DiagnosticStatus.OK, text)

    def _on_sources(self, problem: str | None) -> None:
        """Report a second simulator on our inputs (ERROR), or restore the model's status."""
        if problem:
            self._report(DiagnosticStatus.ERROR, problem, keep=False)
        else:
            self._report(*self._status)

    def _report(self, level: bytes, message: str, keep: bool = True) -> None:
        """
        Publish ``comparison/status``.

        ``keep``: it is the model's status (restored after a second-source error clears).
        """
        if keep:
            self._status = (level, message)
            if getattr(self, '_sources', None) is not None and self._sources.current:
                return  # the second-source error stays on until it clears
        self._pub_status.publish(comparison_status(level, self.get_fully_qualified_name(),
                                                   message, self._model_name))

    # -- comparison ---------------------------------------------------------------------
    def _on_omega(self, data: bytes) -> None:
        try:
            sample = self._read_sample(data)
        except ValueError as err:
            self.get_logger().warning(f'angular_velocity: sample skipped ({err})',
                                      throttle_duration_sec=5.0)
            return
        if self._description is None or self._pending:  # held samples first, in order
            self._pending.append(sample)
            return
        self._compare(sample)

    def _compare(self, sample: tuple[int, tuple]) -> None:
        stamp_ns, numeric = sample
        k, self._received = self._received, self._received + 1
        t = self._timebase.to_years(stamp_ns)
        model_at = self._model_for(t)
        if model_at is not None and k % self._decimation == 0:
            model = self._model_omega(model_at, stamp_ns, t)
            if all(map(math.isfinite, model)):
                relative = self._publish(stamp_ns, numeric, model)
                if relative > DEPARTURE and not any(m is model_at for m in self._departed):
                    self._departed.append(model_at)
                    del self._departed[:-DESCRIPTION_QOS.depth]
                    self._report(DiagnosticStatus.WARN, departure_text(self._model_name, t))
        self._progress.mark(stamp_ns)

    def _model_omega(self, model, stamp_ns: int, t: float) -> list[float]:
        """Evaluate ``model`` at ``t`` [yr] (on the simulator's grid: LOOKAHEAD at once)."""
        grid = self._grid
        k = grid.index_of(stamp_ns) if grid is not None else None
        if k is None:
            return model.omega(np.array([t]))[0].tolist()
        return self._ahead.at(model, grid, k)

    def _model_for(self, t: float):
        """Return the model of the segment containing ``t`` (samples can trail the description)."""
        if self._description is None or t >= self._description.segment_start:
            return self._model
        for start, model in reversed(self._previous):
            if t >= start:
                return model
        return None

    @property
    def consumed(self) -> int:
        """Count the samples taken from angular_velocity and processed (compared or not)."""
        return self._received

    def _publish(self, stamp_ns: int, numeric, model) -> float:
        """
        Publish the model, numeric - model and its norms (3-sequences of floats, rad/yr).

        Stamped with the sample's stamp, frame ``body``. Return the relative error
        |numeric - model| / |numeric|.
        """
        self.compared += 1
        error, norm, relative = comparison_values(numeric, model)
        model_cdr, error_cdr, norm_cdr = self._encoder.comparison(
            stamp_ns, model, error, norm, relative, self._model_name)
        self._pub_model.publish(model_cdr)
        self._pub_error.publish(error_cdr)
        self._pub_norm.publish(norm_cdr)
        return relative

    def close(self) -> None:
        """Tell the simulator this consumer leaves."""
        self._progress.close()


def main(args=None) -> int:
    """Entry point of ``ros2 run tumble_ros comparator``."""
    return run_node(ComparatorNode, args, 'comparator')


if __name__ == '__main__':
    raise SystemExit(main())

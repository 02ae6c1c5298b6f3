"""
The simulator node: ``ros2 run tumble_ros sim``.

Integrates a :class:`~tumble_ros.core.Scenario` with :class:`~tumble_ros.core.Propagator`
and publishes every ``output_interval`` of simulated time:

* ``angular_velocity`` (geometry_msgs/Vector3Stamped): w [rad/yr], body axes, frame ``body``;
* ``attitude`` (geometry_msgs/QuaternionStamped): body -> orbital frame, frame ``orbital``;
* ``euler_angles`` (geometry_msgs/Vector3Stamped): the paper's (phi, psi, theta) [rad] in x, y, z;
* ``/clock`` (rosgraph_msgs/Clock, rclpy's clock QoS), unless ``publish_clock`` is false;
* ``impact_events`` (tumble_ros_interfaces/ImpactEvent) when a pulse has ended;
* ``status`` (tumble_ros_interfaces/SimStatus, latched) on every state change, on ``step``, when
  a consumer is dropped or a second source appears, and once a second while running;
* ``scenario`` (tumble_ros_interfaces/ScenarioDescription, latched) at the start and after each
  impact (one per segment): the scenario as started, the initial state of the segment and the
  run's id (:attr:`SimNode.run_id`, drawn at start-up);
* ``/tf`` (tf2_msgs/TFMessage): the attitude as the transform ``orbital`` -> ``body`` of every
  sample, and ``/tf_static`` (latched) once: ``body`` -> ``body_as_given``; frame ids in the
  node's namespace (``ast1/body``; :mod:`~tumble_ros.runs.messages.transforms`);
* ``markers`` (visualization_msgs/MarkerArray, frame ``orbital``) when ``markers`` is true (off
  for a bare ``ros2 run``, where it would cost ~30 % of the throughput; on in bringup, make run
  and the launch files):
  the 3D scene's moving part (L, the Sun) of every ``marker_decimation``-th sample, and
  ``body_markers`` (latched, frame ``body``) once: the body's shape and axes
  (:mod:`~tumble_ros.runs.messages.markers`).

Every stamp is ROS time carrying simulated time, ``status`` included (the time of the last
published sample): t [yr] = stamp_ns / (1e9 * seconds_per_year)
(``core.model.timebase``). The node is the clock source: it paces on the steady clock
whatever ``use_sim_time`` says. Services:
``apply_impact`` (tumble_ros_interfaces/ApplyImpact, every request answered; its times and
torque in the scenario's ``time_unit``, as ``real_time_factor``), ``pause``,
``resume``, ``step`` (std_srvs/Trigger). Impacts are queued by the service and applied at the
next step boundary, never inside the callback. The node holds no physics and no run logic:
what a batch does is :class:`~tumble_ros.runs.session.SimulationSession`'s (the offline recording's
too); the node publishes its records (:mod:`tumble_ros.runs.messages.records`).
"""
from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.qos import QoSProfile
from rclpy.service_introspection import ServiceIntrospectionState
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage  # type: ignore[attr-defined]  # rosidl-generated

from tumble_ros import topics
from tumble_ros.core import Impact, ImpactLimits, Scenario, ScenarioError, TimeBase
from tumble_ros.core.model.timebase import SampleGrid
from tumble_ros.core.units import from_years, TIME_UNITS
from tumble_ros.nodes.clocks import steady_timer
from tumble_ros.nodes.guarded import GuardedNode
from tumble_ros.nodes.parameters import (declare_node_parameters, declare_scenario_parameters,
                                         read_scenario_parameters)
from tumble_ros.nodes.progress import ConsumerTracker
from tumble_ros.nodes.runner import run_node
from tumble_ros.nodes.sources import SourceMonitor
from tumble_ros.runs.messages.builders import FRAMES, message_class, new_run_id, SampleEncoder
from tumble_ros.runs.messages.markers import marker_every, MarkerScene
from tumble_ros.runs.messages.qos import PUBLISHER_QOS, publisher_qos, SERVICE_QOS
from tumble_ros.runs.messages.records import description_message, impact_message, status_message
from tumble_ros.runs.messages.transforms import TransformEncoder
from tumble_ros.runs.records import (DIVERGED, FINISHED, ImpactEnded, PAUSED, RUNNING, SampleBlock,
                                     SegmentStart, SessionRecord, StatusChange)
from tumble_ros.runs.session import output_grid, SimulationSession
from tumble_ros_interfaces.msg import (  # type: ignore[attr-defined]  # rosidl-generated
    ImpactEvent, ScenarioDescription, SimStatus)
from tumble_ros_interfaces.srv import ApplyImpact  # type: ignore[attr-defined]  # rosidl-generated
from visualization_msgs.msg import MarkerArray

__all__ = ['SimNode', 'main']

#: Wall-clock period of the simulation timer [s].
TICK_PERIOD = 0.002
#: Samples published per tick when running as fast as possible (real_time_factor = 0).
BATCH = 10
#: Largest lead [samples] over the slowest registered consumer (well below STATE_QOS depth).
WINDOW = 4 * BATCH
#: Impacts accepted but not yet ended, at most: a request beyond is refused with the reason.
#: Bounds the node's memory and the burst of impact_events (below STATE_QOS depth) under a flood.
MAX_PENDING_IMPACTS = 500
#: Wall-clock seconds between two status messages while running (a heartbeat with a fresh t).
STATUS_PERIOD = 1.0


class SimNode(GuardedNode):
    """Simulator node; see the module docstring for its interface."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('sim', **kwargs)

    def _set_up(self) -> None:
        # Registered before declaring, so start-up values are validated too (rclpy docs).
        self.add_on_set_parameters_callback(self._on_set_parameters)
        declare_scenario_parameters(self)
        params = declare_node_parameters(self, topics.SIM_NODE_PARAMETERS)
        # ScenarioError: refused
        scenario_parameters = read_scenario_parameters(self)
        self.scenario = Scenario.from_parameters(scenario_parameters)
        # 0: the scenario's own (one ROS second per time_unit), the grid of simulate(scenario)
        self.timebase = (TimeBase(params['seconds_per_year']) if params['seconds_per_year']
                         else self.scenario.timebase)
        # the output grid (the one of Scenario.output_times, at this node's seconds_per_year)
        self._grid = output_grid(self.scenario, self.timebase)
        self._limits = ImpactLimits(params['max_impact_duration'], params['max_impact_impulse'])
        #: years per unit of the scenario's time_unit: real_time_factor and the impact service
        #: are in that unit, the session in years
        self._years_per_unit = TIME_UNITS[self.scenario.time_unit]
        self._rtf = params['real_time_factor']
        #: This run's id, in every ``scenario`` description (a restart draws a new one).
        self.run_id: str = new_run_id()
        self._session = SimulationSession(self.scenario, self._grid, run_id=self.run_id,
                                          paused=params['start_paused'])
        self._next_id = 1   # the id of the next impact requested through the service
        self._status_message = ''
        # (wall time, sample index) when pacing began
        self._pace_origin: tuple[float, int] | None = None

        self._min_consumers = params['min_consumers']
        self._consumers_gate_open = self._min_consumers == 0  # opens once, when they are all here
        self._consumers = ConsumerTracker(self, on_drop=self._publish_status)
        publish = self.create_publisher
        qos = PUBLISHER_QOS
        self._pub_clock = (publish(Clock, topics.CLOCK, qos[topics.CLOCK])
                           if params['publish_clock'] else None)
        # the per-sample topics, published as CDR bytes of the encoder's rows
        self._encoder = SampleEncoder()
        optional = self._session.optional_topics     # (the perturber, the lightcurve)
        sample_publishers = {
            **{t.name: publish(message_class(t.type_name), t.name, publisher_qos(t.name))
               for t in topics.sample_topics(topics.SIM) if optional.get(t.name, True)},
            topics.CLOCK: self._pub_clock}
        self._sample_publishers = {t: p for t, p in sample_publishers.items() if p is not None}
        self._pub_events = publish(ImpactEvent, topics.IMPACT_EVENTS, qos[topics.IMPACT_EVENTS])
        self._pub_status = publish(SimStatus, topics.STATUS, qos[topics.STATUS])
        self._pub_scenario = publish(ScenarioDescription, topics.SCENARIO, qos[topics.SCENARIO])
        namespace = self.get_namespace()
        self._transforms = TransformEncoder(self.scenario, namespace)
        self._pub_tf = publish(TFMessage, topics.TF, qos[topics.TF])
        self._pub_tf_static = publish(TFMessage, topics.TF_STATIC, qos[topics.TF_STATIC])
        self._scene = MarkerScene(self.scenario, namespace) if params['markers'] else None
        self._marker_every = marker_every(params['marker_decimation'], self._grid.count)
        self._pub_markers = (publish(MarkerArray, topics.MARKERS, qos[topics.MARKERS])
                             if self._scene is not None else None)
        self._pub_body_markers = (
            publish(MarkerArray, topics.BODY_MARKERS, qos[topics.BODY_MARKERS])
            if self._scene is not None else None)
        self._srv_impact = self.create_service(ApplyImpact, topics.APPLY_IMPACT,
                                               self._on_apply_impact, qos_profile=SERVICE_QOS)
        self._srv_impact.configure_introspection(
            self.get_clock(), QoSProfile(depth=100), ServiceIntrospectionState.CONTENTS)
        self.create_service(Trigger, topics.PAUSE, self._on_pause)
        self.create_service(Trigger, topics.RESUME, self._on_resume)
        self.create_service(Trigger, topics.STEP, self._on_step)
        # (the shared topics, /tf and /tf_static, have one publisher per asteroid by design)
        absent = {t for t, on in optional.items() if not on} | set(topics.SHARED_TOPICS) | {
            t for t, p in ((topics.CLOCK, self._pub_clock), (topics.MARKERS, self._pub_markers),
                           (topics.BODY_MARKERS, self._pub_body_markers))
            if p is None}
        own = [t for t in topics.SIM_TOPICS if t not in absent]
        self._sources = SourceMonitor(
            self, lambda: own,
            lambda problem: self._publish_status(
                problem or "single source again on the simulator's topics"))
        # Steady clock: the simulator is the clock source, use_sim_time or not.
        self._timer = steady_timer(self, TICK_PERIOD, self._on_tick)
        steady_timer(self, STATUS_PERIOD, self._on_status_period)
        # Announced (the first segment's description, 'started', the log line) at the first
        # tick or step, once the command line was checked in full (an unknown parameter is
        # refused after the node is built): nothing is published for a run that is refused.
        self._started_wall: float | None = None

    # -- parameters ---------------------------------------------------------------------
    def _on_set_parameters(self, parameters: list[Any]) -> SetParametersResult:
        """Refuse invalid values of the run-time parameters with a reason."""
        for p in parameters:
            try:
                if p.name == 'max_impact_duration':
                    ImpactLimits(p.value, 1.0)
                elif p.name == 'max_impact_impulse':
                    ImpactLimits(1.0, p.value)
                elif p.name == 'real_time_factor' and not math.isfinite(p.value):
                    raise ScenarioError(f'real_time_factor: must be finite, got {p.value!r}')
                elif p.name == 'seconds_per_year' and p.value != 0.0:
                    TimeBase(p.value)
            except (ScenarioError, ValueError) as err:
                return SetParametersResult(successful=False, reason=str(err))
        if hasattr(self, '_session'):  # after start-up: apply the accepted run-time changes
            self._apply_runtime_parameters(parameters)
        return SetParametersResult(successful=True)

    def _apply_runtime_parameters(self, parameters: list[Any]) -> None:
        for p in parameters:
            if p.name == 'max_impact_duration':
                self._limits = ImpactLimits(p.value, self._limits.max_impulse)
            elif p.name == 'max_impact_impulse':
                self._limits = ImpactLimits(self._limits.max_duration, p.value)
            elif p.name == 'real_time_factor':
                self._rtf = p.value
                self._pace_origin = None

    # -- simulation ---------------------------------------------------------------------
    @property
    def state(self) -> int:
        """Return the SimStatus state: RUNNING, PAUSED, FINISHED or DIVERGED."""
        return self._session.state

    @property
    def status_message(self) -> str:
        """Return the message of the last status published."""
        return self._status_message

    @property
    def per_sample_topics(self) -> tuple[str, ...]:
        """Return the topics with one message per published sample (not /clock; /tf too)."""
        return tuple(name for name, publisher in self._sample_publishers.items()
                     if name != topics.CLOCK and publisher is not None) + (topics.TF,)

    @property
    def grid(self) -> SampleGrid:
        """Return the output grid the node publishes (its ``seconds_per_year``'s time base)."""
        return self._grid

    @property
    def published_samples(self) -> int:
        """Count the samples published so far."""
        return self._session.samples

    @property
    def t(self) -> float:
        """Return the simulated time [yr] of the last published sample (0 before the first)."""
        return self._session.t

    def _announce(self) -> None:
        """Publish the run's start (description, 'started') and log it, once."""
        if self._started_wall is not None:
            return
        self._started_wall = time.monotonic()
        self._publish_records(self._session.start())   # the first segment, 'started'
        unit = self.scenario.time_unit
        self.get_logger().info(
            f'simulating {from_years(self.scenario.duration, unit):g} {unit} with '
            f'{self.scenario.integrator.method}, {self._grid.count} samples every '
            f'{from_years(self.scenario.output_interval, unit):g} {unit}, real_time_factor '
            f'{self._rtf:g}')

    def _on_tick(self) -> None:
        self._announce()
        if self.state != RUNNING:
            return
        self._publish_up_to(self._target_index())

    def _target_index(self) -> int:
        """Last sample index to publish now: pacing, then flow control on the consumers."""
        return min(self._paced_index(), self._consumer_limit())

    def _consumer_limit(self) -> int:
        next_k = self._session.samples
        if not self._consumers_gate_open:
            if self._consumers.count < self._min_consumers:
                return next_k - 1  # not all expected consumers are here yet
            # for good: a consumer that leaves later is not waited for
            self._consumers_gate_open = True
        if self._consumers.recorders_behind():
            return next_k - 1  # a recorder has not heard a comparator yet: wait for it
        slowest = self._consumers.slowest_ns(self._session.stamp_ns)
        if slowest is None:
            return self._grid.count
        return (slowest // self._grid.interval_ns if slowest >= 0 else -1) + WINDOW

    def _paced_index(self) -> int:
        if self._rtf == 0.0:
            return self._session.samples + BATCH - 1
        now = time.monotonic()
        if self._pace_origin is None:
            self._pace_origin = (now, self._session.samples)
        wall0, k0 = self._pace_origin
        t_target = self._grid.time(k0) + self._rtf * self._years_per_unit * (now - wall0)
        return int(self.timebase.to_ns(t_target) // self._grid.interval_ns)

    def _publish_up_to(self, k_last: int) -> None:
        """Run the session up to sample ``k_last`` and publish the batch's records."""
        self._announce()
        self._publish_records(self._session.advance(k_last))

    def _publish_records(self, records: list[SessionRecord]) -> None:
        """
        Publish a batch's records in their order.

        Impacts that ended within the batch: their events and new descriptions go out before
        its samples (the comparator keeps the previous segment's model for the samples that
        trail a description).
        """
        for record in records:
            if isinstance(record, SampleBlock):
                self._publish_samples(record)
                self._publish_markers(record)
            elif isinstance(record, SegmentStart):
                if record.revision == 0:     # the run's start: what is fixed, once
                    self._publish_fixed(record.stamp_ns)
                self._pub_scenario.publish(description_message(record))
            elif isinstance(record, ImpactEnded):
                self._publish_impact_event(record)
            else:
                self._publish_change(record)

    def _publish_samples(self, block: SampleBlock) -> None:
        """
        Publish n samples, each with its /clock, as CDR bytes (:class:`~.messages.SampleEncoder`).

        Per sample: /clock, ω [rad/yr] (body axes), the attitude quaternion (scalar first,
        body -> orbital), the continuous Euler angles (φ, ψ, θ) [rad], with a Kepler orbit
        where the torquing body is [km] (body axes), with a physical body its lightcurve; then
        the attitude as the transform orbital -> body on /tf.
        """
        blocks = self._encoder.simulator(block.stamps, block.omega, block.quaternion,
                                         block.euler, clock=self._pub_clock is not None,
                                         perturber=block.perturber,
                                         lightcurve=block.lightcurve)
        publishers = [self._sample_publishers[topic].publish for topic, _ in blocks]
        rows = [rows for _, rows in blocks]
        publishers.append(self._pub_tf.publish)     # the attitude on /tf, last
        rows.append(self._transforms.encode(block.stamps, block.quaternion))
        for j in range(len(block)):
            for publish, block_rows in zip(publishers, rows):
                publish(block_rows[j].tobytes())

    def _publish_fixed(self, stamp_ns: int) -> None:
        """Publish what is sent once, at the run's start: /tf_static, body_markers (latched)."""
        self._pub_tf_static.publish(self._transforms.static(stamp_ns))
        if self._scene is not None and self._pub_body_markers is not None:
            self._pub_body_markers.publish(self._scene.body_bytes(stamp_ns))

    def _publish_markers(self, block: SampleBlock) -> None:
        """Publish the 3D scene of the block's samples that get one (decimation)."""
        if self._scene is None or self._pub_markers is None:
            return
        rows = self._scene.encode_samples(self._grid, self._marker_every, block.start,
                                          len(block),
                                          {'omega': block.omega, 'quaternion': block.quaternion})
        for row in rows:
            self._pub_markers.publish(row.tobytes())

    def _publish_impact_event(self, ended: ImpactEnded) -> None:
        """Publish the event of an impact that ended; say so in the log."""
        event = impact_message(ended)
        self._pub_events.publish(event)
        impact = ended.impact
        self.get_logger().info(f'impact {event.id} applied on '
                               f'[{impact.start:.9g}, {impact.end:.9g}] yr: '
                               f'delta w = {np.round(ended.delta_omega, 9).tolist()} rad/yr')

    # -- latched topics -----------------------------------------------------------------
    def _publish_change(self, change: StatusChange) -> None:
        """Publish a status (the session's state changes: log the run's end)."""
        if change.state == DIVERGED:
            self.get_logger().error(f'integration stopped: {change.message}')
        self._status_message = change.message
        self._pub_status.publish(status_message(change))
        if change.state == FINISHED:
            wall = time.monotonic() - (self._started_wall or time.monotonic())
            unit = self.scenario.time_unit
            self.get_logger().info(
                f'finished at t = {from_years(self.t, unit):g} {unit}: '
                f'{self.published_samples} samples in {wall:.1f} '
                's wall (the simulator records nothing: a recorder or bringup does)')

    def _publish_status(self, message: str) -> None:
        """Publish the state, t and ``message``, stamped with simulated time like every sample."""
        self._publish_change(self._session.status(message))

    def _on_status_period(self) -> None:
        if self.state == RUNNING:
            self._publish_status(self._status_message)

    # -- services -----------------------------------------------------------------------
    def _on_apply_impact(self, request: Any, response: Any) -> Any:
        response.accepted = False
        frame = FRAMES.get(request.frame)
        if frame is None:
            response.message = (f'frame: unknown frame {request.frame} '
                                '(FRAME_BODY=0, FRAME_ORBITAL=1)')
            return response
        if self.state in (FINISHED, DIVERGED):
            response.message = 'the simulation has ended: no impact can be applied'
            return response
        if self._session.impacts_in_progress >= MAX_PENDING_IMPACTS:
            response.message = (f'too many impacts in progress ({MAX_PENDING_IMPACTS} accepted '
                                'and not yet ended): retry after some have ended')
            return response
        per = self._years_per_unit               # the request is in the scenario's time_unit
        start = self.t if request.start_now else request.start * per
        per2 = per * per
        torque = (request.torque.x / per2, request.torque.y / per2, request.torque.z / per2)
        try:
            impact = Impact(start, request.duration * per, torque, frame)
            self._limits.check(impact, now=self.t, end=self.scenario.duration)
        except ScenarioError as err:
            response.message = str(err)
            return response
        impact_id, self._next_id = self._next_id, self._next_id + 1
        self._session.request_impact(impact, impact_id)
        response.accepted, response.id = True, impact_id
        unit = self.scenario.time_unit
        response.scheduled_start = from_years(impact.start, unit)
        response.scheduled_end = from_years(impact.end, unit)
        response.message = (f'impact {impact_id} scheduled on [{response.scheduled_start:.9g}, '
                            f'{response.scheduled_end:.9g}] {unit}')
        self.get_logger().info(response.message)
        return response

    def _on_pause(self, request: Any, response: Any) -> Any:
        change = self._session.pause()
        if change is None:
            response.success, response.message = False, f'not running (state {self.state})'
            return response
        self._publish_change(change)
        response.success, response.message = True, f'paused at t = {self.t!r} yr'
        return response

    def _on_resume(self, request: Any, response: Any) -> Any:
        if self.state != PAUSED:
            response.success, response.message = False, f'not paused (state {self.state})'
            return response
        self._pace_origin = None
        change = self._session.resume()
        if change is not None:
            self._publish_change(change)
        response.success, response.message = True, f'resumed at t = {self.t!r} yr'
        return response

    def _on_step(self, request: Any, response: Any) -> Any:
        if self.state != PAUSED:
            response.success, response.message = (
                False, f'step needs the simulation paused (state {self.state})')
            return response
        self._publish_up_to(self._session.samples)
        if self.state == PAUSED:
            self._publish_status(f'stepped to t = {self.t:g} yr')
        response.success = self.state != DIVERGED
        response.message = f'stepped to t = {self.t!r} yr'
        return response


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run tumble_ros sim``."""
    return run_node(SimNode, args, 'sim', needs_params_section=True)


if __name__ == '__main__':
    raise SystemExit(main())

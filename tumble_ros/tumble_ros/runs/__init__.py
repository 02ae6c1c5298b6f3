"""
The run layer: what one run does, once, without ROS (issue 26).

- :mod:`.records`: the plain records a run produces (samples, segment starts, impacts that
  ended, status changes, comparison blocks);
- :mod:`.session`: :class:`~.session.SimulationSession`, what the simulator does each batch;
- :mod:`.comparison`: :class:`~.comparison.Comparison`, the model anchored on each segment and
  compared with the samples;
- :mod:`.offline`: the offline recording, the records written to MCAP (the one module here
  that uses ROS's serialisation; import it by its name).

The session and the comparison return records and never publish or write: the live nodes
(:mod:`tumble_ros.nodes`) turn them into messages, the offline recording writes them.
"""

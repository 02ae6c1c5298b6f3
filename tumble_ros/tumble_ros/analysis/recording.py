"""
Load a tumble_ros MCAP recording into numpy arrays, in one pass, without a ROS runtime.

    from tumble_ros.analysis import load_recording
    rec = load_recording("run.mcap")
    rec.t, rec.omega                # (n,), (n, 3): simulated years, rad/yr (body axes)
    rec.quaternion_t, rec.quaternion  # (m,), (m, 4): scalar first (w, x, y, z), body -> orbital
    rec.perturber_t, rec.perturber    # the torquing body [km], body axes (Kepler orbits only)
    rec.lightcurve_t, rec.lightcurve  # (k,), (k, 8): the lightcurve topic (magnitude column 1)
    rec.impacts, rec.scenario, rec.topics

Every stamped series keeps its own time axis (the simulator may publish the attitude less
often than the angular velocity, the comparator may decimate). Times are simulated years,
t = stamp_ns / (1e9 * seconds_per_year) (:class:`tumble_ros.core.TimeBase`), with
``seconds_per_year`` from the recorded ``/scenario`` (1.0 if there is none). Samples are
sorted by stamp (stable), so a file written out of order still gives monotonic series.

Any topic may be absent: its arrays are then empty (shape (0, k)) and the optional objects
None. Only ``/angular_velocity`` is required (:class:`tumble_ros.errors.AnalysisError`
otherwise: a readable file the analysis cannot work on, one-line message). File-level
failures (missing, empty, not MCAP, truncated before the first complete chunk, undecodable
message) are :class:`tumble_ros.io.McapError`. A file truncated after some complete chunks
loads what it holds; ``finalised`` is then False and ``problem`` says why reading stopped.

Topics and namespaces: the names, types and frames are :mod:`tumble_ros.topics`' (relative
names, as the nodes publish them); a simulator started in a namespace (``--ros-args -r
__ns:=/ast1``) publishes ``/ast1/angular_velocity``, ..., and
:func:`tumble_ros.topics.in_namespace` is the one place that puts a namespace in front of a
name (:meth:`Recording.topic`). ``load_recording`` reads one namespace: the one given, or the
only one whose ``angular_velocity`` topic is in the file (:func:`find_namespaces`); with several
it refuses and lists them.

Runs: every ``/scenario`` description carries its run's ``run_id``
(:func:`tumble_ros.runs.messages.builders.new_run_id`). ``load_recording`` reads one run: the one
given (``run``), or the only one. Descriptions without a run id beside a run's (a foreign
publisher's) are counted, reported in :attr:`Recording.left_out` and left out; descriptions of
several runs (two simulators shared the topics, so their samples mix on the same topics) are
refused unless ``run`` chooses one. A recording whose descriptions carry no run id (older files)
is read whole.
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
import math
import os
from pathlib import Path
import re
import sys
from typing import Any, TextIO

import numpy as np

from tumble_ros.core import parse_scenario, Scenario, ScenarioError, TimeBase
from tumble_ros.errors import AnalysisError
from tumble_ros.io import (McapSummary, read_columns, sample_values, summarize,
                           written_columns, WrittenMessages)
from tumble_ros.topics import (ANGULAR_VELOCITY, ATTITUDE, COMPARISON_STATUS, ERROR, ERROR_NORM,
                               EULER_ANGLES, FRAME_BODY, FRAME_ORBITAL, IMPACT_EVENTS,
                               in_namespace, LIGHTCURVE, MODEL_ANGULAR_VELOCITY, PERTURBER,
                               sample_topic, SAMPLE_TOPICS, SCENARIO, STATUS, TYPES)

__all__ = [
    'EXPECTED_TYPES', 'ROOT_NAMESPACE', 'AnalysisError', 'ImpactRecord', 'SegmentStart',
    'StatusRecord', 'ComparatorStatus', 'Recording', 'find_namespaces', 'load_recording',
    'normalize_namespace', 'stderr_progress',
]

#: The topics the analysis decodes (relative names), with the type each must have
#: (:data:`tumble_ros.topics.TYPES`). Other topics (``/clock``, ``consumer_progress``, service
#: events) are only counted.
EXPECTED_TYPES = {topic: TYPES[topic] for topic in (
    ANGULAR_VELOCITY, ATTITUDE, EULER_ANGLES, IMPACT_EVENTS, SCENARIO, STATUS, PERTURBER,
    MODEL_ANGULAR_VELOCITY, ERROR, ERROR_NORM, COMPARISON_STATUS, LIGHTCURVE)}

#: The per-sample topics read as columns: topic -> its value fields, in the columns' order
#: (their descriptions, :data:`tumble_ros.topics.SAMPLE_TOPICS`).
_COLUMNS = {t.name: t.fields for t in SAMPLE_TOPICS}

#: SimStatus states (tumble_ros_interfaces/msg/SimStatus.msg).
SIM_STATES = {0: 'RUNNING', 1: 'PAUSED', 2: 'FINISHED', 3: 'DIVERGED'}
#: DiagnosticStatus levels.
DIAGNOSTIC_LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
#: ImpactEvent frames.
IMPACT_FRAMES = {0: FRAME_BODY, 1: FRAME_ORBITAL}


# -- namespaces -------------------------------------------------------------------------------

ROOT_NAMESPACE = '/'
_NAME_TOKEN = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')


def normalize_namespace(namespace: str) -> str:
    """
    Return ``'/ast1'`` for ``'ast1'``, ``'/ast1/'`` or ``'/ast1'``; ``'/'`` for ``''``.

    AnalysisError for a name that is not a ROS namespace.
    """
    tokens = [token for token in str(namespace).strip().split('/') if token]
    bad = [token for token in tokens if not _NAME_TOKEN.fullmatch(token)]
    if bad:
        raise AnalysisError(f'not a ROS namespace: {namespace!r} (each name in it is letters, '
                            f'digits and _, not starting with a digit)')
    return '/' + '/'.join(tokens)


def find_namespaces(names: dict[str, str] | Iterable[str]) -> list[str]:
    """
    Return the namespaces that hold an ``angular_velocity`` topic, sorted.

    ``names``: topic names, or a mapping topic -> type name; with types, only the namespaces
    whose ``angular_velocity`` has the expected type count, unless none has.
    """
    types = names if isinstance(names, dict) else dict.fromkeys(names)
    suffix = in_namespace(ROOT_NAMESPACE, ANGULAR_VELOCITY)      # /angular_velocity
    found = {name[:-len(suffix)] or ROOT_NAMESPACE: type_name
             for name, type_name in types.items() if name.endswith(suffix)}
    typed = [ns for ns, type_name in found.items()
             if type_name == EXPECTED_TYPES[ANGULAR_VELOCITY]]
    return sorted(typed or found)


def _choose_namespace(path: Path, types: dict[str, str], namespace: str | None) -> str:
    """Return the namespace to analyse: ``namespace`` (normalised), or the only one."""
    found = find_namespaces(types)
    if namespace is not None:
        namespace = normalize_namespace(namespace)
        if in_namespace(namespace, ANGULAR_VELOCITY) in types:
            return namespace
        where = (f'namespaces with the tumble topics: {", ".join(found)}' if found
                 else f'topics: {", ".join(sorted(types)) or "none"}')
        raise AnalysisError(f'{path}: no {in_namespace(namespace, ANGULAR_VELOCITY)} topic in '
                            f'namespace {namespace} ({where})')
    if len(found) > 1:
        raise AnalysisError(f'{path}: the tumble topics are in {len(found)} namespaces: '
                            f'{", ".join(found)}; choose one with --namespace')
    if not found:
        present = ', '.join(sorted(types)) or 'none'
        raise AnalysisError(f'{path}: no {in_namespace(ROOT_NAMESPACE, ANGULAR_VELOCITY)} '
                            f'topic: not a tumble_ros simulator recording (topics: {present})')
    return found[0]


@dataclass(frozen=True)
class ImpactRecord:
    """One ``/impact_events`` message (times in years, rates in rad/yr)."""

    id: int  # noqa: A003 (public field, as in the ImpactEvent message)
    start: float
    end: float
    frame: str                      # 'body' or 'orbital' (or 'frame <n>' if unknown)
    torque: tuple[float, float, float]
    delta_omega: tuple[float, float, float]
    t: float                        # the message's stamp as simulated time (= end)

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class SegmentStart:
    """One ``/scenario`` message: the state an integration segment starts from."""

    revision: int
    segment_start: float
    omega: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]   # (w, x, y, z)


@dataclass(frozen=True)
class StatusRecord:
    """One ``/status`` message."""

    t: float
    state: str
    message: str


@dataclass(frozen=True)
class ComparatorStatus:
    """The last ``/comparison/status`` message."""

    level: str
    message: str
    values: dict[str, str]


def _empty(k: int) -> np.ndarray:
    return np.empty((0, k))


@dataclass
class Recording:
    """A recording's content as arrays (see the module docstring)."""

    path: Path
    finalised: bool
    problem: str | None
    #: topic -> (type name, message count) of every topic in the file.
    topics: dict[str, tuple[str, int]]
    seconds_per_year: float
    seconds_per_year_source: str            # the scenario topic's full name, or 'default'
    t: np.ndarray                           # (n,) [yr] of /angular_velocity
    omega: np.ndarray                       # (n, 3) [rad/yr]
    stamp_ns: np.ndarray                    # (n,) int64, the stamps of t
    euler_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    euler: np.ndarray = field(default_factory=lambda: _empty(3))          # (phi, psi, theta)
    quaternion_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    quaternion: np.ndarray = field(default_factory=lambda: _empty(4))     # (w, x, y, z)
    perturber_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    perturber: np.ndarray = field(default_factory=lambda: _empty(3))      # [km], body axes
    lightcurve_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    # the lightcurve topic's fields (topics.SAMPLE_TOPICS: brightness, magnitude, ...)
    lightcurve: np.ndarray = field(default_factory=lambda: _empty(8))
    model_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    model_omega: np.ndarray = field(default_factory=lambda: _empty(3))
    error_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    error: np.ndarray = field(default_factory=lambda: _empty(3))          # w_numeric - w_model
    norm_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    error_norm: np.ndarray = field(default_factory=lambda: np.empty(0))   # |error| [rad/yr]
    error_relative: np.ndarray = field(default_factory=lambda: np.empty(0))
    error_models: tuple[str, ...] = ()      # model names of /comparison/error_norm, in order seen
    comparator_status: ComparatorStatus | None = None
    impacts: list[ImpactRecord] = field(default_factory=list)
    segments: list[SegmentStart] = field(default_factory=list)
    scenario: Scenario | None = None        # from the last parsable /scenario
    scenario_error: str | None = None       # why /scenario could not be parsed
    status: list[StatusRecord] = field(default_factory=list)
    #: Topics present but skipped because their type is not the expected one.
    skipped: dict[str, str] = field(default_factory=dict)
    #: The namespace whose topics were read ('/' for the root namespace).
    namespace: str = ROOT_NAMESPACE
    #: One line per kind of sample left out of the arrays (non-finite samples, ...).
    left_out: list[str] = field(default_factory=list)
    #: The run read (the run_id of its /scenario descriptions; '' when they carry none).
    run_id: str = ''

    @property
    def n(self) -> int:
        return len(self.t)

    def topic(self, name: str) -> str:
        """Return the full name in this namespace of ``name``, a tumble topic's relative name."""
        return in_namespace(self.namespace, name)

    @property
    def has_comparator(self) -> bool:
        return bool(len(self.error_norm) or len(self.error_t) or len(self.model_t))


#: progress(messages_done, messages_total)
Progress = Callable[[int, int], None]


def stderr_progress(min_total: int = 100_000, stream: TextIO | None = None) -> Progress:
    """
    Return a progress callback that prints every 10 % to ``stream`` (default: stderr).

    It prints ``reading FILE: 40% (400000 of 1000000 messages)``, for files of at least
    ``min_total`` messages (silent otherwise).
    """
    state = {'next': 0.1}

    def report(done: int, total: int) -> None:
        out = stream or sys.stderr
        if total < min_total or total <= 0:
            return
        fraction = done / total
        if fraction >= state['next']:
            print(f'reading: {min(fraction, 1.0):4.0%} ({done} of {total} messages)', file=out,
                  flush=True)
            state['next'] = math.floor(fraction * 10 + 1) / 10
    return report


def _vec(v) -> tuple[float, float, float]:
    return (float(v.x), float(v.y), float(v.z))


def _ns(header) -> int:
    return TimeBase.stamp_ns(header.stamp.sec, header.stamp.nanosec)


def _level(value) -> str:
    if isinstance(value, (bytes, bytearray)):
        value = value[0] if value else 0
    try:
        return DIAGNOSTIC_LEVELS.get(int(value), str(value))
    except (TypeError, ValueError):
        return str(value)


def _sorted(ns, rows, k: int, *, owned: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the stamps and the (n, k) values, ordered by stamp (stable).

    Copies, unless ``owned`` (``ns`` and ``rows`` are arrays no one else holds, as
    :func:`load_recording`'s columns: in order, they are returned as they are).
    """
    stamps = np.asarray(ns, dtype=np.int64)
    values = np.asarray(rows, dtype=float).reshape(-1, k) if len(rows) else _empty(k)
    if not len(stamps) or bool((stamps[1:] >= stamps[:-1]).all()):
        if owned:                               # in order already (recordings are): no sort
            return stamps, values
        return stamps.copy(), values.copy()
    order = np.argsort(stamps, kind='stable')
    return stamps[order], values[order]


def _steps_back(ns) -> int:
    """Count the stamps earlier than the one before them (in the file's order)."""
    stamps = np.asarray(ns, dtype=np.int64)
    return int((stamps[1:] < stamps[:-1]).sum()) if len(stamps) > 1 else 0


def _select_topics(info, namespace: str | None
                   ) -> tuple[str, dict[str, str], dict[str, str]]:
    """Return (namespace, {full name: root name} of the topics to decode, {skipped: why})."""
    types = {name: t.type_name for name, t in info.topics.items()}
    namespace = _choose_namespace(info.path, types, namespace)
    wanted: dict[str, str] = {}
    skipped: dict[str, str] = {}
    for topic, expected in EXPECTED_TYPES.items():
        full = in_namespace(namespace, topic)
        if full not in types:
            continue
        if types[full] != expected:
            skipped[full] = f'type {types[full]}, expected {expected}'
        else:
            wanted[full] = topic
    velocity = in_namespace(namespace, ANGULAR_VELOCITY)
    if velocity in skipped:
        raise AnalysisError(f'{info.path}: {velocity} has {skipped[velocity]}')
    return namespace, wanted, skipped


def _runs_text(counts: dict[str, int]) -> str:
    return ', '.join(f"{run or 'no run id'}: {n}" for run, n in counts.items())


def _own_run(path: Path, topic: str, scenarios: list, run: str | None
             ) -> tuple[str, list, list[str], bool]:
    """
    Return (the run read, its descriptions, lines on what was left out, other runs?).

    ``scenarios``: the (stamp, message) of every description; other runs: descriptions of
    another run id are among them (another simulator published its samples on the topics too).

    ``run``: the run id chosen (None: the only run in the file). AnalysisError for a run that is
    not in the file, or for several runs and none chosen.
    """
    ids = [getattr(msg, 'run_id', '') for _, msg in scenarios]   # older schemas have none
    counts = dict(Counter(ids))             # in order of first appearance
    named = [r for r in counts if r]
    if run is not None:
        if run not in named:
            raise AnalysisError(f'{path}: no run {run!r} in {topic} (descriptions per run: '
                                f'{_runs_text(counts) or "none"})')
        own = run
    elif len(named) > 1:
        raise AnalysisError(f'{path}: {topic} holds the descriptions of {len(named)} runs '
                            f'({_runs_text(counts)}): two simulators shared these topics and '
                            'their samples are mixed; choose one with --run ID')
    elif named:
        own = named[0]
    else:
        return '', scenarios, [], False
    others = {r: n for r, n in counts.items() if r != own}
    lines = []
    if others:
        lines.append(f'{topic}: left out {sum(others.values())} of {len(ids)} descriptions '
                     f'that are not of run {own} ({_runs_text(others)}: a foreign publisher)')
    return own, [d for d, r in zip(scenarios, ids) if r == own], lines, any(others.keys() - {''})


def _same_file(written: WrittenMessages | None, info: McapSummary) -> bool:
    """Whether ``written`` holds every message of the finalised file ``info`` summarises."""
    if written is None or not written.closed or written.path is None or not info.finalised:
        return False
    try:
        if not os.path.samefile(written.path, info.path):
            return False
    except OSError:
        return False
    return written.counts() == {name: t.message_count for name, t in info.topics.items()}


def load_recording(path: str | os.PathLike[str], *, namespace: str | None = None,
                   run: str | None = None, progress: Progress | None = None,
                   written: WrittenMessages | None = None) -> Recording:
    """
    Read ``path`` once and return its :class:`Recording`.

    ``written``: the messages the writer of ``path`` kept in this process
    (:class:`tumble_ros.io.WrittenMessages`, ``McapWriter(..., keep=written)``); when it holds
    every message of the finalised file (per topic), the columns are gathered from it instead of
    reading the file back (:func:`tumble_ros.io.written_columns`): the same Recording
    (tests/test_io_written.py), a second faster. Otherwise the file is read.

    ``namespace``: the ROS namespace of the topics to read (``'/ast1'``, ``'/'`` for the root);
    None: the only namespace in the file that has an ``angular_velocity`` topic. ``run``: the
    run id whose descriptions to use (None: the only run; see the module docstring).
    Raises :class:`McapError` for an unreadable file and :class:`AnalysisError` when it has no
    ``angular_velocity`` messages in that namespace (or that topic has another type), or when
    ``namespace`` is None and several namespaces have them. ``progress`` is called as
    ``progress(done, total)`` while reading (``total`` from the file's statistics); not when the
    columns come from ``written`` (nothing is read).
    """
    info = summarize(path)
    topics = {name: (t.type_name, t.message_count) for name, t in info.topics.items()}
    namespace, wanted, skipped = _select_topics(info, namespace)

    # Raw columns, stamps as integer ns (seconds_per_year may only be known later in the file).
    raw: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    impacts_raw: list[tuple[int, Any]] = []  # (stamp [ns], ROS message)
    scenarios: list[tuple[int, Any]] = []
    statuses: list[tuple[int, Any]] = []
    norm_models: list[str] = []
    comparator_status = None
    # The per-sample topics as numpy columns (io.columns: ~1 M messages/s), the rest decoded.
    per_sample = {full for full, topic in wanted.items() if topic in _COLUMNS}
    total = max(1, info.message_count)
    from_memory = _same_file(written, info)

    def report(done: int) -> None:
        if progress is not None and not from_memory:
            progress(min(done, total), total)

    if from_memory:
        assert written is not None
        # nothing is read: no "reading: N%" lines (the gathering takes ~0.1 s at 1.4 M messages)
        columns, messages = written_columns(written, sorted(per_sample),
                                            as_messages=sorted(set(wanted) - per_sample))
    else:
        columns, messages = read_columns(info.path, sorted(per_sample),
                                         as_messages=sorted(set(wanted) - per_sample),
                                         progress=report)
    for full, table in columns.items():
        topic = wanted[full]
        raw[topic] = sample_values(table, sample_topic(topic))
        if topic == ERROR_NORM:
            norm_models.extend(table.strings['model'])
    for record in messages:
        topic, msg = wanted[record.topic], record.message
        if topic == IMPACT_EVENTS:
            impacts_raw.append((_ns(msg.header), msg))
        elif topic == SCENARIO:
            scenarios.append((_ns(msg.header), msg))
        elif topic == STATUS:
            statuses.append((_ns(msg.header), msg))
        elif topic == COMPARISON_STATUS:
            comparator_status = ComparatorStatus(
                level=_level(msg.level), message=str(msg.message),
                values={str(kv.key): str(kv.value) for kv in msg.values})
    report(total)
    scenario_topic = in_namespace(namespace, SCENARIO)
    run_id, scenarios, left_out, mixed = _own_run(info.path, scenario_topic, scenarios, run)

    # The time base: the first /scenario's seconds_per_year.
    spy, spy_source = 1.0, 'default'
    for _, msg in scenarios:
        value = float(msg.seconds_per_year)
        if math.isfinite(value) and value > 0:
            spy, spy_source = value, in_namespace(namespace, SCENARIO)
            break
    timebase = TimeBase(spy)

    def years(ns: np.ndarray) -> np.ndarray:
        return ns.astype(np.float64) / timebase.ns_per_year

    stamp_ns, rows = raw.get(ANGULAR_VELOCITY, ([], []))
    back = _steps_back(stamp_ns)
    if back:    # one simulator writes its samples in time order
        left_out.append(f'{in_namespace(namespace, ANGULAR_VELOCITY)}: the stamps go back '
                        f'{back} times in the file: more than one publisher wrote samples on it '
                        '(another run, a test tool or a replay)')
    stamps, omega = _sorted(stamp_ns, rows, 3, owned=True)
    if mixed:   # another run chosen away: its samples are on the same topic, not separable
        shared = len(stamps) - len(np.unique(stamps))
        left_out.append(f'{in_namespace(namespace, ANGULAR_VELOCITY)}: the samples of the other '
                        f"runs cannot be told apart from run {run_id}'s and are kept "
                        f'({shared} samples share their stamp with another)')
    finite = np.isfinite(omega).all(axis=1)
    if not finite.all():   # a foreign publisher's NaN: the analysis takes the rest
        left_out.append(f'{in_namespace(namespace, ANGULAR_VELOCITY)}: left out '
                        f'{int((~finite).sum())} of {len(finite)} samples that are not finite '
                        '(NaN or infinite: a foreign publisher?)')
        stamps, omega = stamps[finite], omega[finite]
    if len(stamps) == 0:
        raise AnalysisError(f'{info.path}: {in_namespace(namespace, ANGULAR_VELOCITY)} has no '
                            f'messages'
                            + ('' if info.finalised else f' (file truncated: {info.problem})'))
    rec = Recording(path=info.path, finalised=info.finalised, problem=info.problem,
                    topics=topics, seconds_per_year=spy, seconds_per_year_source=spy_source,
                    t=years(stamps), omega=omega, stamp_ns=stamps, skipped=skipped,
                    namespace=namespace, left_out=left_out, run_id=run_id)
    if EULER_ANGLES in raw:
        ns, rec.euler = _sorted(*raw[EULER_ANGLES], 3, owned=True)
        rec.euler_t = years(ns)
    if ATTITUDE in raw:
        ns, rec.quaternion = _sorted(*raw[ATTITUDE], 4, owned=True)
        rec.quaternion_t = years(ns)
    if PERTURBER in raw:
        ns, rec.perturber = _sorted(*raw[PERTURBER], 3, owned=True)
        rec.perturber_t = years(ns)
    if LIGHTCURVE in raw:
        ns, rec.lightcurve = _sorted(*raw[LIGHTCURVE], len(_COLUMNS[LIGHTCURVE]), owned=True)
        rec.lightcurve_t = years(ns)

    def compared(topic: str, k: int, finite: int) -> tuple[np.ndarray, np.ndarray]:
        """
        Return the comparisons of ``topic`` at the kept samples' stamps (the rest left out, said).

        ``finite``: the leading columns that must be finite (an error norm's relative error is
        infinite at a zero rate, and kept).
        """
        ns, values = _sorted(*raw[topic], k, owned=True)
        at_samples = (np.array_equal(ns, stamps)      # (every sample compared: no search)
                      or np.isin(ns, stamps))
        keep = at_samples & np.isfinite(values[:, :finite]).all(axis=1)
        if not keep.all():
            left_out.append(f'{in_namespace(namespace, topic)}: left out {int((~keep).sum())} '
                            f'of {len(keep)} comparisons that are not of a sample of the run '
                            '(not finite, or at a stamp with no finite sample of '
                            f'{ANGULAR_VELOCITY}: a foreign publisher?)')
            ns, values = ns[keep], values[keep]
        return ns, values

    if MODEL_ANGULAR_VELOCITY in raw:
        ns, rec.model_omega = compared(MODEL_ANGULAR_VELOCITY, 3, 3)
        rec.model_t = years(ns)
    if ERROR in raw:
        ns, rec.error = compared(ERROR, 3, 3)
        rec.error_t = years(ns)
    if ERROR_NORM in raw:
        ns, values = compared(ERROR_NORM, 2, 1)
        rec.norm_t = years(ns)
        rec.error_norm, rec.error_relative = values[:, 0].copy(), values[:, 1].copy()
        rec.error_models = tuple(norm_models)
    rec.comparator_status = comparator_status

    for stamp, msg in sorted(impacts_raw, key=lambda item: item[0]):
        frame = int(msg.frame)
        rec.impacts.append(ImpactRecord(
            id=int(msg.id), start=float(msg.start), end=float(msg.end),
            frame=IMPACT_FRAMES.get(frame, f'frame {frame}'), torque=_vec(msg.torque),
            delta_omega=_vec(msg.delta_omega), t=timebase.to_years(stamp)))
    for _, msg in scenarios:
        q = msg.attitude
        rec.segments.append(SegmentStart(
            revision=int(msg.revision), segment_start=float(msg.segment_start),
            omega=_vec(msg.omega), quaternion=(float(q.w), float(q.x), float(q.y), float(q.z))))
    # Every description holds the scenario as started; the first of a run (revision 0) with its
    # scheduled impacts, the later ones without. The last revision 0 readable, else the last
    # one readable (a recorder that started late).
    latest_first = list(reversed(scenarios))
    for _, msg in ([d for d in latest_first if int(d[1].revision) == 0]
                   + [d for d in latest_first if int(d[1].revision) != 0]):
        try:
            rec.scenario = parse_scenario(msg.parameters_yaml)
            rec.scenario_error = None
            break
        except (ScenarioError, ValueError, TypeError) as err:   # a description we cannot use
            rec.scenario_error = ' '.join(str(err).split()) or type(err).__name__
    for _, msg in statuses:
        state = int(msg.state)
        rec.status.append(StatusRecord(t=float(msg.t), state=SIM_STATES.get(state, str(state)),
                                       message=str(msg.message)))
    return rec

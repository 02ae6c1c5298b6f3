"""
What a recording shows: every number of the summary, computed in one call.

    from tumble_ros.analysis import load_recording, analyze, format_summary, summary_to_dict
    summary = analyze(load_recording("run.mcap"))
    print(format_summary(summary))          # text
    summary_to_dict(summary)                # JSON-safe dict (NaN/inf -> None)

:func:`analyze` gathers the concerns, each in its module: the time axis (``timeaxis``), the
comparator's error (``comparator``), the Jacobi-integral drift per segment (``invariants``),
the impacts (``impacts``), the theory's frequency lines and the aliasing check (``theory``),
the dominant frequencies of wx (``spectrum``), and the text and JSON (``report``). Their
names are re-exported here. How each number is computed is documented in docs/analysis.md.
Units: simulated years [yr], rad/yr (w in body axes), inertia normalised; the text and the
figures show them in :attr:`AnalysisSummary.units` (``display``: hours and rad/h for a flyby).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

from tumble_ros.topics import ANGULAR_VELOCITY, SCENARIO

from .comparator import comparator_errors, ErrorStats
from .display import DisplayUnits, is_flyby, recording_units
from .impacts import impact_intervals, impact_summaries, ImpactSummary
from .invariants import InvariantDrift, jacobi_drift, JacobiSegment
from .recording import Recording, ROOT_NAMESPACE
from .spectrum import Peak, Spectrum, spectrum
from .spin import closest_approach, spin_change, SpinChange
from .theory import AliasingCheck, check_aliasing, theory_lines, TheoryLine
from .timeaxis import Sampling, sampling

__all__ = [
    'AliasingCheck', 'AnalysisSummary', 'ErrorStats', 'ImpactSummary', 'InvariantDrift',
    'JacobiSegment', 'SummaryParts', 'Peak', 'Sampling', 'Spectrum', 'TheoryLine',
    'analyze', 'check_aliasing', 'comparator_errors', 'impact_intervals',
    'impact_summaries', 'jacobi_drift', 'sampling', 'spectrum',
    'theory_lines',
]


@dataclass(frozen=True)
class AnalysisSummary:
    """Everything the summary reports about one recording (one namespace of it)."""

    path: str
    finalised: bool
    problem: str | None
    topics: dict[str, tuple[str, int]]
    seconds_per_year: float
    seconds_per_year_source: str
    sampling: Sampling
    scenario: dict | None                    # the scenario's parameters (flat, as ROS params)
    scenario_error: str | None
    final_status: str | None                 # 'FINISHED at t = 2 yr: reached duration'
    comparator: ErrorStats | None
    comparator_note: str | None
    invariant: InvariantDrift | None
    invariant_note: str | None
    impacts: tuple[ImpactSummary, ...]
    theory_basis: str
    theory: tuple[TheoryLine, ...]
    spectrum: Spectrum | None
    aliasing: AliasingCheck
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    namespace: str = ROOT_NAMESPACE          # the ROS namespace whose topics were analysed
    spin: SpinChange | None = None           # the tumbling state at the start and the end
    spin_note: str | None = None
    closest_approach: tuple[float, float] | None = None   # (t [yr], km) of /perturber
    units: DisplayUnits | None = None        # what the text and the figures show it in
    flyby: bool = False                      # the torquing body passes on a hyperbola


def analyze(rec: Recording, *, n_peaks: int = 5) -> AnalysisSummary:
    """Everything the summary reports, computed from a loaded recording."""
    warnings: list[str] = []
    notes: list[str] = []
    if not rec.finalised:
        warnings.append(f'the file is truncated ({rec.problem}): analysed the messages of its '
                        f'complete chunks only')
    for topic, why in rec.skipped.items():
        notes.append(f'{topic} skipped: {why}')
    samp = sampling(rec.t)
    if samp.duplicates:
        warnings.append(f'{samp.duplicates} repeated stamps on {rec.topic(ANGULAR_VELOCITY)} '
                        f'(two runs in one file?)')
    if samp.gaps:
        notes.append(f'{samp.gaps} gaps longer than 1.5 dt in {rec.topic(ANGULAR_VELOCITY)}')
    if rec.seconds_per_year_source == 'default':
        notes.append(f'no {rec.topic(SCENARIO)}: seconds_per_year = 1 assumed')
    if rec.scenario_error:
        warnings.append(f'{rec.topic(SCENARIO)} could not be parsed: {rec.scenario_error}')

    units = recording_units(rec)
    final_status = None
    if rec.status:
        last = rec.status[-1]
        final_status = f'{last.state} at t = {units.time_text(last.t)}' + (
            f': {units.retime(last.message)}' if last.message else '')
        for s in rec.status:
            if s.state == 'DIVERGED':
                warnings.append(f'the simulation DIVERGED at t = {units.time_text(s.t)}: '
                                f'{units.retime(s.message)}')
        if last.state in ('RUNNING', 'PAUSED'):
            notes.append(f'the recording ends before the simulator finished (last status '
                         f'{last.state})')

    comparator, comparator_note = comparator_errors(rec)
    invariant, invariant_note = jacobi_drift(rec)
    lines, basis = theory_lines(rec.scenario, rec.omega)
    spec = _wx_spectrum(rec, lines, n_peaks)
    if spec is not None and spec.resampled:
        notes.append('wx was linearly interpolated onto a uniform grid for the spectrum '
                     '(uneven sampling)')
    spin, spin_note = spin_change(rec)
    aliasing = check_aliasing(samp, lines)
    if aliasing.warning:
        warnings.append(aliasing.warning)
    return AnalysisSummary(
        path=str(rec.path), finalised=rec.finalised, problem=rec.problem, topics=rec.topics,
        seconds_per_year=rec.seconds_per_year,
        seconds_per_year_source=rec.seconds_per_year_source, sampling=samp,
        scenario=rec.scenario.to_parameters() if rec.scenario is not None else None,
        scenario_error=rec.scenario_error, final_status=final_status,
        comparator=comparator, comparator_note=comparator_note,
        invariant=invariant, invariant_note=invariant_note, impacts=tuple(impact_summaries(rec)),
        theory_basis=basis, theory=tuple(lines), spectrum=spec, aliasing=aliasing,
        warnings=tuple(warnings), notes=tuple(notes), namespace=rec.namespace, spin=spin,
        spin_note=spin_note, closest_approach=closest_approach(rec), units=units,
        flyby=is_flyby(rec.scenario))


def _wx_spectrum(rec: Recording, lines: Sequence[TheoryLine], n_peaks: int) -> Spectrum | None:
    """Return the spectrum of wx the summary reports (and its figure draws)."""
    return spectrum(rec.t, rec.omega[:, 0], lines, n_peaks=n_peaks)


class SummaryParts:
    """
    The parts of :func:`analyze`'s summary the figures draw, computed when first asked for.

    ``comparator`` (its :class:`ErrorStats`: the time the model left the solution),
    ``theory`` (the theory's lines) and ``spectrum`` (of wx, ``n_peaks`` peaks), each by the
    call :func:`analyze` makes, on the same recording: the same values. The main job hands
    them, with the recording, to the processes that draw the figures
    (:mod:`.figure_pool`), which start before :func:`analyze` has run; each computes only
    what its figures take (~0.02 s each). Pickled before use: the recording alone.
    """

    def __init__(self, rec: Recording, n_peaks: int = 5) -> None:
        self.rec = rec
        self.n_peaks = n_peaks

    @cached_property
    def comparator(self) -> ErrorStats | None:
        """:attr:`AnalysisSummary.comparator`."""
        return comparator_errors(self.rec)[0]

    @cached_property
    def theory(self) -> tuple[TheoryLine, ...]:
        """:attr:`AnalysisSummary.theory`."""
        lines, _ = theory_lines(self.rec.scenario, self.rec.omega)
        return tuple(lines)

    @cached_property
    def spectrum(self) -> Spectrum | None:
        """:attr:`AnalysisSummary.spectrum`."""
        return _wx_spectrum(self.rec, self.theory, self.n_peaks)

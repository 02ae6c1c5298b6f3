"""
The summary as text and as JSON.

The text: one section per concern (file and topics, time axis, scenario, comparator error,
invariant drift, impacts, expected frequencies, spectrum, aliasing), then the notes and one
``WARNING:`` line per warning. The JSON: the same fields as plain types, NaN and inf as null.
The text is in the summary's display units (``display``: yr and rad/yr for the paper's runs,
h and rad/h for a flyby; directions in degrees, frame named); the JSON in the units as computed:
years [yr], rad/yr (body axes), J in normalised inertia times (rad/yr)^2, and ``units`` names
the display units.
"""
from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from tumble_ros.core import DEPARTURE
from tumble_ros.topics import ANGULAR_VELOCITY, in_namespace, SCENARIO

from .display import display_units, DisplayUnits
from .recording import ROOT_NAMESPACE

if TYPE_CHECKING:
    from tumble_ros.core.model.observables import SpinObservables

    from .summary import AnalysisSummary

__all__ = ['format_summary', 'summary_to_dict']


def _finite_or_none(x):
    return x if x is not None and math.isfinite(x) else None


def _g(x, digits: int = 6) -> str:
    if x is None:
        return '-'
    return f'{x:.{digits}g}'


def _v(v, digits: int = 6) -> str:
    return '(' + ', '.join(_g(x, digits) for x in v) + ')'


def _file(s: AnalysisSummary) -> list[str]:
    out = [f'recording: {s.path}']
    if s.namespace != ROOT_NAMESPACE:
        out.append(f'namespace: {s.namespace}')
    state = 'finalised' if s.finalised else f'TRUNCATED ({s.problem})'
    total = sum(count for _, count in s.topics.values())
    out.append(f'file: {state}, {len(s.topics)} topics, {total} messages')
    width = max((len(name) for name in s.topics), default=0)
    twidth = max((len(t) for t, _ in s.topics.values()), default=0)
    for name, (type_name, count) in sorted(s.topics.items()):
        out.append(f'  {name:<{width}}  {type_name:<{twidth}}  {count:>9}')
    return out


def _units(s: AnalysisSummary) -> DisplayUnits:
    """Return the units the summary is shown in (years for a summary built without them)."""
    return s.units if s.units is not None else display_units(math.inf)


def _time_and_scenario(s: AnalysisSummary) -> list[str]:
    out = []
    u = _units(s)
    p = s.sampling
    dt_min = p.dt_min if p.dt_min is not None else math.nan  # (set with dt)
    dt = (f'dt = {u.time_text(p.dt)}' + (' (uniform)' if p.uniform else
                                         f' (median; {_g(u.t(dt_min))} .. '
                                         f'{u.time_text(p.dt_max)})')
          if p.dt is not None else 'one sample')
    out.append(f'simulated time: {p.n} samples of {in_namespace(s.namespace, ANGULAR_VELOCITY)}, '
               f't = {_g(u.t(p.t_first))} .. '
               f'{u.time_text(p.t_last)}, duration {u.time_text(p.duration)}, {dt}')
    source = s.seconds_per_year_source
    out.append(f'time base: seconds_per_year = {_g(s.seconds_per_year)} '
               f'({"default" if source == "default" else f"from {source}"})')
    if s.scenario is not None:
        sc = s.scenario
        out.append(f"scenario: inertia {_v(sc['inertia'])}, orbit_rate "
                   f"{u.rate_text(sc['orbit_rate'])}, omega0 {_v(u.w(np.asarray(sc['omega0'])))} "
                   f"{u.rate}, euler0 {_v(sc['euler0'])} rad, duration "
                   f"{u.time_text(sc['duration'])}, output_interval "
                   f"{u.time_text(sc['output_interval'])}, {sc['integrator.method']}, "
                   f"{len(sc['impacts.start'])} scheduled impact(s)")
    else:
        out.append('scenario: none' + (f' ({s.scenario_error})' if s.scenario_error else
                                       f' (no {in_namespace(s.namespace, SCENARIO)} topic)'))
    if s.final_status:
        out.append(f'simulator status: {s.final_status}')
    return out


def _comparator(s: AnalysisSummary) -> list[str]:
    if s.comparator is None:
        return [f'comparator error: none ({s.comparator_note})']
    u = _units(s)
    c = s.comparator
    models = ', '.join(repr(m) for m in c.models) or 'unknown'
    out = [f'comparator error (model {models}; {c.n} samples from {c.source}):']
    out.append(f'  |w - w_model|: max {u.rate_text(c.max_abs)} at t = {u.time_text(c.t_max_abs)}, '
               f'RMS {u.rate_text(c.rms_abs)}')
    if c.max_rel is not None:
        out.append(f'  relative |w - w_model|/|w|: max {_g(c.max_rel)} at t = '
                   f'{u.time_text(c.t_max_rel)}, RMS {_g(c.rms_rel)}'
                   + (f' ({c.infinite_rel} samples with |w| = 0 left out)'
                      if c.infinite_rel else ''))
    if c.max_component is not None:
        out.append(f'  max |error| per component (x, y, z): '
                   f'{_v(u.w(np.asarray(c.max_component)))} {u.rate}')
    if c.t_departure is not None:
        out.append(f'  the model left the numeric solution at t = {u.time_text(c.t_departure)} '
                   f'(|w - w_model| > {DEPARTURE:g} |w|; {c.departed} of {c.n} samples beyond): '
                   'the w figure is scaled on the numeric solution, the model clipped')
    return out


def _invariant(s: AnalysisSummary) -> list[str]:
    if s.flyby:
        return []           # not conserved on a hyperbola: nothing to report
    if s.invariant is None:
        return [f'invariant drift: not computed ({s.invariant_note})']
    u = _units(s)
    inv = s.invariant
    out = [f"invariant drift: {inv.name} J = 1/2 w.Iw + 3/2 ws^2 u.Iu + ws (Iw).z' "
           f'(attitude from {inv.attitude_source}), per segment between impacts:']
    for seg in inv.segments:
        out.append(f'  segment {seg.index}: t = {_g(u.t(seg.t_start))} .. '
                   f'{u.time_text(seg.t_end)}, '
                   f'{seg.n} samples, J0 = {_g(seg.j0, 10)}, max |J - J0| = '
                   f'{_g(seg.max_drift, 3)} (relative {_g(seg.rel_drift, 3)})')
    if inv.excluded:
        out.append(f'  ({inv.excluded} samples inside a pulse left out)')
    return out


def _impacts(s: AnalysisSummary) -> list[str]:
    if not s.impacts:
        return ['impacts: none recorded']
    u = _units(s)
    out = [f'impacts: {len(s.impacts)}']
    for imp in s.impacts:
        e = imp.event
        out.append(f'  #{e.id}: {e.frame} torque {_v(u.torque(np.asarray(e.torque)))} '
                   f'{u.torque_unit} on [{_g(u.t(e.start), 10)}, '
                   f'{_g(u.t(e.end), 10)}] {u.time} ({u.time_text(e.duration, 3)}): delta_omega '
                   f'{_v(u.w(np.asarray(e.delta_omega)))} {u.rate}, |delta_omega| = '
                   f'{_g(u.w(math.hypot(*e.delta_omega)))}')
        if imp.sampled_jump is not None:
            assert imp.t_before is not None  # (a jump is measured between two samples)
            out.append(f'      recorded w jump between the samples at t = '
                       f'{_g(u.t(imp.t_before))} and {u.time_text(imp.t_after)}: '
                       f'{_v(u.w(np.asarray(imp.sampled_jump)))} {u.rate} '
                       '(includes the free motion between)')
    return out


def _frequencies(s: AnalysisSummary) -> list[str]:
    if s.flyby:
        # one passage: no line a spectrum could resolve, no sampling to alias
        return []
    u = _units(s)
    out = [f'expected frequencies: {s.theory_basis}']
    for line in s.theory:
        out.append(f'  {line.name:<20} {u.w(line.omega):12.6g} {u.rate}  (period '
                   f'{u.period_text(2 * math.pi / line.omega if line.omega else math.inf)})  '
                   f'{line.meaning}')
    sp = s.spectrum
    if sp is not None:
        out.append(f'dominant frequencies of {sp.component}: {sp.window} window, {sp.n} samples'
                   f'{" (resampled)" if sp.resampled else ""}, dt = {u.time_text(sp.dt)}, '
                   f'resolution {u.rate_text(sp.resolution, 4)}, Nyquist pi/dt = '
                   f'{u.rate_text(sp.nyquist)}')
        for k, peak in enumerate(sp.peaks, 1):
            match = ''
            if peak.nearest:
                assert peak.offset is not None  # (set with nearest)
                alias = (f' aliased to {_g(u.w(peak.omega - peak.offset))}'
                         if peak.nearest_aliased else '')
                match = (f', nearest line {peak.nearest} = {_g(u.w(peak.nearest_omega))}{alias} '
                         f'(offset {u.w(peak.offset):+.3g})')
            out.append(f'  {k}. {u.w(peak.omega):12.6g} {u.rate} (period '
                       f'{u.period_text(peak.period)}), amplitude '
                       f'{u.rate_text(peak.amplitude, 4)}{match}')
        if not sp.peaks:
            out.append('  no peak (constant signal)')
    else:
        out.append('dominant frequencies: fewer than 8 samples, no spectrum')
    al = s.aliasing
    if al.nyquist is not None and al.fastest is not None and not al.aliased:
        out.append(f'aliasing: none expected: Nyquist pi/dt = {u.rate_text(al.nyquist)} > '
                   f'fastest expected line {al.fastest.name} = {u.rate_text(al.fastest.omega)}')
    elif al.nyquist is None or al.fastest is None:
        out.append('aliasing: not checked (no expected frequencies or a single sample)')
    return out


def _pole(u: DisplayUnits, state) -> str:
    if state.pole_longitude is None:
        return ''
    return f', pole {u.direction_text(state.pole_longitude, state.pole_latitude)}'


def _block_text(block: SpinObservables) -> str:
    """Return the inertia ratios and phases of a ``spin.*`` block (its line has the rest)."""
    # (in [0, 360) after rounding at 1e-9 deg: 2 pi - 1e-16 is 0, not 360)
    phi, psi = (round(math.degrees(v), 9) % 360.0 for v in block.phases)
    ratios = ', '.join(f'{v:.6g}' for v in block.inertia_ratios)
    sense = ', anti_aligned' if block.anti_aligned else ''
    return f'inertia_ratios [{ratios}], phases (phi0, psi0) = ({phi:.6g}, {psi:.6g}) deg{sense}'


def _spin(s: AnalysisSummary) -> list[str]:
    if s.spin is None:
        return [f'spin state: not computed ({s.spin_note})']
    u = _units(s)
    out = ['spin state (torque-free through the sample; docs/analysis.md):']
    for label, t, state, block in (
            ('start', s.spin.t_start, s.spin.start, s.spin.start_block),
            ('end', s.spin.t_end, s.spin.end, s.spin.end_block)):
        out.append(f'  {label} (t = {u.time_text(t, 10)}): {state.mode}, rotation '
                   f'{u.period_text(state.rotation_period)}, precession '
                   f'{u.period_text(state.precession_period)}{_pole(u, state)}')
        if block is not None:
            out.append(f'    as spin.*: {_block_text(block)}')
    if s.spin.pole_shift is not None:
        out.append(f'  pole shift: {math.degrees(s.spin.pole_shift):.3g} deg')
    if s.closest_approach is not None:
        t, km = s.closest_approach
        out.append(f'  closest approach of the torquing body: {km:.6g} km at t = '
                   f'{u.time_text(t, 6)}')
    if s.flyby:
        out.append(_before_after(s, u))
    return out


def _before_after(s: AnalysisSummary, u: DisplayUnits) -> str:
    """One line: what the encounter did (start -> end of the recording)."""
    assert s.spin is not None  # (a flyby's summary has one)
    a, b = s.spin.start, s.spin.end
    w0, w1 = s.spin.rate_start, s.spin.rate_end
    rate = (f'|w| {u.rate_text(w0, 4)} -> {u.rate_text(w1, 4)} (x {w1 / w0:.4g})'
            if w0 else '|w| 0')
    shift = (f', pole shift {math.degrees(s.spin.pole_shift):.3g} deg'
             if s.spin.pole_shift is not None else '')
    return (f'  encounter, before -> after: {a.mode} -> {b.mode}, rotation '
            f'{u.period_text(a.rotation_period)} -> {u.period_text(b.rotation_period)}, '
            f'precession {u.period_text(a.precession_period)} -> '
            f'{u.period_text(b.precession_period)}, {rate}{shift}')


def format_summary(s: AnalysisSummary) -> str:
    """Return the summary as text (one WARNING: line per warning, at the end)."""
    out = (_file(s) + _time_and_scenario(s) + _comparator(s) + _invariant(s) + _impacts(s)
           + _spin(s) + _frequencies(s))
    out += [f'note: {note}' for note in s.notes]
    out += [f'WARNING: {warning}' for warning in s.warnings]
    # what was written in years by code that knows no display unit (the theory's basis, the
    # nodes' messages, the warnings) in the display unit too
    return _units(s).retime('\n'.join(out))


def _jsonable(value):
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out = {}
        for f in dataclasses.fields(value):
            if f.metadata.get('json', True):
                out[f.name] = _jsonable(getattr(value, f.name))
        for name in ('duration', 'period', 'worst_rel'):
            attr = getattr(type(value), name, None)
            if isinstance(attr, property):
                out[name] = _jsonable(getattr(value, name))
        return out
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        return _finite_or_none(float(value))
    if isinstance(value, np.integer):
        return int(value)
    return value


def summary_to_dict(s: AnalysisSummary) -> dict:
    """
    Return the summary as plain JSON types; non-finite numbers become None.

    ``topics`` maps each name to {"type", "count"}.
    """
    out = _jsonable(s)
    out['topics'] = {name: {'type': t, 'count': n} for name, (t, n) in s.topics.items()}
    return out

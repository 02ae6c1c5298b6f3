"""
Offline analysis of recorded MCAP files and the paper's figures.

Reads the files written by ``tumble_ros.io`` and computes errors, periods and plots without a
ROS runtime: no rclpy, no running nodes, no sourced workspace needed.

    from tumble_ros.analysis import load_recording, analyze, format_summary, write_figures
    rec = load_recording("run.mcap")          # arrays: rec.t, rec.omega, rec.quaternion, ...
    summary = analyze(rec)                    # AnalysisSummary
    print(format_summary(summary))            # or summary_to_dict(summary) for JSON
    write_figures(rec, "figures/", summary)   # PNG paths (never over an existing file)

Modules: ``recording`` (MCAP -> arrays), ``summary`` (``analyze``: every number, gathered from
one module per concern: ``timeaxis``, ``comparator``, ``invariants``, ``impacts``, ``theory``,
``spectrum``; the text and JSON in ``report``), ``figures`` (matplotlib, Agg; imported lazily
here so that the summary needs no matplotlib), ``cli`` (the ``analyze`` command,
``python -m tumble_ros.analysis``). See docs/analysis.md.

Errors: what the analysis refuses is a :class:`tumble_ros.errors.AnalysisError` (re-exported
here; the figures' ``FigurePathError`` and ``FigureExistsError`` derive from it), an unreadable
file a :class:`tumble_ros.io.McapError`; both are :class:`tumble_ros.errors.TumbleRosError`.
"""
import os
from pathlib import Path

from tumble_ros.errors import AnalysisError

from .recording import load_recording, Recording
from .report import format_summary, summary_to_dict
from .summary import AnalysisSummary, analyze

__all__ = ['AnalysisError', 'AnalysisSummary', 'Recording', 'analyze', 'format_summary',
           'load_recording', 'summary_to_dict', 'write_figures']


def write_figures(rec: Recording, out_dir: str | os.PathLike[str],
                  summary: AnalysisSummary | None = None, *,
                  overwrite: bool = False) -> list[Path]:
    """:func:`tumble_ros.analysis.figures.write_figures` (imports matplotlib on first use)."""
    from .figures import write_figures as _write

    return _write(rec, out_dir, summary, overwrite=overwrite)

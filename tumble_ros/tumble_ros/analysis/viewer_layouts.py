"""
The shipped Foxglove/Lichtblick layouts, and which one fits a recording.

A recording's timeline counts ROS seconds, and one ROS second is one ``time_unit`` of the run
(``seconds_per_year`` 0, the default: 1 s per yr for a run in years, 365.25 * 24 = 8766 s per
yr for a run in hours). A viewer plots a value against that timeline as it is published: w
in rad/yr (``tumble_ros.topics``). So each layout is made for one timeline unit and shows
rates in rad per that unit (the flyby's layout converts them with user scripts,
``/studio_script/...``), stating the units in every panel title:

    layout = layout_for(rec.seconds_per_year)   # ViewerLayout or None (no layout in that unit)
    layout_line(rec.seconds_per_year)           # what the main job prints: the file and why

The layouts are ``config/<file>`` (:func:`tumble_ros.core.model.shipped.config_dir`;
installed to ``share/tumble_ros/config``). docs/viewing.md shows them.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path

from tumble_ros.core.model.shipped import config_dir
from tumble_ros.core.units import TIME_UNITS

__all__ = ['ViewerLayout', 'LAYOUTS', 'timeline_unit', 'layout_for', 'layout_line']


@dataclass(frozen=True)
class ViewerLayout:
    """
    One shipped layout: its file in ``config/``, its timeline unit, the runs it is made for.

    ``time_unit``: one second of the timeline it expects (a key of ``TIME_UNITS``); its rates
    are in rad per that unit. ``runs``: which runs, in words.
    """

    file: str
    time_unit: str
    runs: str

    @property
    def path(self) -> Path:
        """Return the layout's file (in the shipped files' folder)."""
        return config_dir() / self.file

    @property
    def rate(self) -> str:
        """Return the unit of the rates it plots, e.g. 'rad/h'."""
        return f'rad/{self.time_unit}'


#: The shipped layouts, one per timeline unit (the registry :func:`layout_for` reads).
LAYOUTS = (
    ViewerLayout('foxglove_layout.json', 'yr',
                 'runs in years (default, fig3-fig10): the Sun, the impacts'),
    ViewerLayout('foxglove_layout_flyby.json', 'h',
                 'runs in hours (apophis_2029): the Earth in body axes'),
)


def timeline_unit(seconds_per_year: float) -> str | None:
    """
    Return the time unit one second of a recording's timeline is, or None when it is none.

    ``seconds_per_year``: ROS seconds per simulated year (the recorded ``/scenario``'s); one
    timeline second is a ``TIME_UNITS`` unit u when 1 / seconds_per_year = TIME_UNITS[u]
    (relative tolerance 1e-9).
    """
    if not (math.isfinite(seconds_per_year) and seconds_per_year > 0.0):
        return None
    for unit, years in TIME_UNITS.items():
        if math.isclose(years * seconds_per_year, 1.0, rel_tol=1e-9):
            return unit
    return None


def layout_for(seconds_per_year: float) -> ViewerLayout | None:
    """Return the shipped layout made for a recording on this time base (None: there is none)."""
    unit = timeline_unit(seconds_per_year)
    return next((layout for layout in LAYOUTS if layout.time_unit == unit), None)


def layout_line(seconds_per_year: float) -> str:
    """Return one line naming the layout to open a recording with, and why (or that none fits)."""
    layout = layout_for(seconds_per_year)
    if layout is not None:
        return (f'viewer: open the recording in Foxglove or Lichtblick with the layout '
                f'{_shown(layout.path)} (timeline t in {layout.time_unit}, w in {layout.rate}; '
                f'{layout.runs})')
    unit = timeline_unit(seconds_per_year)
    second = (f'one {unit}' if unit is not None
              else f'{1.0 / seconds_per_year:.6g} yr' if seconds_per_year > 0.0 else 'unknown')
    shipped = ', '.join(f'{_shown(layout.path)} (t in {layout.time_unit}, w in {layout.rate})'
                        for layout in LAYOUTS)
    return (f'viewer: no shipped layout fits this recording (one second of its timeline is '
            f'{second}); the shipped ones: {shipped}')


def _shown(path: Path) -> str:
    """Return ``path`` relative to the working directory when it is under it, else absolute."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)

"""A figure as data: what the renderer (:mod:`trackfuse.reportkit.render`) draws.

A :class:`Plot` names a metric (or a few, one row of panels each) against an x column of
``summary.csv`` (a swept parameter or a row key such as ``ops``), one curve per algorithm
in its declared look, one panel per setting of the other swept parameters, the interval
read from ``summary.csv`` (Wilson for 0/1 metrics, Student-t clipped to the metric's bounds
otherwise), and :class:`Reference` lines. Pure data: no matplotlib.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

Scale = Literal["auto", "linear", "log", "symlog"]
#: The two widths (in) a journal page prints a figure at: one column, two columns.
SLOTS = {"single": 3.5, "double": 7.16}
#: The most legend entries a figure has: the rest of the detail goes to its caption.
MAX_ENTRIES = 6


@dataclass(frozen=True)
class Reference:
    """A reference drawn in every panel.

    * ``algorithm``: that algorithm's curve drawn as a dashed reference (an exact optimum),
      its interval shaded light grey;
    * ``y``: a horizontal level (a bound, chance) drawn dotted, labelled ``label`` (an
      unlabelled one is named in the caption);
    * ``x``: vertical lines at each of ``at`` (a setting the paper names), unlabelled
      (the caption says what they are);
    * ``band``: ``(low, high)`` shaded as the paper's claim, labelled ``label``, across
      the panel or, with ``until``, from the first x value up to ``until`` (the x the
      claim reaches: paper 000's "below 5 % up to 9 false returns");
    * ``values``: ``((algorithm, y), ...)`` the paper's value of each method, drawn as an
      open star in its colour at the sweep ``points`` where the run is at the paper's
      setting (one legend entry, ``label``).

    ``metrics``: the metrics whose panels draw it (``()``: every panel), e.g. a design
    false-association rate only in the false-association panel.
    """

    algorithm: str = ""
    y: float | None = None
    x: tuple[float, ...] = ()
    band: tuple[float, float] | None = None
    label: str = ""
    values: tuple[tuple[str, float], ...] = ()
    points: tuple[int, ...] = ()
    metrics: tuple[str, ...] = ()
    until: float | None = None


@dataclass(frozen=True)
class Plot:
    """One figure drawn by the kit.

    ``metrics``: metric names, one row of panels each (the panels of one row share their y
    axis); ``x``: the x column; ``algorithms``: the curves, in legend order (``()``: every
    algorithm the run has, at most :data:`MAX_ENTRIES` with the references);
    ``columns``: the swept key whose values go across (``""``: every setting of the swept
    keys but ``x`` one panel each, wrapped at ``max_columns``); ``at``: row keys held fixed
    (``{"ops": "last"}`` takes each algorithm's last checkpoint; a tuple keeps the rows at
    any of its values, and of a swept key only those panels); ``xscale``/``yscale``
    (``yscale`` may map each metric to its own): ``auto`` picks log for a positive grid
    spanning 10x or more over 4 values or more, symlog for one that starts at 0;
    ``categories``: the x values are separate scenes, drawn as unjoined points side by
    side; ``width``: ``single`` (3.5 in), ``double`` (7.16 in) or ``auto`` (single for one
    column of panels); ``panel_height``: of a row of panels (in); ``root``: draw the square
    root of the metric's mean and interval ends, labelled ``root`` (a root mean square
    error from a mean squared error; the unit's square root); ``together``: swept keys that
    a zipped sweep varies with ``x`` (not panels of their own).
    """

    metrics: tuple[str, ...]
    x: str
    algorithms: tuple[str, ...] = ()
    references: tuple[Reference, ...] = ()
    columns: str = ""
    max_columns: int = 3
    at: Mapping[str, Any] = field(default_factory=dict)
    xscale: Scale = "auto"
    yscale: Scale | Mapping[str, Scale] = "linear"
    categories: bool = False
    width: Literal["single", "double", "auto"] = "auto"
    panel_height: float = 1.9
    root: str = ""
    together: tuple[str, ...] = ()

    def yscale_of(self, metric: str) -> Scale:
        """The y scale of ``metric``'s panels."""
        if isinstance(self.yscale, str):
            return self.yscale
        return self.yscale.get(metric, "linear")

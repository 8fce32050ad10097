"""Shared figure style: one look for every trackfuse figure.

Use :func:`new_figure` for axes with the house style, :func:`band` for a mean or proportion
curve with its confidence band, and :func:`reference_line` for bounds and exact optima.

:func:`new_figure` lays the panels out with matplotlib's constrained layout, which measures
every text element at each save (most of a figure's drawing time). :func:`fixed_figure` places
panels at fixed margins given in inches instead, several times faster to save; draw its titles
and labels inside :func:`context` (so they take the house font sizes) and put its legend in
the reserved bottom strip with :func:`legend_in_strip`.
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from contextlib import AbstractContextManager
from dataclasses import dataclass
from functools import cache

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

PAGE_WIDTH_IN = 7.16
"""Width (in) of a two-column figure on an IEEE journal page: the widest a figure prints."""

RC = {
    "figure.dpi": 110,
    "savefig.dpi": 200,
    "font.size": 9,
    "axes.titlesize": 10,
    # titles at the top of their axes, where matplotlib puts them when nothing is above
    # the axes; left to itself it searches every tick label for that at each draw (a
    # tenth of the drawing time, and no shipped figure's bytes change without it)
    "axes.titley": 1.0,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.4,
    "lines.markersize": 4,
    "figure.constrained_layout.use": True,
}


def new_figure(ncols: int = 1, nrows: int = 1, width: float = 5.0, height: float = 3.4):
    """Return ``(fig, axes)`` with the house style; ``axes`` is a flat array if > 1 panel."""
    with matplotlib.rc_context(RC):
        fig = Figure(figsize=(width * ncols, height * nrows), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False)
    flat = axes.ravel()
    return fig, (flat[0] if flat.size == 1 else flat)


def mosaic_figure(layout: list[list[str]], width: float, height: float, **kw):
    """Return ``(fig, axes by name)`` with the house style and constrained layout, panels
    placed as in :meth:`~matplotlib.figure.Figure.subplot_mosaic` (a panel may span rows or
    columns); ``width`` and ``height`` in inches, ``kw`` to ``subplot_mosaic``."""
    with matplotlib.rc_context(RC):
        fig = Figure(figsize=(width, height), layout="constrained")
        axes = fig.subplot_mosaic(layout, **kw)
    return fig, axes


@cache
def warm_up(formats: tuple[str, ...], dpi: int) -> None:
    """Draw one small figure in the house style and save it in memory in each format (once
    per process).

    What the first figure of a process loads (the fonts, the PDF font subsetter, the image
    writers: about 0.5 s) is then loaded here once, before the drawing processes fork from
    this one, instead of once in each of them.
    """
    fig, (ax,) = fixed_figure(panel=(1.0, 0.8))
    with context():
        ax.plot([0, 1], [0, 1], marker="o", label="a")
        ax.set_title("title 0.5 %")
        ax.set_xlabel("x (m)")
        legend_in_strip(fig, *ax.get_legend_handles_labels(), ncols=1)
    for fmt in formats:
        fig.savefig(io.BytesIO(), format=fmt, dpi=dpi)


def context() -> AbstractContextManager:
    """The house style as a context: text created inside it takes the house font sizes."""
    return matplotlib.rc_context(RC)


@dataclass(frozen=True)
class Margins:
    """Fixed figure margins and gaps in inches: ``left`` (room for y tick labels and the
    y label), ``right``, ``top`` (titles), ``bottom`` (x tick labels and x label), ``wspace``
    and ``hspace`` between panels, ``strip`` an extra strip below everything for a legend."""

    left: float = 0.7
    right: float = 0.15
    top: float = 0.6
    bottom: float = 0.5
    wspace: float = 0.55
    hspace: float = 0.75
    strip: float = 0.0


def fixed_figure(ncols: int = 1, nrows: int = 1, panel: tuple[float, float] = (4.0, 2.8),
                 margins: Margins = Margins()):
    """``(fig, axes)`` with panels of ``panel = (width, height)`` inches at fixed
    ``margins`` (no layout engine); ``axes: (nrows * ncols,)``, row-major, always an array."""
    width = margins.left + margins.right + ncols * panel[0] + (ncols - 1) * margins.wspace
    height = (margins.top + margins.bottom + margins.strip + nrows * panel[1]
              + (nrows - 1) * margins.hspace)
    with context():
        fig = Figure(figsize=(width, height), layout="none")
        axes = fig.subplots(nrows, ncols, squeeze=False)
    fig.subplots_adjust(left=margins.left / width, right=1 - margins.right / width,
                        bottom=(margins.bottom + margins.strip) / height,
                        top=1 - margins.top / height, wspace=margins.wspace / panel[0],
                        hspace=margins.hspace / panel[1])
    return fig, axes.ravel()


LEGEND_ROW_IN = 0.2
"""Height (in) of one row of a :func:`legend_in_strip` legend, for sizing the strip."""


def trim_bottom(fig, inches: float) -> None:
    """Cut ``inches`` off the bottom of a :func:`fixed_figure` (a legend row it reserved and
    does not use), every panel and title keeping its place measured from the top."""
    height = fig.get_figheight()
    new = height - inches
    for ax in fig.axes:
        x0, y0, width, tall = ax.get_position().bounds
        ax.set_position([x0, (y0 * height - inches) / new, width, tall * height / new])
    if fig._suptitle is not None:
        fig._suptitle.set_y(1 - (1 - fig._suptitle.get_position()[1]) * height / new)
    fig.set_figheight(new)


def legend_in_strip(fig, handles: list, labels: list[str], ncols: int) -> None:
    """One figure legend centred at the bottom of ``fig``, in the strip that
    :class:`Margins` ``strip`` reserved (:data:`LEGEND_ROW_IN` per legend row)."""
    with context():
        fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, 0.0),
                   ncols=max(1, ncols), frameon=False, borderaxespad=0.3)


def legend_entries(axes: Iterable[Axes]) -> tuple[list, list[str]]:
    """``(handles, labels)`` of every labelled artist of ``axes``, each label once (the
    first handle drawn with it)."""
    entries: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    return list(entries.values()), list(entries)


def legend_below(fig: Figure, handles: list, labels: list[str], column_width: float = 3.4
                 ) -> None:
    """One legend below the panels of a :func:`new_figure` (constrained layout), one column
    per ``column_width`` inches of the figure's width, at most one per entry."""
    ncols = max(1, min(len(labels), int(fig.get_figwidth() / column_width)))
    fig.legend(handles, labels, loc="outside lower center", ncols=ncols)


def band(ax, x, y, low, high, label: str, marker: str = "o", **kw) -> None:
    """Draw ``y`` against ``x`` with a shaded ``[low, high]`` confidence band."""
    x = np.asarray(x, dtype=float)
    (line,) = ax.plot(x, y, marker=marker, label=label, **kw)
    ax.fill_between(x, np.asarray(low, dtype=float), np.asarray(high, dtype=float),
                    color=line.get_color(), alpha=0.18, linewidth=0)


def wants_log_axis(values) -> bool:
    """Whether a grid of swept ``values`` is drawn on a log axis: at least 4 distinct
    positive values spanning at least 10x (a narrower grid stays linear)."""
    v = np.unique(np.asarray(values, dtype=float))
    return len(v) >= 4 and v.min() > 0 and v.max() / v.min() >= 10


def reference_line(ax, y: float, label: str, **kw) -> None:
    """A horizontal reference (bound, exact optimum) drawn dashed in black."""
    kw.setdefault("color", "k")
    kw.setdefault("linestyle", "--")
    kw.setdefault("linewidth", 1.0)
    ax.axhline(y, label=label, **kw)

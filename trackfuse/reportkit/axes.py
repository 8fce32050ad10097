"""Axis scales and ticks of the kit's figures: plain numbers, integer ticks for counts, a
log or symlog axis only where the grid asks for it, and a margin so that no marker is cut
by a panel's edge."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

from trackfuse.reportkit.typography import number

if TYPE_CHECKING:
    from trackfuse.reportkit.render import Quantity

#: Room beyond the first and last x value, as a fraction of the span on the axis's scale.
X_MARGIN = 0.05
#: The most x values ticked one by one; a denser grid is ticked by a locator.
MAX_VALUE_TICKS = 5
#: The most values of a log or symlog grid ticked one by one when it spans too few powers
#: of 10 to tick those (``0, 25, 50, 100, 200, 500`` rather than ``0, 100``).
MAX_SPREAD_TICKS = 7
#: The most powers of 10 a log y axis spans with 1-2-5 ticks; a wider one ticks the powers.
MAX_SPREAD_DECADES = 2.5
PLAIN = FuncFormatter(lambda value, _: number(value))


def scale_of(values: np.ndarray, wanted: str) -> str:
    """The x scale of a sorted grid: ``wanted`` unless ``auto``; ``auto`` is symlog for a
    grid from 0 whose positive values span 10x or more, log for 3 or more positive values
    spanning 10x or more, else linear."""
    if wanted != "auto":
        return wanted
    positive = values[values > 0]
    if len(values) >= 3 and values[0] == 0 and len(positive) and \
            positive[-1] / positive[0] >= 10:
        return "symlog"
    if len(values) >= 3 and values[0] > 0 and values[-1] / values[0] >= 10:
        return "log"
    return "linear"


def _set_scale(ax: Axes, scale: str, values: np.ndarray) -> None:
    if scale == "symlog":  # linear up to the first positive value, log above
        ax.set_xscale("symlog", linthresh=float(values[values > 0][0]), linscale=0.6)
    elif scale == "log":
        ax.set_xscale("log")


def _ticks(values: np.ndarray, scale: str) -> Sequence[float] | None:
    """The x ticks: every value of a short grid, 0 and the powers of 10 of a long log one
    (every value when those are fewer than 3 and the grid at most :data:`MAX_SPREAD_TICKS`
    long), ``None`` (a locator) for a long linear one."""
    if len(values) <= MAX_VALUE_TICKS:
        return list(values)
    if scale == "linear":
        return None
    positive = values[values > 0]
    powers = 10.0 ** np.arange(np.ceil(np.log10(positive[0])), np.floor(np.log10(values[-1])) + 1)
    ticks = [0.0] * bool(values[0] == 0) + list(powers)
    return list(values) if len(ticks) < 3 and len(values) <= MAX_SPREAD_TICKS else ticks


def x_axis(axes: Sequence[Axes], values: Sequence[Any], wanted: str, shown: Quantity,
           categories: bool, room: float) -> str:
    """Scale, ticks and limits of the shared x axis over the sorted ``values``; returns its
    label (naming a log or symlog scale; over two lines when wider than ``room`` in)."""
    if categories:
        for ax in axes:
            ax.set_xticks(range(len(values)), [shown.word(v) for v in values])
            ax.set_xlim(-0.6, len(values) - 0.4)
            ax.grid(False, axis="x")
        return shown.axis(room=room)
    values = np.asarray(values, dtype=float)
    scale = scale_of(values, wanted)
    ticks = _ticks(values, scale)
    for ax in axes:
        _set_scale(ax, scale, values)
        if ticks is None:
            ax.xaxis.set_major_locator(MaxNLocator(nbins=5, integer=shown.count))
        else:
            ax.set_xticks(ticks)
        ax.xaxis.set_major_formatter(PLAIN)
        ax.xaxis.set_minor_formatter(NullFormatter())
        _pad(ax, float(values[0]), float(values[-1]))
    return shown.axis("" if scale == "linear" else scale, room)


def _pad(ax: Axes, low: float, high: float) -> None:
    """X limits ``low``-``high`` widened by :data:`X_MARGIN` on the axis's own scale."""
    transform = ax.xaxis.get_transform()
    a, b = transform.transform(np.array([low, high], dtype=float))
    pad = X_MARGIN * (b - a) if b > a else 0.5
    ax.set_xlim(*transform.inverted().transform(np.array([a - pad, b + pad])))


def shifted(x: np.ndarray, grid: np.ndarray, wanted: str, fraction: float) -> np.ndarray:
    """``x`` moved right by ``fraction`` of the grid's span on its scale (a curve drawn
    beside one it coincides with, not hidden under it)."""
    scale = scale_of(grid, wanted)
    if scale == "log":
        span = np.log10(grid[-1] / grid[0])
        return x * 10 ** (fraction * span)
    span = float(grid[-1] - grid[0]) or 1.0
    if scale == "symlog":
        return np.where(x > 0, x * 10 ** (fraction * np.log10(max(grid[-1], 10.0))), x + fraction)
    return x + fraction * span


def y_log(ax: Axes, scale: str) -> None:
    """A log (or symlog, linear below 1) y axis labelled with plain numbers, ticked at
    1, 2 and 5 times the powers of 10 over a view of at most :data:`MAX_SPREAD_DECADES`,
    at the powers alone over more."""
    if scale == "symlog":
        ax.set_yscale("symlog", linthresh=1.0)
    else:
        ax.set_yscale("log")
        low, high = ax.get_ylim()
        decades = np.log10(high / low) if 0 < low < high else 0.0
        ax.yaxis.set_major_locator(LogLocator(
            subs=(1.0,) if decades > MAX_SPREAD_DECADES else (1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(PLAIN)
    ax.yaxis.set_minor_formatter(NullFormatter())


def bounded_limits(ax: Axes, low: float, high: float) -> None:
    """Y limits kept within a quantity's bounds ``[low, high]`` (shown units) plus room
    for a marker at either end: 3 % of the span, or of the view on a log-like axis."""
    view_low, view_high = ax.get_ylim()
    span = (high - low) if np.isfinite(high - low) else (view_high - view_low)
    room = 0.03 * span if ax.get_yscale() == "linear" else 0.3
    ax.set_ylim(max(view_low, low - room), min(view_high, high + room))

"""Shared figure style: one look for every trackfuse figure.

Use :func:`new_figure` for axes with the house style, :func:`band` for a mean or proportion
curve with its confidence band, and :func:`reference_line` for bounds and exact optima.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.text import Text

RC = {
    "figure.dpi": 110,
    "savefig.dpi": 200,
    "font.size": 9,
    "axes.titlesize": 10,
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


def band(ax, x, y, low, high, label: str, marker: str = "o", **kw) -> None:
    """Draw ``y`` against ``x`` with a shaded ``[low, high]`` confidence band."""
    x = np.asarray(x, dtype=float)
    (line,) = ax.plot(x, y, marker=marker, label=label, **kw)
    ax.fill_between(x, np.asarray(low, dtype=float), np.asarray(high, dtype=float),
                    color=line.get_color(), alpha=0.18, linewidth=0)


def reference_line(ax, y: float, label: str, **kw) -> None:
    """A horizontal reference (bound, exact optimum) drawn dashed in black."""
    kw.setdefault("color", "k")
    kw.setdefault("linestyle", "--")
    kw.setdefault("linewidth", 1.0)
    ax.axhline(y, label=label, **kw)


def legend_below(fig, ax, max_cols: int | None = None) -> None:
    """One figure legend below the panels, built from ``ax``'s entries.

    ``max_cols`` caps the legend's columns; by default as many as fit the figure width
    (one per 2.8 inches).
    """
    handles, labels = ax.get_legend_handles_labels()
    cap = max_cols if max_cols is not None else int(fig.get_figwidth() / 2.8)
    fig.legend(handles, labels, loc="outside lower center",
               ncols=max(1, min(len(labels), cap)))



def text_overlaps(fig, tolerance_px: float = 1.0) -> list[tuple[str, str]]:
    """Pairs of text elements drawn in ``fig`` whose boxes overlap.

    The figure is drawn once while every :class:`~matplotlib.text.Text` that actually
    renders (visible, non-empty, inside its axes' view) is recorded; boxes are in display
    pixels and overlap when they share more than ``tolerance_px`` in both directions.
    Returns ``[(text_a, text_b), ...]``; empty for a clean figure.
    """
    drawn: list[Text] = []
    original = Text.draw

    def recording(self: Text, renderer) -> None:
        original(self, renderer)
        if self.get_visible() and self.get_text().strip():
            drawn.append(self)

    Text.draw = recording
    try:
        fig.canvas.draw()
    finally:
        Text.draw = original
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in drawn]
    found = []
    for i, (text_a, a) in enumerate(boxes):
        for text_b, b in boxes[i + 1:]:
            dx = min(a.x1, b.x1) - max(a.x0, b.x0)
            dy = min(a.y1, b.y1) - max(a.y0, b.y0)
            if dx > tolerance_px and dy > tolerance_px:
                found.append((text_a, text_b))
    return found

"""One journal style and one layout for every figure: sized for a printed slot.

Every figure is drawn at the size it prints: :data:`~trackfuse.reportkit.spec.SLOTS` wide
(3.5 in, one column; 7.16 in, two columns), at most :data:`MAX_HEIGHT_IN` tall, its text
at least :data:`MIN_POINTS` at that size, in matplotlib's bundled DejaVu Sans (the same on
every host), with TrueType fonts embedded in PDFs (``pdf.fonttype`` 42: journal checkers
reject Type 3). Panels are placed by matplotlib's constrained layout; one legend sits below
them.
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from contextlib import AbstractContextManager
from functools import cache

import matplotlib
import numpy as np
from matplotlib import font_manager
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from trackfuse.reportkit import pdffont
from trackfuse.reportkit.spec import MAX_ENTRIES, SLOTS

MAX_HEIGHT_IN = 8.5
"""Tallest figure (in) a page holds with its caption."""
MIN_POINTS = 7.0
"""Smallest text (pt) at printed size."""
CHAR_IN = 0.058
"""Mean width (in) of a character of 7 pt DejaVu Sans: to fit legend columns."""

RC = {
    "font.family": "DejaVu Sans",
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "figure.titlesize": 8.5,
    "figure.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "legend.title_fontsize": 7,
    "axes.titley": 1.0,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "axes.linewidth": 0.6,
    "lines.linewidth": 1.2,
    "lines.markersize": 3.5,
    "errorbar.capsize": 2,
    "figure.dpi": 100,
    "savefig.dpi": 200,
    "pdf.fonttype": 42,
    "ps.fonttype": 42,
    "svg.fonttype": "path",
    "figure.constrained_layout.h_pad": 0.03,
    "figure.constrained_layout.w_pad": 0.03,
}


def context() -> AbstractContextManager:
    """The journal style as a context: figures created and saved inside it take it."""
    return matplotlib.rc_context(RC)


def slot_width(width: str, columns: int) -> float:
    """Width (in) of a figure of ``columns`` panel columns: ``single``, ``double`` or
    ``auto`` (one column: single, more: double)."""
    if width == "auto":
        width = "single" if columns == 1 else "double"
    return SLOTS[width]


def panels(rows: int, columns: int, width: str = "auto", panel_height: float = 1.9,
           extra_height: float = 0.9, **subplots) -> tuple[Figure, Iterable[Axes]]:
    """``(fig, axes)``: a grid of ``rows x columns`` panels on a slot-wide figure, each
    row ``panel_height`` in tall plus ``extra_height`` for the title and the legend, the
    whole at most :data:`MAX_HEIGHT_IN` (rows shrink to fit); ``axes`` of shape
    ``(rows, columns)``; ``subplots`` to :meth:`~matplotlib.figure.Figure.subplots`."""
    height = min(MAX_HEIGHT_IN, rows * panel_height + extra_height)
    with context():
        fig = Figure(figsize=(slot_width(width, columns), height), layout="constrained")
        axes = fig.subplots(rows, columns, squeeze=False, **subplots)
    return fig, axes


def legend_entries(axes: Iterable[Axes]) -> tuple[list, list[str]]:
    """``(handles, labels)`` of every labelled artist of ``axes``, each label once (the
    first handle drawn with it)."""
    entries: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            if not label.startswith("_"):
                entries.setdefault(label, handle)
    return list(entries.values()), list(entries)


def legend_below(fig: Figure, axes: Iterable[Axes]) -> None:
    """One legend below the panels, each label once (:func:`legend_entries`), at most
    :data:`~trackfuse.reportkit.spec.MAX_ENTRIES` entries, in as many columns as fit."""
    entries = dict(zip(*reversed(legend_entries(axes)), strict=True))
    if not entries:
        return
    if len(entries) > MAX_ENTRIES:
        raise ValueError(f"{len(entries)} legend entries; at most {MAX_ENTRIES}")
    longest = max(len(label) for label in entries)
    per_row = max(1, min(len(entries), int(fig.get_figwidth() / (CHAR_IN * longest + 0.55))))
    with context():
        fig.legend(list(entries.values()), list(entries), loc="outside lower center",
                   ncols=per_row, frameon=False)


@cache
def shared_pdf_font() -> None:
    """Subset the house font once for every PDF this process (and its forks) writes
    (:mod:`.pdffont`; matplotlib's own subsetting where its private API has changed)."""
    if pdffont.install():
        with context():
            pdffont.prepare(font_manager.findfont(font_manager.FontProperties(
                family=RC["font.family"])))


@cache
def warm_up(formats: tuple[str, ...], dpi: int) -> None:
    """Draw one small figure in the journal style and save it in memory in each format
    (once per process), so the fonts, the PDF font subset and the image writers are
    loaded once before the drawing processes fork, not once in each."""
    if "pdf" in formats:
        shared_pdf_font()
    fig, axes = panels(1, 1, "single")
    with context():
        axes[0, 0].plot([0, 1], [0, 1], marker="o", label="a")
        axes[0, 0].set_title("title 0.5 %")
        legend_below(fig, axes.ravel())
        for fmt in formats:
            fig.savefig(io.BytesIO(), format=fmt, dpi=dpi)


def band(ax: Axes, x, y, low, high, label: str, marker: str = "o", **line) -> None:
    """``y`` against ``x`` with its ``[low, high]`` interval shaded in the line's colour
    (``line``: more :meth:`~matplotlib.axes.Axes.plot` arguments): for a plugin's own
    figure that no :class:`~trackfuse.reportkit.spec.Plot` declares."""
    x = np.asarray(x, dtype=float)
    (drawn,) = ax.plot(x, y, marker=marker, label=label, **line)
    ax.fill_between(x, np.asarray(low, dtype=float), np.asarray(high, dtype=float),
                    color=drawn.get_color(), alpha=0.18, linewidth=0)

"""A report module for experiments whose figures are all declared
(:attr:`~trackfuse.experiments.base.FigureSpec.plot`): set ``report=
"trackfuse.reportkit.declared"`` on the ``Experiment`` and write no drawing code."""

from __future__ import annotations

from collections.abc import Collection

from matplotlib.figure import Figure

from trackfuse.reportkit import render
from trackfuse.rundata import RunData


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """Every ``wanted`` figure whose spec declares a plot, drawn by the kit's renderer (a
    one-line reason for one the run cannot draw)."""
    specs = run.experiment.figures
    return {name: render.draw(run, specs[name].plot) if specs[name].plot is not None
            else "declared without a plot, and this experiment has no report module of its own"
            for name in wanted if name in specs}

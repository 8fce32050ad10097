"""Report of the coin plugin: reads the finished run only (``trackfuse.rundata.RunData``)."""

from __future__ import annotations

from collections.abc import Collection

import pandas as pd
from matplotlib.figure import Figure

from trackfuse.plots.style import band, new_figure
from trackfuse.rundata import RunData


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure]:
    """``error``: mean absolute error against the swept bias, with its 95 % t band."""
    if "error" not in wanted or "p" not in run.sweep:
        return {}
    rows = run.summary[run.summary["metric"] == "abs_error"].sort_values("p")
    fig, ax = new_figure()
    band(ax, rows["p"], rows["mean"], rows["ci_low"], rows["ci_high"], "sample mean")
    ax.set_xlabel("true bias p (1)")
    ax.set_ylabel("mean absolute error (1)")
    ax.legend()
    return {"error": fig}


def tables(run: RunData) -> dict[str, pd.DataFrame]:
    """``coverage``: the Wald interval's coverage per point (Wilson interval)."""
    rows = run.summary[run.summary["metric"] == "covered"]
    return {"coverage": rows[["point", *run.sweep, "n", "mean", "ci_low", "ci_high"]]}

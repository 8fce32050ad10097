"""Report module of the toy Gaussian experiments (tests only)."""

from __future__ import annotations

from collections.abc import Collection

from matplotlib.figure import Figure

from trackfuse.plots.style import band, new_figure
from trackfuse.rundata import RunData


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure]:
    """``estimate``: mean estimate per algorithm with its t band, against the point."""
    if "estimate" not in wanted:
        return {}
    fig, ax = new_figure()
    rows = run.summary[run.summary["metric"] == "estimate"]
    for algorithm, group in rows.groupby("algorithm", sort=False):
        band(ax, group["point"], group["mean"], group["ci_low"], group["ci_high"], algorithm)
    ax.set_xlabel("sweep point")
    ax.set_ylabel("estimate (m)")
    ax.legend()
    return {"estimate": fig}


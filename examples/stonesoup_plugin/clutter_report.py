"""Report of the Stone Soup plugin: reads the finished run only (``RunData``)."""

from __future__ import annotations

from collections.abc import Collection

from matplotlib.figure import Figure

from trackfuse.reportkit.style import band, context, legend_below, panels
from trackfuse.rundata import RunData


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """``lost``: fraction of tracks lost against the swept clutter rate, per tracker."""
    if "lost" not in wanted:
        return {}
    if "clutter_mean" not in run.sweep:
        return {"lost": "clutter_mean is not swept"}
    fig, axes = panels(1, 1, "single")
    ax = axes[0, 0]
    with context():
        summary = run.summary[run.summary["metric"] == "lost"].sort_values("clutter_mean")
        for name, rows in summary.groupby("algorithm"):
            band(ax, rows["clutter_mean"], rows["mean"], rows["ci_low"], rows["ci_high"],
                 {"pda": "Kalman + PDA", "nn": "Kalman + nearest neighbour"}[name])
        ax.set_xlabel("mean false detections per scan")
        ax.set_ylabel("tracks lost at the last scan (fraction)")
        ax.set_title(f"Stone Soup trackers, {run.config['trials']} trials per point")
        legend_below(fig, [ax])
    return {"lost": fig}

"""Report module of the toy Gaussian experiments (tests only)."""

from __future__ import annotations

from collections.abc import Collection

import pandas as pd
from matplotlib.figure import Figure

from trackfuse.reportkit.style import band, context, legend_below, panels
from trackfuse.reportkit.verdicts import AGREES, DIFFERS
from trackfuse.rundata import RunData

#: The run folders :func:`prepare` was called for, in order (the tests read it).
PREPARED: list[object] = []


def prepare(run: RunData) -> None:
    """Note the run: the report calls this once, before it draws."""
    PREPARED.append(run.path)


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """``estimate``: mean estimate per algorithm with its t band, against the point;
    ``estimate_vs_sigma`` (toy_picky) only says why it is not drawn without a sigma sweep."""
    if "estimate_vs_sigma" in wanted and "sigma" not in (run.config.get("sweep") or {}):
        return {"estimate_vs_sigma": "sigma is not swept"}
    if "estimate" not in wanted:
        return {}
    fig, axes = panels(1, 1, "single")
    ax = axes[0, 0]
    with context():
        rows = run.summary[run.summary["metric"] == "estimate"]
        for algorithm, group in rows.groupby("algorithm", sort=False):
            band(ax, group["point"], group["mean"], group["ci_low"], group["ci_high"], algorithm)
        ax.set_xlabel("sweep point")
        ax.set_ylabel("estimate (m)")
        legend_below(fig, [ax])
    return {"estimate": fig}



def tables(run: RunData) -> dict[str, pd.DataFrame]:
    """``paper_vs_reproduced``: a made-up paper claims 95 % coverage for each algorithm."""
    rows = run.summary[(run.summary["metric"] == "covered") & (run.summary["point"] == 0)]
    out = pd.DataFrame({
        "paper_item": "Fig. 1", "quantity": "coverage of the 95 % interval",
        "algorithm": rows["algorithm"].to_numpy(), "paper_value": "0.95",
        "reproduced": rows["mean"].to_numpy(), "ci_low": rows["ci_low"].to_numpy(),
        "ci_high": rows["ci_high"].to_numpy(), "unit": "fraction",
        "trials": rows["n"].to_numpy()})
    inside = (out["ci_low"] <= 0.95) & (out["ci_high"] >= 0.95)
    out["verdict"] = inside.map({True: AGREES, False: DIFFERS})
    out["reason"] = "the paper's 0.95 against our Wilson interval"
    out["docs"] = "docs/papers/twin_sensor.md#metrics"  # a real note, so its link lands
    out["claim"] = "coverage"
    out["setting"] = ""
    return {"paper_vs_reproduced": out}

"""Report of the coin plugin: reads the finished run only (``trackfuse.rundata.RunData``).

Its figures are declared on ``coin.EXPERIMENT`` and drawn by the report kit; this module adds
only what is its own, a table.
"""

from __future__ import annotations

import pandas as pd

from trackfuse.reportkit.declared import figures
from trackfuse.rundata import RunData


def tables(run: RunData) -> dict[str, pd.DataFrame]:
    """``coverage``: the Wald interval's coverage per point (Wilson interval)."""
    rows = run.summary[run.summary["metric"] == "covered"]
    return {"coverage": rows[["point", *run.sweep, "n", "mean", "ci_low", "ci_high"]]}


__all__ = ["figures", "tables"]

"""Chosen rows of ``summary.csv`` as a wide table: one row per sweep point, each chosen
(metric, algorithm) a column with its interval, for a report's per-point table."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import pandas as pd


def per_point(summary: pd.DataFrame, keys: Sequence[str],
              wanted: Mapping[tuple[str, str], str]) -> pd.DataFrame:
    """Per point: each ``(metric, algorithm) -> column`` of ``wanted`` with its interval."""
    out = []
    for point, g in summary.groupby("point", sort=True):
        row = {"point": point, **{k: g[k].iloc[0] for k in keys}}
        for (metric, name), column in wanted.items():
            hit = g[(g["metric"] == metric) & (g["algorithm"] == name)]
            if len(hit):
                row.update({column: hit["mean"].iloc[0],
                            f"{column}_ci_low": hit["ci_low"].iloc[0],
                            f"{column}_ci_high": hit["ci_high"].iloc[0]})
        out.append(row)
    return pd.DataFrame(out)

"""Summaries of ``trials.csv``: per point x row keys x metric, n, mean, std and a 95 % CI.

The CSV is read in fixed-size chunks and the per-chunk (n, mean, M2) are combined exactly
(Chan, Golub & LeVeque 1979), so memory stays flat for any number of trials and the result
does not depend on how the trials were scheduled. Rows of failed trials (``status ==
"failed"``) are left out and counted separately.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from trackfuse.results import FAILED_ROW, RUNNER_COLUMNS
from trackfuse.stats import t_interval, wilson_interval

CHUNK_ROWS = 200_000


def _clipped(metrics: pd.Series, low: np.ndarray, high: np.ndarray,
             bounds: Mapping[str, tuple[float, float]] | tuple[float, float] | None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Interval ends ``low, high`` (one per row of ``metrics``) clipped to each metric's
    ``bounds`` (one pair: every metric's)."""
    if isinstance(bounds, tuple):
        bounds = dict.fromkeys(metrics.unique(), bounds)
    for metric, (lo, hi) in (bounds or {}).items():
        mine = (metrics == metric).to_numpy()
        low = np.where(mine, np.clip(low, lo, hi), low)
        high = np.where(mine, np.clip(high, lo, hi), high)
    return low, high


def summarize(source: Path | pd.DataFrame, keys: Sequence[str], binary: Sequence[str] = (),
              chunk_rows: int = CHUNK_ROWS, suffix: str = "", skip: Sequence[str] = (),
              bounds: Mapping[str, tuple[float, float]] | tuple[float, float] | None = None
              ) -> tuple[pd.DataFrame, int]:
    """Return ``(summary, failed_rows)`` for the CSV at ``source``, or for the CSV already
    read whole (``pd.read_csv(path, low_memory=False)``), taken in the same chunks.

    ``keys`` are the grouping columns (``point``, swept keys, the experiment's row keys);
    every other numeric column whose name ends in ``suffix`` and is not in ``skip`` (labels
    such as a chosen track's index) is a metric. ``binary`` metrics get Wilson intervals, the
    rest Student-t intervals, clipped to a metric's ``bounds`` ``(low, high)`` if given
    (one pair: every metric's).
    """
    partial: list[pd.DataFrame] = []
    failed = 0
    chunks: Iterable[pd.DataFrame]
    if isinstance(source, pd.DataFrame):
        chunks = (source.iloc[i:i + chunk_rows] for i in range(0, len(source), chunk_rows))
    else:
        try:
            chunks = pd.read_csv(source, chunksize=chunk_rows, low_memory=False)
        except pd.errors.EmptyDataError:
            chunks = []
    for chunk in chunks:
        if "status" in chunk:
            bad = chunk["status"].astype(str) == FAILED_ROW
            failed += int(bad.sum())
            chunk = chunk[~bad]
        group = [k for k in keys if k in chunk]
        metrics = [c for c in chunk.columns if c not in group and c not in RUNNER_COLUMNS
                   and c not in skip and c.endswith(suffix)
                   and pd.api.types.is_numeric_dtype(chunk[c])]
        if chunk.empty or not metrics:
            continue
        partial.append(_chunk_stats(chunk, group, metrics))
    if not partial:
        return pd.DataFrame(columns=[*keys, "metric", "n", "mean", "std", "ci_low", "ci_high",
                                     "interval"]), failed
    stats = pd.concat(partial, ignore_index=True)
    group = [c for c in stats.columns if c not in ("n", "mean", "m2")]
    if len(partial) > 1:
        stats = _combine(stats, group)
    n = stats["n"].to_numpy(float)
    mean = stats["mean"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(n > 1, np.sqrt(stats["m2"].to_numpy(float) / (n - 1)), np.nan)
    is_binary = stats["metric"].isin(list(binary)).to_numpy()
    w_low, w_high = wilson_interval(np.round(mean * n), n)
    t_low, t_high = _clipped(stats["metric"], *t_interval(mean, std, n), bounds)
    out = stats[group].copy()
    out["n"] = n.astype(int)
    out["mean"], out["std"] = mean, std
    out["ci_low"] = np.where(is_binary, w_low, t_low)
    out["ci_high"] = np.where(is_binary, w_high, t_high)
    out["interval"] = np.where(is_binary, "wilson", "t")
    return out, failed


def _chunk_stats(chunk: pd.DataFrame, group: list[str], metrics: list[str]) -> pd.DataFrame:
    """``(*group, metric, n, mean, m2)`` of one chunk: one row per group and metric with at
    least one value, metric by metric, each metric's groups in the order of their first
    value (the long format's order). ``n``, ``mean`` and the variance come from pandas'
    grouped count, mean and var over the chunk's rows in order."""
    values = chunk[metrics]
    keys = [chunk[k] for k in group]
    grouped = values.groupby(keys, sort=False, dropna=False)
    n, mean, var = grouped.count(), grouped.mean(), grouped.var()
    row = np.where(values.notna().to_numpy(), np.arange(len(chunk))[:, None], len(chunk))
    first = pd.DataFrame(row, columns=metrics, index=chunk.index).groupby(
        keys, sort=False, dropna=False).min()
    counts = n.to_numpy().T.ravel()  # metric-major: every group of the first metric, ...
    which = np.repeat(np.arange(len(metrics)), len(n))
    order = np.lexsort((first.to_numpy().T.ravel(), which))
    order = order[counts[order] > 0]
    out = n.index.to_frame(index=False).iloc[order % len(n)].reset_index(drop=True)
    out["metric"] = np.asarray(metrics, dtype=object)[which[order]]
    out["n"] = counts[order]
    out["mean"] = mean.to_numpy(float).T.ravel()[order]
    variance = var.to_numpy(float).T.ravel()[order]
    out["m2"] = np.where(out["n"].to_numpy() > 1, variance * (out["n"] - 1), 0.0)
    return out


def _combine(stats: pd.DataFrame, group: list[str]) -> pd.DataFrame:
    """Exact pooling of per-chunk (n, mean, M2) rows that share a group."""
    stats = stats.assign(sum=stats["n"] * stats["mean"])
    g = stats.groupby(group, sort=False, dropna=False)
    pooled = g[["n", "sum"]].sum()
    pooled["mean"] = pooled["sum"] / pooled["n"]
    stats = stats.join(pooled["mean"].rename("pooled"), on=group)
    stats["m2"] += stats["n"] * (stats["mean"] - stats["pooled"]) ** 2
    pooled["m2"] = stats.groupby(group, sort=False, dropna=False)["m2"].sum()
    # an infinite value makes the variance undefined, as in one chunk (pandas' var is NaN;
    # the grouped sum above would skip that chunk's NaN and report inf)
    pooled.loc[~np.isfinite(pooled["mean"]), "m2"] = np.nan
    return pooled.drop(columns="sum").reset_index()

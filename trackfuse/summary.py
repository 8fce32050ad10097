"""Summaries of ``trials.csv``: per point x row keys x metric, n, mean, std and a 95 % interval
(columns: ``docs/outputs.md``). The CSV is read in chunks whose (n, mean, M2) combine exactly
(Chan, Golub & LeVeque 1979), so memory stays flat and the result does not depend on the
schedule; failed trials' rows are left out and counted."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from trackfuse import store
from trackfuse.rowformat import FAILED_ROW, RUNNER_COLUMNS
from trackfuse.stats import rmse_intervals, t_interval, wilson_interval

CHUNK_ROWS = 200_000
#: The statistics of a group and metric in one chunk, which the chunks' pooling needs.
STAT_COLUMNS = ("n", "mean", "m2")


class ChunkStats:
    """The ``(*group, metric, n, mean, m2)`` rows of every chunk read so far, kept small: a
    chunk whose groups and metrics come in the order of the chunk before it keeps only its
    three statistics, 24 bytes a group and metric, and shares the key columns of the first
    such chunk. That is the case when a point spans many chunks and a chunk holds whole
    trials (200,000 rows of 40-row or 160-row trials); a chunk that starts mid-trial lists
    its groups in another order and keeps its own key columns too."""

    def __init__(self) -> None:
        self.chunks: list[tuple[pd.DataFrame, list[np.ndarray]]] = []
        #: The last chunk's key columns, compared with the next chunk's (comparing with the
        #: kept ones would add to pandas' record of their views, chunk after chunk).
        self._last: pd.DataFrame | None = None

    def add(self, stats: pd.DataFrame) -> None:
        """Keep one chunk's ``stats`` (:func:`_chunk_stats`)."""
        keys = stats.drop(columns=list(STAT_COLUMNS))
        same = self._last is not None and self._last.equals(keys)
        self._last = keys
        kept = self.chunks[-1][0] if same else keys
        self.chunks.append((kept, [stats[c].to_numpy(copy=True) for c in STAT_COLUMNS]))

    def frame(self) -> pd.DataFrame:
        """The rows of every chunk, in order, as the chunks gave them."""
        return pd.concat([keys.assign(**dict(zip(STAT_COLUMNS, values, strict=True)))
                          for keys, values in self.chunks], ignore_index=True)


def _clipped(metrics: pd.Series, low: np.ndarray, high: np.ndarray,
             bounds: Mapping[str, tuple[float, float]] | tuple[float, float] | None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Interval ends ``low, high`` (per row of ``metrics``) clipped to each metric's ``bounds``."""
    if isinstance(bounds, tuple):
        bounds = dict.fromkeys(metrics.unique(), bounds)
    for metric, (lo, hi) in (bounds or {}).items():
        mine = (metrics == metric).to_numpy()
        low = np.where(mine, np.clip(low, lo, hi), low)
        high = np.where(mine, np.clip(high, lo, hi), high)
    return low, high


def summarize(source: Path | pd.DataFrame, keys: Sequence[str], binary: Sequence[str] = (),
              chunk_rows: int = CHUNK_ROWS, suffix: str = "", skip: Sequence[str] = (),
              bounds: Mapping[str, tuple[float, float]] | tuple[float, float] | None = None,
              rms: Sequence[str] = ()) -> tuple[pd.DataFrame, int]:
    """``(summary, failed_rows)`` of the CSV at ``source`` (or of that CSV already read whole).
    ``keys`` group; every other numeric column ending in ``suffix`` and not in ``skip`` is a
    metric: Wilson intervals for ``binary``, root mean square for ``rms``, else Student-t, clipped
    to ``bounds`` ``(low, high)`` if given."""
    partial = ChunkStats()
    squares: dict[tuple, list[np.ndarray]] = {}
    failed = 0
    for chunk in _chunks(source, chunk_rows):
        failed += _add_chunk(chunk, keys, suffix, skip, rms, partial, squares)
        del chunk  # before the next chunk is read: one chunk in memory, not two
    if not partial.chunks:
        return pd.DataFrame(columns=[*keys, "metric", "n", "mean", "std", "ci_low", "ci_high",
                                     "interval"]), failed
    stats = partial.frame()
    group = [c for c in stats.columns if c not in STAT_COLUMNS]
    if len(partial.chunks) > 1:
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
    if squares:
        _as_rms(out, group, squares)
    return out, failed


def _add_chunk(chunk: pd.DataFrame, keys: Sequence[str], suffix: str, skip: Sequence[str],
               rms: Sequence[str], partial: ChunkStats,
               squares: dict[tuple, list[np.ndarray]]) -> int:
    """Append the ``(n, mean, M2)`` of one chunk's rows that did not fail to ``partial`` (and
    the squares of its ``rms`` metrics to ``squares``); return the number that failed."""
    failed = 0
    if "status" in chunk:
        bad = chunk["status"].astype(str) == FAILED_ROW
        failed = int(bad.sum())
        if failed:  # no copy of the chunk when every row is valid
            chunk = chunk[~bad]
    group = [k for k in keys if k in chunk]
    metrics = [c for c in chunk.columns if c not in group and c not in RUNNER_COLUMNS
               and c not in skip and c.endswith(suffix)
               and pd.api.types.is_numeric_dtype(chunk[c])]
    if chunk.empty or not metrics:
        return failed
    if mine := [m for m in rms if m in metrics]:
        chunk = chunk.assign(**{m: chunk[m] ** 2 for m in mine})
        _keep_squares(chunk, group, mine, squares)
    partial.add(_chunk_stats(chunk, group, metrics))
    return failed


def _chunks(source: Path | pd.DataFrame, chunk_rows: int) -> Iterable[pd.DataFrame]:
    """``source`` (CSV, Parquet or a frame) in chunks of ``chunk_rows`` rows."""
    if isinstance(source, pd.DataFrame):
        return (source.iloc[i:i + chunk_rows] for i in range(0, len(source), chunk_rows))
    return store.chunks(Path(source), chunk_rows)


def _keep_squares(chunk: pd.DataFrame, group: list[str], metrics: list[str],
                  squares: dict[tuple, list[np.ndarray]]) -> None:
    """Append each group's squared values of ``metrics`` (NaN dropped) to ``squares``."""
    for metric in metrics:
        grouped = chunk.groupby(group, sort=False, dropna=False)[metric] if group \
            else [((), chunk[metric])]
        for key, values in grouped:
            key = key if isinstance(key, tuple) else (key,)
            kept = values.dropna().to_numpy(float)
            squares.setdefault((*key, metric), []).append(kept)


def _as_rms(out: pd.DataFrame, group: list[str], squares: dict[tuple, list[np.ndarray]]
            ) -> None:
    """Turn the rows of ``out`` that have ``squares`` into an RMS with its interval, in place."""
    keys = [tuple(row) for row in out[group].itertuples(index=False)]  # (*keys, metric)
    rows = [i for i, key in enumerate(keys) if key in squares]
    if not rows:
        return
    bounds = rmse_intervals([np.concatenate(squares[keys[i]]) for i in rows])
    at = out.index[rows]
    out.loc[at, "mean"] = np.sqrt(out.loc[at, "mean"].to_numpy(float))
    out.loc[at, "std"] = np.nan
    out.loc[at, "ci_low"], out.loc[at, "ci_high"] = bounds[:, 0], bounds[:, 1]
    out.loc[at, "interval"] = "bootstrap-t rms"


def _chunk_stats(chunk: pd.DataFrame, group: list[str], metrics: list[str]) -> pd.DataFrame:
    """``(*group, metric, n, mean, m2)`` of one chunk, in the long format's order."""
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

"""A run's failed trials in words: each left one row with ``status == "failed"`` and its
error in ``trials.csv`` (:mod:`trackfuse.batch`), which ``trackfuse run`` and the report
name instead of a bare count."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

import pandas as pd

from trackfuse import store
from trackfuse.rowformat import FAILED_ROW
from trackfuse.summary import CHUNK_ROWS


def _value_text(value: object) -> str:
    """A swept value as the user wrote it: ``0`` rather than ``0.0``."""
    try:
        return f"{float(value):.12g}"
    except (TypeError, ValueError):
        return str(value)


def _describe(row: pd.Series, swept: Sequence[str]) -> str:
    """``point 0 (clutter.mean=0), trial 0: ValueError: math domain error`` for the failed
    row ``row`` of ``trials.csv`` whose swept columns are ``swept``."""
    values = ", ".join(f"{k}={_value_text(row[k])}" for k in swept if k in row.index)
    where = f"point {row['point']}" + (f" ({values})" if values else "")
    return f"{where}, trial {row['trial']}: {' '.join(str(row.get('error', '')).split())}"


def first_failure(source: Path | pd.DataFrame, swept: Sequence[str]) -> str | None:
    """The first failed trial of ``trials.csv`` (path or frame) in words, or ``None``."""
    chunks: Iterable[pd.DataFrame]
    if isinstance(source, pd.DataFrame):
        chunks = [source]
    elif Path(source).suffix == ".parquet":
        chunks = store.chunks(Path(source), CHUNK_ROWS, {"point", "trial", "status", "error",
                                                          *swept})
    else:
        wanted = {"point", "trial", "status", "error", *swept}
        chunks = pd.read_csv(source, chunksize=CHUNK_ROWS, dtype=str, keep_default_na=False,
                             usecols=lambda c: c in wanted)
    for chunk in chunks:
        if "status" not in chunk:
            return None
        failed = chunk[chunk["status"].astype(str) == FAILED_ROW]
        if not failed.empty:
            return _describe(failed.iloc[0], swept)
    return None

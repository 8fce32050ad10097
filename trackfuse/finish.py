"""The first steps after the last batch: merge the verified parts into the final files, then
summarise them. Each returns what the manifest's ``files`` records of what it wrote (size
and SHA-256, and rows for the trials); the runner then draws the report and writes the
manifest (:meth:`trackfuse.runner.Runner.run`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from trackfuse.experiments.base import NON_NEGATIVE, Experiment
from trackfuse.results import (
    CONFIG,
    SUMMARY,
    TIMING_SUMMARY,
    TIMINGS,
    TRIALS,
    TRIALS_PARQUET,
    BatchSpan,
    RunFolder,
    atomic_write,
    sha256_file,
)
from trackfuse.rowformat import TIME_SUFFIX
from trackfuse.rowtable import frame_csv
from trackfuse.sequential import SequentialCounts
from trackfuse.store import write_parquet
from trackfuse.summary import summarize


@dataclass
class Merged:
    """The final files written so far (file name -> its manifest record) and the trial
    rows they hold; ``timed``: whether any trial recorded a time (``timings.csv``)."""

    files: dict[str, dict[str, Any]]
    rows: int
    timed: bool


def merge(folder: RunFolder, spans: Callable[[], Iterable[BatchSpan]], config_file:
          dict[str, Any], store: str, on_phase: Callable[[str], None]) -> Merged:
    """Merge the parts of ``spans()`` into ``trials.csv`` (``trials.parquet`` with ``store``
    ``parquet``) and ``timings.csv`` (removed when no trial was timed); ``config_file``:
    the record of ``config.yaml``. Raises :class:`~trackfuse.results.PartDamaged`."""
    path = folder.path
    on_phase("merging parts into trials.csv")
    files = {CONFIG: config_file, TRIALS: folder.merge(spans, "trials", TRIALS)}
    if store == "parquet":
        on_phase("writing trials.parquet")
        files[TRIALS_PARQUET] = write_parquet(path / TRIALS, path / TRIALS_PARQUET)
        del files[TRIALS]
    rows = files.get(TRIALS, files.get(TRIALS_PARQUET))["rows"]
    timings = folder.merge(spans, "timings", TIMINGS)
    if timings["rows"]:
        files[TIMINGS] = timings
    else:
        (path / TIMINGS).unlink()
    return Merged(files, rows, bool(timings["rows"]))


def summarise(path: Path, trials: pd.DataFrame | Path, keys: list[str], experiment: Experiment,
              sequential: SequentialCounts | None, timed: bool) -> tuple[dict[str, Any], int]:
    """Write ``summary.csv`` of ``trials`` (the merged rows, or their file) by ``keys``, and
    ``timings_summary.csv`` when ``timed``; return their manifest records and the number of
    failed trial rows."""
    summary, failed_rows = summarize(trials, keys, experiment.binary_metrics,
                                     skip=experiment.categorical_metrics,
                                     bounds=experiment.metric_bounds,
                                     rms=experiment.rms_metrics)
    if sequential is not None:  # each interval with the rule that stopped it
        summary["stopping"] = summary["point"].map(sequential.stopping)
    files = {SUMMARY: _write_record(path / SUMMARY, frame_csv(summary))}
    if timed:
        timing_summary, _ = summarize(path / TIMINGS, keys, suffix=TIME_SUFFIX,
                                      bounds=NON_NEGATIVE)
        files[TIMING_SUMMARY] = _write_record(path / TIMING_SUMMARY, frame_csv(timing_summary))
    else:
        (path / TIMING_SUMMARY).unlink(missing_ok=True)
    return files, failed_rows


def _write_record(path: Path, text: str) -> dict[str, Any]:
    """Write ``text`` atomically; return its size and checksum for the manifest."""
    atomic_write(path, text)
    return {"bytes": path.stat().st_size, "sha256": sha256_file(path)}

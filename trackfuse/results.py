"""The run folder on disk: atomic files, per-batch parts, the merged CSVs and the manifest.

Layout of ``<out>/<config-stem>/<run-id>/``::

    config.yaml        resolved config (what produced the numbers)
    manifest.json      provenance and status: "running", "interrupted" or "complete"
    parts/             one trials part and one timings part per finished batch (resume state)
    trials.csv         tidy rows, merged from the parts in (point, batch) order
    timings.csv        wall/CPU-time columns (``*_time_s``), kept out of trials.csv
    summary.csv        per point x row keys x metric: n, mean, std, 95 % CI
    tables/, figures/  experiment reports

Every file is written to a temporary name in the same folder and renamed into place, so a
killed process leaves either the old file or the new one, never half of one. A batch exists
iff its trials part exists; the run is complete iff the manifest says so.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import yaml

TRIALS, TIMINGS, SUMMARY, MANIFEST, CONFIG = (
    "trials.csv", "timings.csv", "summary.csv", "manifest.json", "config.yaml")
TIME_SUFFIX = "_time_s"


def atomic_write(path: Path, data: str | bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file, fsync and rename."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        fh.write(data.encode() if isinstance(data, str) else data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def run_id(resolved: dict[str, Any], version: str) -> str:
    """Stable id of everything that determines the numbers: config, seed, package version."""
    science = {k: resolved[k] for k in ("experiment", "trials", "seed", "batch_size", "params",
                                        "sweep", "sweep_mode")}
    blob = json.dumps({"config": science, "version": version}, sort_keys=True, default=str)
    return f"seed{resolved['seed']}-{hashlib.sha256(blob.encode()).hexdigest()[:10]}"


def format_value(value: Any) -> str:
    """One CSV cell: shortest round-trip repr for floats, ints as ints, bools as 0/1."""
    if hasattr(value, "dtype") and hasattr(value, "item"):
        value = value.item()  # numpy scalar -> Python scalar
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    if isinstance(value, (list, tuple)):
        return ";".join(format_value(v) for v in value)
    return str(value)


def rows_to_csv(rows: Sequence[dict[str, Any]]) -> str:
    """CSV text (with header) for ``rows``; columns in order of first appearance."""
    columns: dict[str, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([format_value(row.get(c)) for c in columns])
    return buf.getvalue()


class RunFolder:
    """One run's folder: parts for resume, merge into final CSVs, manifest."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.parts = self.path / "parts"

    # -- state ------------------------------------------------------------------------------
    def prepare(self, resolved: dict[str, Any]) -> None:
        """Create the folder, write config.yaml, and remove temporaries left by a crash."""
        self.parts.mkdir(parents=True, exist_ok=True)
        for stale in list(self.path.glob(".*.tmp")) + list(self.parts.glob(".*.tmp")):
            stale.unlink(missing_ok=True)
        atomic_write(self.path / CONFIG, yaml.safe_dump(resolved, sort_keys=False))

    @staticmethod
    def part_name(point: int, batch: int) -> str:
        return f"p{point:06d}-b{batch:07d}"

    def finished_batches(self) -> set[tuple[int, int]]:
        """(point, batch) of every batch whose trials part is on disk."""
        found = set()
        for part in self.parts.glob("p*-b*.trials.csv"):
            point, batch = part.name.split(".")[0][1:].split("-b")
            found.add((int(point), int(batch)))
        return found

    def write_part(self, name: str, trials_csv: str, timings_csv: str) -> None:
        """Store one finished batch (timings first, so a trials part implies both)."""
        atomic_write(self.parts / f"{name}.timings.csv", timings_csv)
        atomic_write(self.parts / f"{name}.trials.csv", trials_csv)

    def read_manifest(self) -> dict[str, Any] | None:
        try:
            return json.loads((self.path / MANIFEST).read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None

    def write_manifest(self, manifest: dict[str, Any]) -> None:
        atomic_write(self.path / MANIFEST, json.dumps(manifest, indent=2, sort_keys=False) + "\n")

    # -- merge ------------------------------------------------------------------------------
    def merge(self, names: Iterable[str], kind: str, target: str) -> int:
        """Concatenate the ``kind`` parts of ``names`` (in the given order) into ``target``.

        Parts may have different columns; the merged header is their union in order of
        first appearance and missing cells are empty. Streams part by part, so memory stays
        flat. Returns the number of data rows written.
        """
        names = list(names)
        header: dict[str, None] = {}
        for name in names:
            with open(self.parts / f"{name}.{kind}.csv", newline="") as fh:
                header.update(dict.fromkeys(next(csv.reader(fh), [])))
        columns = list(header)
        tmp = self.path / f".{target}.{os.getpid()}.tmp"
        rows = 0
        with open(tmp, "w", newline="") as out:
            writer = csv.writer(out, lineterminator="\n")
            writer.writerow(columns)
            for name in names:
                with open(self.parts / f"{name}.{kind}.csv", newline="") as fh:
                    reader = csv.reader(fh)
                    own = next(reader, [])
                    if own == columns:
                        for row in reader:
                            writer.writerow(row)
                            rows += 1
                        continue
                    index = [own.index(c) if c in own else -1 for c in columns]
                    for row in reader:
                        writer.writerow([row[i] if i >= 0 else "" for i in index])
                        rows += 1
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, self.path / target)
        return rows


def split_timings(rows: list[dict[str, Any]], keys: Sequence[str]) -> tuple[list[dict], list[dict]]:
    """Split rows into (trial rows without ``*_time_s`` columns, timing rows with ``keys``)."""
    trial_rows, timing_rows = [], []
    for row in rows:
        times = {k: v for k, v in row.items() if k.endswith(TIME_SUFFIX)}
        trial_rows.append({k: v for k, v in row.items() if not k.endswith(TIME_SUFFIX)})
        if times:
            timing_rows.append({**{k: row[k] for k in keys if k in row}, **times})
    return trial_rows, timing_rows

"""Find the run folders under an output root and say what each one holds.

A run folder is ``<root>/<config-stem>/<run-id>/`` with a ``manifest.json``; this module
reads only manifests and file sizes (never the CSVs), so listing thousands of runs is quick.
Each run's status is :func:`trackfuse.runstate.run_state` in words, as ``plot`` and
``compare`` decide it; a folder whose manifest cannot be read is listed as
:data:`~trackfuse.runstate.DAMAGED`. :func:`trackfuse.rundata.load` (which also compares
checksums) says what is wrong.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

from trackfuse.coerce import int_or
from trackfuse.results import (
    MANIFEST,
    PART_KINDS,
    RunFolder,
    RunFolderError,
    RunStatus,
    part_names,
)
from trackfuse.runstate import DAMAGED, STOPPED, run_state


@dataclass(frozen=True)
class RunInfo:
    """One run folder as its manifest describes it (times as ISO-8601 text)."""

    path: Path
    stem: str
    experiment: str
    name: str
    status: str
    trials_done: int
    trials_total: int
    started: str
    wall_s: float | None


def _wall_seconds(manifest: dict[str, Any]) -> float | None:
    """Seconds from the first start to the finish of a complete run, else ``None``."""
    try:
        first = datetime.fromisoformat(str(manifest["first_started"]))
        end = datetime.fromisoformat(str(manifest["finished"]))
    except (KeyError, TypeError, ValueError):
        return None
    return (end - first).total_seconds()


def _saved_trials(path: Path, manifest: dict[str, Any]) -> int:
    """Trials of the batches of the run's plan whose two parts are in ``parts/`` (names only,
    none read): what a running or stopped run has saved, which its manifest (rewritten at
    most every few seconds) lags behind."""
    per_point, batch = int_or(manifest.get("trials_per_point")), int_or(manifest.get("batch_size"))
    points = int_or(manifest.get("points"))
    if batch < 1:
        return int_or(manifest.get("trials_done"))
    kinds: dict[tuple[int, int], set[str]] = {}
    for point, number, kind in part_names(RunFolder(path).parts):
        if point < points and number * batch < per_point:
            kinds.setdefault((point, number), set()).add(kind)
    return sum(min(batch, per_point - number * batch)
               for (_, number), found in kinds.items() if found == set(PART_KINDS))


def _info(path: Path, manifest: dict[str, Any]) -> RunInfo:
    state = run_state(path, manifest)
    done = (_saved_trials(path, manifest) if state.status in (RunStatus.RUNNING, STOPPED)
            else int_or(manifest.get("trials_done")))
    return RunInfo(path, path.parent.name, str(manifest.get("experiment", "")),
                   str(manifest.get("name") or ""), str(state),
                   done, int_or(manifest.get("trials_total")),
                   str(manifest.get("first_started") or manifest.get("started") or ""),
                   _wall_seconds(manifest))


def is_run_folder(path: Path) -> bool:
    return (Path(path) / MANIFEST).is_file()


def find_runs(root: Path) -> list[RunInfo]:
    """Every run folder at ``root`` itself, one level below it (a config stem's folder) or
    two levels below (an output root), newest first."""
    root = Path(root)
    candidates = [root] + sorted(root.glob("*")) + sorted(root.glob("*/*"))
    found = []
    for path in candidates:
        try:
            if not path.is_dir() or not is_run_folder(path):
                continue
        except OSError:  # a folder this user may not read (another user's, /proc/1/cwd)
            continue
        try:
            manifest = RunFolder(path).read_manifest()
        except RunFolderError:
            found.append(RunInfo(path, path.parent.name, "", "", DAMAGED, 0, 0, "", None))
            continue
        if manifest is not None:
            found.append(_info(path, manifest))
    return sorted(found, key=lambda r: r.started, reverse=True)

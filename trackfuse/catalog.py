"""Find the run folders under an output root and say what each one holds.

Reads only manifests, file sizes and the small ``config.yaml`` (never the CSVs), so listing
thousands of runs is quick. Each run's status is :func:`trackfuse.runstate.run_state` in
words; an unreadable manifest is :data:`~trackfuse.runstate.DAMAGED` (``trackfuse.load`` says
what is wrong). :func:`differences` picks the values in which each run differs from the other
runs of its experiment; :func:`runs` (``trackfuse.runs(path)``) returns every run as one row
of a DataFrame (``docs/outputs.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from trackfuse.manifest import Manifest, read_manifest
from trackfuse.results import (
    CONFIG,
    MANIFEST,
    PART_KINDS,
    RunFolder,
    RunFolderError,
    RunStatus,
    part_names,
)
from trackfuse.runstate import DAMAGED, STOPPED, run_state
from trackfuse.safe_yaml import YamlInputError, read_yaml_file

if TYPE_CHECKING:  # listing runs on the command line loads no pandas
    import pandas as pd


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
    #: The root seed and the trials per sweep point (``None`` where not recorded).
    seed: int | None = None
    trials_per_point: int | None = None
    #: Every parameter of the run's config by dotted key; a swept key holds its list of
    #: values (empty when ``config.yaml`` cannot be read).
    params: dict[str, Any] = field(default_factory=dict)


def _params(path: Path) -> dict[str, Any]:
    """The parameters of the run at ``path`` from its ``config.yaml`` (swept keys as their
    lists of values), or ``{}`` when it is missing or not a run's config."""
    try:
        config = read_yaml_file(path / CONFIG, regular_only=True)  # a FIFO: no wait
    except (OSError, YamlInputError):
        return {}
    if not isinstance(config, dict) or not isinstance(config.get("params"), dict):
        return {}
    sweep = config.get("sweep") if isinstance(config.get("sweep"), dict) else {}
    return {**config["params"], **sweep}


def _wall_seconds(manifest: Manifest) -> float | None:
    """Seconds from the first start to the finish of a complete run, else ``None``."""
    try:
        first = datetime.fromisoformat(str(manifest.first_started))
        end = datetime.fromisoformat(str(manifest.finished))
    except ValueError:
        return None
    return (end - first).total_seconds()


def _saved_trials(path: Path, manifest: Manifest) -> int:
    """Trials of the batches of the run's plan whose two parts are in ``parts/`` (names only,
    none read): what a running or stopped run has saved, which its manifest (rewritten at
    most every few seconds) lags behind."""
    per_point, batch = manifest.trials_per_point or 0, manifest.batch_size or 0
    points = manifest.points or 0
    if batch < 1:
        return manifest.trials_done or 0
    kinds: dict[tuple[int, int], set[str]] = {}
    for point, number, kind in part_names(RunFolder(path).parts):
        if point < points and number * batch < per_point:
            kinds.setdefault((point, number), set()).add(kind)
    return sum(min(batch, per_point - number * batch)
               for (_, number), found in kinds.items() if found == set(PART_KINDS))


def _info(path: Path, manifest: Manifest) -> RunInfo:
    state = run_state(path, manifest)
    done = (_saved_trials(path, manifest) if state.status in (RunStatus.RUNNING, STOPPED)
            else manifest.trials_done or 0)
    return RunInfo(path, path.parent.name, manifest.experiment or "", manifest.name or "",
                   str(state), done, manifest.trials_total or 0,
                   manifest.first_started or manifest.started or "",
                   _wall_seconds(manifest), manifest.root_seed, manifest.trials_per_point,
                   _params(path))


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
            manifest = read_manifest(path)
        except RunFolderError:
            found.append(RunInfo(path, path.parent.name, "", "", DAMAGED, 0, 0, "", None))
            continue
        if manifest is not None:
            found.append(_info(path, manifest))
    return sorted(found, key=lambda r: r.started, reverse=True)


def differences(runs: list[RunInfo]) -> list[dict[str, Any]]:
    """For each of ``runs``, in order, ``{key: value}`` of the parameters (and ``seed``,
    ``trials``) whose values are not the same in every run of its experiment listed: what
    tells the runs of one experiment apart. A run alone of its experiment differs in
    nothing."""
    def described(run: RunInfo) -> dict[str, Any]:
        return {"seed": run.seed, "trials": run.trials_per_point, **run.params}

    by_experiment: dict[str, list[dict[str, Any]]] = {}
    for run in runs:
        by_experiment.setdefault(run.experiment, []).append(described(run))
    varying: dict[str, set[str]] = {}
    for experiment, values in by_experiment.items():
        keys = dict.fromkeys(k for v in values for k in v)
        varying[experiment] = {k for k in keys
                               if len({repr(v.get(k)) for v in values}) > 1}
    return [{k: v for k, v in described(run).items() if k in varying[run.experiment]}
            for run in runs]


def runs(path: str | Path = "results") -> pd.DataFrame:
    """Every run under ``path`` (:func:`find_runs`), newest first, one row each: ``path``,
    ``experiment``, ``status``, ``name``, ``seed``, ``trials`` (per sweep point),
    ``trials_done``, ``trials_total``, ``start`` (UTC timestamp), ``wall_s`` (seconds from
    the first start to the finish; NaN unless complete), then ``params.<key>`` for every
    parameter of any run (a swept key: its list of values; missing where a run's experiment
    lacks the key). Like MLflow's ``search_runs``: filter and group it with pandas."""
    import pandas as pd
    found = find_runs(Path(path))
    rows = [{"path": str(r.path), "experiment": r.experiment, "status": r.status,
             "name": r.name, "seed": r.seed, "trials": r.trials_per_point,
             "trials_done": r.trials_done, "trials_total": r.trials_total,
             "start": pd.to_datetime(r.started or None, utc=True),
             "wall_s": r.wall_s, **{f"params.{k}": v for k, v in r.params.items()}}
            for r in found]
    columns = ["path", "experiment", "status", "name", "seed", "trials", "trials_done",
               "trials_total", "start", "wall_s"]
    frame = pd.DataFrame(rows, columns=[*columns, *dict.fromkeys(
        k for row in rows for k in row if k not in columns)])
    return frame.astype({"seed": "Int64", "trials": "Int64", "wall_s": float})

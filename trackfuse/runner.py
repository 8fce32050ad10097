"""Run a validated config: plan batches, seed trials, execute, resume, write outputs.

Seeding: trial ``t`` of sweep point ``p`` under root seed ``s`` draws from the two streams of
:func:`trackfuse.seeding.trial_streams` (one common to every sweep point, one specific to
the point) and nothing else, so the numbers do not depend on worker count, executor, batch
placement or completion order. Trials are cut into batches of
``batch_size`` by trial index alone; finished batches are stored as parts and the final CSVs
are merged in (point, batch) order, so any schedule writes byte-identical files.

Resume: the run folder's name is a hash of everything that determines the numbers. Running
the same config again finds the finished parts and computes only the missing batches.
"""

from __future__ import annotations

import platform
import subprocess
import sys
import time
import traceback
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import scipy

import trackfuse
from trackfuse.config import Config
from trackfuse.executors import make_executor
from trackfuse.experiments.base import Experiment
from trackfuse.progress import RunProgress
from trackfuse.results import (
    SUMMARY,
    TIMINGS,
    TRIALS,
    RunFolder,
    atomic_write,
    rows_to_csv,
    run_id,
    split_timings,
)
from trackfuse.seeding import batch_streams, trial_streams
from trackfuse.summary import summarize
from trackfuse.sweep import SweepPoint, expand

MANIFEST_EVERY_S = 5.0
TIMING_SUMMARY = "timings_summary.csv"


class RunInterrupted(Exception):
    """Ctrl-C during a run; the finished batches are saved and the run can be resumed."""

    def __init__(self, folder: Path, done: int, total: int):
        self.folder, self.done, self.total = folder, done, total
        super().__init__(f"interrupted after {done}/{total} trials")


@dataclass(frozen=True)
class BatchTask:
    """Everything a worker needs to run one batch (picklable, self-contained)."""

    experiment: Experiment
    params: dict[str, Any]
    point: int
    swept: dict[str, Any]
    seed: int
    batch: int
    first_trial: int
    stop_trial: int


@dataclass(frozen=True)
class BatchResult:
    """A finished batch as CSV text, ready to store."""

    point: int
    batch: int
    trials: int
    trials_csv: str
    timings_csv: str
    wall_s: float


@dataclass
class RunOutcome:
    """What a run produced (for the CLI's closing lines)."""

    folder: Path
    status: str  # "complete" (finished now) or "already complete" (nothing to do)
    total_trials: int
    computed_trials: int
    failed_trials: int = 0
    rows: int = 0
    figures: list[Path] = field(default_factory=list)
    figure_errors: list[str] = field(default_factory=list)
    seconds: float = 0.0


def _failure(prefix: dict[str, Any], err: BaseException) -> dict[str, Any]:
    text = "".join(traceback.format_exception_only(type(err), err)).strip().replace("\n", " ")
    return {**prefix, "algorithm": "", "status": "failed", "error": text[:500]}


def execute_batch(task: BatchTask) -> BatchResult:
    """Run one batch (in a worker). A trial that raises becomes a ``failed`` row."""
    t0 = time.perf_counter()
    exp = task.experiment
    trials = range(task.first_trial, task.stop_trial)
    prefixes = [{"point": task.point, "trial": t, **task.swept} for t in trials]
    try:
        per_trial = exp.run_trials(task.params, batch_streams(task.seed, task.point, trials))
        if len(per_trial) != len(prefixes):
            raise ValueError(f"run_batch returned {len(per_trial)} trials for {len(prefixes)}")
    except Exception:  # noqa: BLE001 - isolate the failing trial(s) one by one
        per_trial = []
        for t in trials:
            try:
                streams = trial_streams(task.seed, task.point, t)
                per_trial.append(exp.run_trial(task.params, streams))
            except Exception as err:  # noqa: BLE001 - recorded in the CSV, the run goes on
                per_trial.append(err)
    rows: list[dict[str, Any]] = []
    for prefix, result in zip(prefixes, per_trial, strict=True):
        if isinstance(result, BaseException):
            rows.append(_failure(prefix, result))
        else:
            rows.extend({**prefix, **row} for row in result)
    keys = ["point", "trial", *task.swept, *exp.row_keys]
    trial_rows, timing_rows = split_timings(rows, keys)
    return BatchResult(task.point, task.batch, len(prefixes), rows_to_csv(trial_rows),
                       rows_to_csv(timing_rows), time.perf_counter() - t0)


def _git_commit() -> str | None:
    here = Path(trackfuse.__file__).resolve().parent
    try:
        head = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--", "."],
                               capture_output=True, text=True, timeout=5, check=False)
        dirty = dirty.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("-dirty" if dirty else "")


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


class Runner:
    """Run one config into ``<out>/<config-stem>/<run-id>/``."""

    def __init__(self, config: Config, out: Path = Path("results"), *, workers: int = 1,
                 executor: str = "process", scheduler: str | None = None,
                 scheduler_file: str | None = None, plots: bool = True,
                 progress: bool = True, command: list[str] | None = None):
        self.config = config
        self.resolved = config.to_dict()
        self.run_id = run_id(self.resolved, trackfuse.__version__)
        self.folder = RunFolder(Path(out) / Path(config.source).stem / self.run_id)
        self.points = expand(config.sweep, config.sweep_mode)
        self.workers, self.executor_kind = workers, executor
        self.scheduler, self.scheduler_file = scheduler, scheduler_file
        self.plots, self.progress = plots, progress
        self.command = command if command is not None else sys.argv
        self.git_commit = _git_commit()

    @property
    def total_trials(self) -> int:
        return len(self.points) * self.config.trials

    def batches(self) -> Iterator[tuple[SweepPoint, int, int, int]]:
        """Every (point, batch index, first trial, stop trial), lazily, in output order."""
        size, n = self.config.batch_size, self.config.trials
        for point in self.points:
            for batch, first in enumerate(range(0, n, size)):
                yield point, batch, first, min(first + size, n)

    def _tasks(self, todo) -> Iterator[BatchTask]:
        cfg = self.config
        for point, batch, first, stop in todo:
            yield BatchTask(cfg.experiment, {**cfg.params, **point.values}, point.index,
                            point.values, cfg.seed, batch, first, stop)

    def _manifest(self, status: str, started: str, per_point: dict[int, float],
                  failed: int, done: int, previous: dict | None) -> dict[str, Any]:
        versions = {"trackfuse": trackfuse.__version__, "python": platform.python_version(),
                    "numpy": np.__version__, "scipy": scipy.__version__,
                    "pandas": pd.__version__}
        return {
            "status": status,
            "run_id": self.run_id,
            "experiment": self.config.experiment.name,
            "config_file": self.config.source,
            "command": list(self.command),
            "git_commit": self.git_commit,
            "versions": versions,
            "platform": platform.platform(),
            "host": platform.node(),
            "root_seed": self.config.seed,
            "executor": self.executor_kind,
            "workers": self.workers,
            "points": len(self.points),
            "trials_per_point": self.config.trials,
            "batch_size": self.config.batch_size,
            "trials_total": self.total_trials,
            "trials_done": done,
            "trials_failed": failed,
            "first_started": (previous or {}).get("first_started", started),
            "started": started,
            "finished": _now() if status == "complete" else None,
            "sessions": (previous or {}).get("sessions", 0) + 1,
            "per_point_wall_s": {str(k): round(v, 6) for k, v in sorted(per_point.items())},
        }

    def run(self) -> RunOutcome:
        """Compute the missing batches, then merge, summarize and draw."""
        t0 = time.perf_counter()
        previous = self.folder.read_manifest()
        if previous and previous.get("status") == "complete":
            return RunOutcome(self.folder.path, "already complete", self.total_trials, 0,
                              previous.get("trials_failed", 0), previous.get("rows", 0))
        self.folder.prepare(self.resolved)
        started = _now()
        per_point = {int(k): v for k, v in ((previous or {}).get("per_point_wall_s") or {}).items()}
        finished = self.folder.finished_batches()
        todo = [b for b in self.batches() if (b[0].index, b[1]) not in finished]
        done = self.total_trials - sum(stop - first for _, _, first, stop in todo)
        computed = 0
        self.folder.write_manifest(self._manifest("running", started, per_point, 0, done,
                                                  previous))
        label = f"{self.config.experiment.name} [{self.run_id}]"
        if todo:
            executor = make_executor(self.executor_kind, self.workers, self.scheduler,
                                     self.scheduler_file)
            self.workers = executor.workers
            last = time.monotonic()
            try:
                with RunProgress(self.total_trials, done, label, self.progress) as bar:
                    for res in executor.imap_unordered(execute_batch, self._tasks(todo)):
                        self.folder.write_part(RunFolder.part_name(res.point, res.batch),
                                               res.trials_csv, res.timings_csv)
                        per_point[res.point] = per_point.get(res.point, 0.0) + res.wall_s
                        done += res.trials
                        computed += res.trials
                        bar.advance(res.trials)
                        if time.monotonic() - last > MANIFEST_EVERY_S:
                            last = time.monotonic()
                            self.folder.write_manifest(self._manifest(
                                "running", started, per_point, 0, done, previous))
            except KeyboardInterrupt:
                executor.close()
                self.folder.write_manifest(self._manifest("interrupted", started, per_point,
                                                          0, done, previous))
                raise RunInterrupted(self.folder.path, done, self.total_trials) from None
            executor.close()
        outcome = self.finish(started, per_point, previous)
        outcome.computed_trials = computed
        outcome.seconds = time.perf_counter() - t0
        return outcome

    def finish(self, started: str, per_point: dict[int, float],
               previous: dict | None) -> RunOutcome:
        """Merge parts into the final CSVs, summarize, draw, and mark the run complete."""
        names = [RunFolder.part_name(p.index, b) for p, b, _, _ in self.batches()]
        rows = self.folder.merge(names, "trials", TRIALS)
        if self.folder.merge(names, "timings", TIMINGS) == 0:
            (self.folder.path / TIMINGS).unlink()
        keys = ["point", *self.config.sweep, *self.config.experiment.row_keys]
        summary, failed_rows = summarize(self.folder.path / TRIALS, keys,
                                         self.config.experiment.binary_metrics)
        atomic_write(self.folder.path / SUMMARY, summary.to_csv(index=False))
        if (self.folder.path / TIMINGS).exists():
            timing_summary, _ = summarize(self.folder.path / TIMINGS, keys)
            atomic_write(self.folder.path / TIMING_SUMMARY,
                         timing_summary.to_csv(index=False))
        outcome = RunOutcome(self.folder.path, "complete", self.total_trials, 0, failed_rows,
                             rows)
        if self.plots:
            outcome.figures, outcome.figure_errors = draw_reports(
                self.folder.path, self.config.experiment, self.resolved)
        manifest = self._manifest("complete", started, per_point, failed_rows,
                                  self.total_trials, previous)
        manifest["rows"] = rows
        manifest["figure_errors"] = outcome.figure_errors
        self.folder.write_manifest(manifest)
        return outcome


def draw_reports(folder: Path, experiment: Experiment,
                 resolved: dict[str, Any]) -> tuple[list[Path], list[str]]:
    """Draw figures and tables from the CSVs in ``folder`` (no trial is recomputed).

    The summary handed to the experiment includes the timing metrics (``*_time_s``).
    Returns the written figure paths and one message per figure or table that failed.
    """
    written: list[Path] = []
    errors: list[str] = []
    if experiment.tables is None and experiment.figures is None:
        return written, errors
    trials = pd.read_csv(folder / TRIALS, low_memory=False)
    summary = pd.read_csv(folder / SUMMARY, low_memory=False)
    if (folder / TIMING_SUMMARY).exists():
        timing = pd.read_csv(folder / TIMING_SUMMARY, low_memory=False)
        summary = pd.concat([summary, timing], ignore_index=True)
    if experiment.tables is not None:
        tables_dir = folder / "tables"
        tables_dir.mkdir(exist_ok=True)
        try:
            for name, table in experiment.tables(trials, summary, resolved).items():
                atomic_write(tables_dir / f"{name}.csv", table.to_csv(index=False))
                atomic_write(tables_dir / f"{name}.md", markdown_table(table))
        except Exception as err:  # noqa: BLE001 - a report bug must not lose the run
            errors.append(f"tables: {type(err).__name__}: {err}")
    if experiment.figures is None:
        return written, errors
    wanted = resolved.get("outputs", {}).get("figures", "all")
    formats = resolved.get("outputs", {}).get("formats", ["png", "pdf"])
    fig_dir = folder / "figures"
    fig_dir.mkdir(exist_ok=True)
    try:
        figures = experiment.figures(trials, summary, resolved)
    except Exception as err:  # noqa: BLE001
        return written, [*errors, f"figures: {type(err).__name__}: {err}"]
    for name, fig in figures.items():
        if wanted != "all" and name not in wanted:
            plt.close(fig)
            continue
        for fmt in formats:
            path = fig_dir / f"{name}.{fmt}"
            tmp = fig_dir / f".{name}.tmp.{fmt}"
            fig.savefig(tmp, format=fmt, metadata=_metadata(fmt))
            tmp.replace(path)
            written.append(path)
        plt.close(fig)
    return written, errors


def _metadata(fmt: str) -> dict[str, Any] | None:
    """Strip timestamps so figure files are reproducible too."""
    if fmt == "pdf":
        return {"CreationDate": None, "ModDate": None}
    if fmt == "svg":
        return {"Date": None}
    return None


def markdown_table(table: pd.DataFrame) -> str:
    """A GitHub-style Markdown table without the optional ``tabulate`` dependency."""
    def cell(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v).replace("|", "\\|")

    lines = ["| " + " | ".join(map(str, table.columns)) + " |",
             "|" + "|".join("---" for _ in table.columns) + "|"]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |"
              for row in table.itertuples(index=False)]
    return "\n".join(lines) + "\n"


__all__ = ["BatchTask", "RunInterrupted", "RunOutcome", "Runner", "draw_reports",
           "execute_batch", "markdown_table"]

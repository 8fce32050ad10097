"""Run a validated config: plan batches, seed trials, execute, resume, write outputs.

Seeding: trial ``t`` of sweep point ``p`` under root seed ``s`` draws from the two streams of
:func:`trackfuse.seeding.trial_streams` (one common to every sweep point, one keyed by the
point's draw point, :func:`trackfuse.seeding.draw_points`) and nothing else, so the numbers
do not depend on worker count, executor, batch placement or completion order (rows, parts
and resume are keyed by the point itself). Trials are cut into batches of ``batch_size`` by
trial index alone; finished batches are stored as parts and the final CSVs are merged in
(point, batch) order, so for a given ``batch_size`` any schedule writes byte-identical
files. The batch size itself is part of the run id: an experiment's vectorized
``run_batch`` may round the last bits differently for different batch compositions.

Each batch runs in a worker through :func:`trackfuse.batch.execute_batch`, which contains
whatever a trial raises.

Resume: the run folder's name is a hash of everything that determines the numbers. Running
the same config again takes the folder's lock (:mod:`trackfuse.runlock`), keeps the parts
that pass verification (:mod:`trackfuse.results`), recomputes the rest, and merges. The
plan is lazy: batches are generated as they are submitted, never listed whole.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import io
import math
import platform
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from functools import partial
from pathlib import Path
from typing import Any

import pandas as pd

import trackfuse
from trackfuse.batch import BatchTask, execute_batch, watch_sigint
from trackfuse.cluster import JobqueueExecutor
from trackfuse.coerce import int_or
from trackfuse.config import Config
from trackfuse.environment import (
    cpu,
    cpu_words,
    environment_difference,
    library_versions,
    recorded_cpus,
    unseen_cpus,
    version,
    worker_environment,
)
from trackfuse.executors import ExecutorError, make_executor, unpicklable
from trackfuse.experiments import plugin_folder
from trackfuse.experiments.base import NON_NEGATIVE
from trackfuse.failures import first_failure
from trackfuse.fingerprint import code_fingerprint
from trackfuse.progress import RunProgress
from trackfuse.reports import NothingToDraw, figure_formats, load_drawing, write_report
from trackfuse.results import (
    CONFIG,
    INDEX_HTML,
    REPORT_FILES,
    SUMMARY,
    TIME_SUFFIX,
    TIMING_SUMMARY,
    TIMINGS,
    TRIALS,
    TRIALS_PARQUET,
    BatchSpan,
    PartDamaged,
    PartScan,
    RunFolder,
    RunFolderError,
    RunStatus,
    atomic_write,
    config_hash,
    csv_line,
    read_part,
    removed_words,
    run_id,
    sha256_file,
    sibling_manifests,
)
from trackfuse.rowtable import frame_csv
from trackfuse.rundata import RunData, load
from trackfuse.runlock import RunLock, busy_problem, creation_problem
from trackfuse.runstate import has_report
from trackfuse.seeding import draw_points
from trackfuse.sequential import SequentialCounts, widest_half_width
from trackfuse.store import trials_file, write_parquet
from trackfuse.summary import CHUNK_ROWS, summarize
from trackfuse.sweep import expand

MANIFEST_EVERY_S = 5.0
MAX_REPAIRS = 3


class RunInterrupted(Exception):
    """Ctrl-C during a run; the finished batches are saved and the run can be resumed."""

    def __init__(self, folder: Path, done: int, total: int):
        self.folder, self.done, self.total = folder, done, total
        super().__init__(f"interrupted after {done}/{total} trials")


@dataclass
class RunOutcome:
    """What a run produced (for the CLI's closing lines)."""

    folder: Path
    status: RunStatus  # COMPLETE (finished now) or ALREADY_COMPLETE (nothing to do)
    total_trials: int
    computed_trials: int
    failed_trials: int = 0
    first_failure: str | None = None  # the first failed trial in words (trackfuse.failures)
    rows: int = 0
    figures: list[Path] = field(default_factory=list)
    figure_errors: list[str] = field(default_factory=list)
    not_drawn: dict[str, str] = field(default_factory=dict)  # wanted figure -> why not
    report: Path | None = None
    seconds: float = 0.0


# -- the run, in the client ------------------------------------------------------------------
def _git_state(where: Path) -> dict[str, Any] | None:
    """Commit and dirty flag of the git repository containing ``where`` (the folder the
    user runs from), or ``None`` outside a repository or without git."""
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(where), *args], capture_output=True, text=True,
                              timeout=5, check=True).stdout.strip()
    try:
        return {"repository": git("rev-parse", "--show-toplevel"),
                "commit": git("rev-parse", "HEAD"),
                "dirty": bool(git("status", "--porcelain", "--untracked-files=no"))}
    except (OSError, subprocess.SubprocessError):
        return None


def _said(value: Any) -> str:
    """A version for a sentence: ``None`` (not installed, or not recorded) in words."""
    return "not installed or not recorded" if value is None else str(value)


def _with_cpus(recorded: Any, current: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Every CPU that computed a run's batches, in order: ``recorded`` plus ``current``."""
    cpus = recorded_cpus(recorded)
    return cpus + unseen_cpus(current, cpus)


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _print_warning(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr, flush=True)


def config_origin(source: str) -> str:
    """The config file a run is made from: ``source``, or for a run folder's own
    ``config.yaml`` the config that run was made from (its manifest's ``config_file``): run
    again, it finds that run instead of computing it anew under ``<out>/config/``. The
    manifest records it as ``config_file``; its ``command`` keeps the file given."""
    path = Path(source)
    if path.name != CONFIG:
        return source
    try:
        recorded = (RunFolder(path.parent).read_manifest() or {}).get("config_file")
    except RunFolderError:  # an unreadable manifest: the file's own name
        return source
    return recorded if isinstance(recorded, str) and recorded else source


def folder_name(source: str) -> str:
    """The run's folder under the output root: the stem of the config it is made from
    (:func:`config_origin`) without leading dots, so that a config called ``...yaml`` (stem
    ``..``) cannot name the root's parent."""
    return Path(config_origin(source)).stem.lstrip(".") or "config"


@dataclass
class _Session:
    """State of one ``run()`` call, for the manifest."""

    previous: dict[str, Any] | None
    started: str
    config_file: dict[str, Any]
    per_point: dict[int, float]
    done: int = 0
    computed: int = 0


class Runner:
    """Run one config into ``<out>/<config-stem>/<run-id>/``."""

    def __init__(self, config: Config, out: Path = Path("results"), *, workers: int = 1,
                 executor: str = "process", scheduler: str | None = None,
                 scheduler_file: str | None = None, plots: bool = True,
                 progress: bool = True, command: list[str] | None = None,
                 warn: Callable[[str], None] = _print_warning, force: bool = False,
                 name: str | None = None, on_phase: Callable[[str], None] | None = None,
                 cluster: str | None = None):
        self.config = config
        self.resolved = config.to_dict()
        self.code = code_fingerprint(config.experiment)
        self.libraries = library_versions()
        self.run_id = run_id(self.resolved, trackfuse.__version__, self.code.digest,
                             self.libraries)
        self.cpus = [cpu()]  # of the machines that compute: this one, or the dask workers
        self.out = Path(out)
        self.config_file = config_origin(config.source)  # before --force empties the folder
        self.folder = RunFolder(self.out / folder_name(self.config_file) / self.run_id)
        self.points = expand(config.sweep, config.sweep_mode)
        self.draw_points = draw_points(self.points, config.experiment.drawing)
        self.batches_per_point = math.ceil(config.trials / config.batch_size)  # at most
        #: Where a sequential run stands (``None`` for a fixed count, or before it starts).
        self.sequential: SequentialCounts | None = None
        self.workers, self.executor_kind = workers, executor
        self.executor_used: str | None = None
        self.scheduler, self.scheduler_file = scheduler, scheduler_file
        self.cluster = cluster  # a batch system (trackfuse.cluster), or None
        self.plots, self.progress = plots, progress
        self.command = command if command is not None else sys.argv
        self.warn = warn
        self.force, self.name = force, name
        self.on_phase = on_phase or (lambda phase: None)  # told each step after the trials
        self.git = _git_state(Path.cwd())

    @property
    def _on_dask(self) -> bool:
        """Whether the batches run on dask workers (see :func:`make_executor`)."""
        return self.executor_kind == "dask" or bool(self.scheduler or self.scheduler_file
                                                    or self.cluster)

    @property
    def counts(self) -> list[int]:
        """Trials planned per point: the fixed count, or a sequential run's current plan."""
        if self.sequential is not None:
            return self.sequential.counts
        return [self.config.trials] * len(self.points)

    @property
    def total_trials(self) -> int:
        return sum(self.counts)

    def span(self, point: int, batch: int) -> BatchSpan | None:
        """Batch ``batch`` of sweep point ``point``, or ``None`` if the plan has no such batch."""
        if not (0 <= point < len(self.points) and 0 <= batch < self.batches_per_point):
            return None
        first = batch * self.config.batch_size
        return BatchSpan(point, batch, first, min(first + self.config.batch_size,
                                                  self.config.trials))

    def spans(self) -> Iterator[BatchSpan]:
        """Every batch of the run's plan (:attr:`counts`), lazily, in output order."""
        for point, count in enumerate(self.counts):
            for batch in range(math.ceil(count / self.config.batch_size)):
                yield self.span(point, batch)

    def _tasks(self, todo: Iterator[BatchSpan]) -> Iterator[BatchTask]:
        cfg = self.config
        for span in todo:
            swept = self.points[span.point].values
            yield BatchTask(cfg.experiment, {**cfg.params, **swept}, swept, cfg.seed, span,
                            self.draw_points[span.point], cfg.trial_timeout)

    def _manifest(self, status: RunStatus, session: _Session, failed: int = 0) -> dict[str, Any]:
        versions = {"trackfuse": trackfuse.__version__, **self.libraries,
                    "matplotlib": version("matplotlib")}  # None when not installed
        previous = session.previous or {}
        return {
            "status": status,
            "run_id": self.run_id,
            "name": self.name if self.name is not None else previous.get("name"),
            "experiment": self.config.experiment.name,
            "plugin_folder": plugin_folder(self.config.experiment_ref),
            "config_file": self.config_file,
            "command": list(self.command),
            "git": self.git,
            "config_sha256": config_hash(self.resolved),
            "code_fingerprint": {"sha256": self.code.digest, "modules": list(self.code.modules)},
            "trackfuse_path": str(Path(trackfuse.__file__).resolve().parent),
            "versions": versions,
            "platform": platform.platform(),
            "cpu": _with_cpus(previous.get("cpu"), self.cpus),
            "host": platform.node(),
            "root_seed": self.config.seed,
            "executor": self.executor_used or previous.get("executor") or self.executor_kind,
            "executor_requested": self.executor_kind,
            **({"cluster": {"kind": self.cluster, **dataclasses.asdict(self.config.cluster)}}
               if self.cluster else {}),
            "workers": self.workers,
            "points": len(self.points),
            "draw_points": list(self.draw_points),
            "trials_per_point": self.config.trials,
            "batch_size": self.config.batch_size,
            "trials_total": self.total_trials,
            "trials_done": session.done,
            "trials_failed": failed,
            "first_started": previous.get("first_started", session.started),
            "started": session.started,
            "finished": _now() if status == RunStatus.COMPLETE else None,
            "sessions": int_or(previous.get("sessions"), 0) + 1,
            "per_point_wall_s": {str(k): round(v, 6)
                                 for k, v in sorted(session.per_point.items())},
            REPORT_FILES: previous.get(REPORT_FILES, []),  # until drawn anew: ours to delete
            **({"sequential": self.sequential.manifest_entry()} if self.sequential else {}),
        }

    def _check_output_root(self) -> None:
        if self.out.exists() and not self.out.is_dir():
            raise RunFolderError(f"{self.out}: the output root is not a folder")

    def planned_start(self) -> str:
        """What :meth:`run` would start from, in a few words (``--dry-run``): a new run, a
        resume, a complete run or, with ``--force``, a recomputation. Raises
        :class:`~trackfuse.results.RunFolderError` with the reason :meth:`run` would stop
        for when the run folder cannot be created or used; reads, never writes."""
        self._check_output_root()
        if problem := creation_problem(self.folder.path) or busy_problem(self.folder.path):
            raise RunFolderError(problem)
        if not self.folder.path.exists():
            return "new"
        self.folder.check_layout()
        if self.force:
            return "exists; --force recomputes every trial"
        try:
            previous = self.folder.read_manifest()
        except RunFolderError:
            return "unreadable manifest; verifies the saved batches, computes the rest"
        if previous is None:
            return "no manifest; verifies the saved batches, computes the rest"
        status = previous.get("status")
        if status == RunStatus.COMPLETE:
            if problem := self.folder.check_final_files(previous):
                return f"complete, but {problem}; rebuilds the final files"
            if self.plots and not has_report(self.folder.path, previous):
                return "complete; nothing to compute, draws the report"
            return "complete; nothing to compute"
        if status == RunStatus.INTERRUPTED:
            return f"interrupted, {int_or(previous.get('trials_done'), 0)} trials saved; resumes"
        return "stopped before it ended; resumes from its saved batches"

    def run(self) -> RunOutcome:
        """Compute the missing batches, then merge, summarize and draw.

        Raises :class:`RunInterrupted` on Ctrl-C (the manifest says ``interrupted``),
        :class:`~trackfuse.results.RunFolderError` if the folder cannot be used (another
        process holds it, a file of it is not a file...).
        """
        t0 = time.perf_counter()
        self._check_output_root()
        self._check_picklable()
        with RunLock(self.folder.path, self.warn), watch_sigint():
            outcome = self._run_locked()
        outcome.seconds = time.perf_counter() - t0
        return outcome

    def _check_picklable(self) -> None:
        """Refuse, before anything is written, an experiment the process pool cannot send
        to its workers (it failed at the first batch with a PicklingError traceback)."""
        pooled = self.executor_kind == "process" and self.workers > 1 and not self._on_dask
        if pooled and (why := unpicklable(self.config.experiment)):
            raise ExecutorError(f"{self.config.source}: experiment {self.config.experiment.name}:"
                                f" {why}")

    def _run_locked(self) -> RunOutcome:
        self.folder.check_layout()
        if self.force and (removed := self.folder.clear()):
            self.warn(f"{self.folder.path}: --force removed {removed_words(removed)}")
        previous = self._previous_manifest()
        if previous is None:
            self._note_other_code()
        elif previous.get("status") != RunStatus.COMPLETE and not self._on_dask:
            self._note_other_cpu(previous)  # on dask: once the workers' CPUs are known
        if previous is not None and previous.get("status") == RunStatus.COMPLETE:
            problem = self.folder.check_final_files(previous)
            if problem is None:
                self.folder.remove_temporaries()
                self.folder.drop_resume_state()
                if self.name is not None and self.name != previous.get("name"):
                    previous = {**previous, "name": self.name}
                    self.folder.write_manifest(previous)
                return self._already_complete(previous)
            self.warn(f"{problem}; rebuilding the final files (from parts/ where they are "
                      "still there, else by recomputing)")
        session = _Session(previous, _now(), self.folder.prepare(self.resolved),
                           _per_point(previous), done=self._saved_before(previous))
        try:
            for _ in range(MAX_REPAIRS):
                self._compute_missing(session)
                try:
                    return self._finish(session)
                except PartDamaged as err:
                    self.warn(f"{self.folder.path}/{err}; recomputing its batch")
                    self.folder.drop_part(err.span)
            raise RunFolderError(f"{self.folder.parts}: parts fail verification right after "
                                 "being written: the experiment's rows do not make valid "
                                 "CSV (a bug in its run_trial or run_batch, the warnings "
                                 "above say what), or the disk is failing")
        except KeyboardInterrupt:
            self.folder.write_manifest(self._manifest(RunStatus.INTERRUPTED, session))
            raise RunInterrupted(self.folder.path, session.done, self.total_trials) from None
        except OSError:  # a full or failing disk: the saved batches stay resumable
            with contextlib.suppress(OSError):
                self.folder.write_manifest(self._manifest(RunStatus.INTERRUPTED, session))
            raise

    def _saved_before(self, previous: dict[str, Any] | None) -> int:
        """The trials an earlier session recorded as saved: what an interrupt says before
        the parts are verified (never 0 for a run whose parts are all there)."""
        return min(max(int_or((previous or {}).get("trials_done"), 0), 0), self.total_trials)

    def _already_complete(self, previous: dict[str, Any]) -> RunOutcome:
        """The outcome of a run found complete; its report drawn if it has none (it finished
        with --no-plots, or its report files were removed)."""
        recorded = (previous.get("sequential") or {}).get("trials")
        if self.config.sequential is not None and isinstance(recorded, list):
            self.sequential = SequentialCounts.recorded(self.config.sequential,
                                                        self.config.batch_size, recorded)
        failed = int_or(previous.get("trials_failed"), 0)
        outcome = RunOutcome(self.folder.path, RunStatus.ALREADY_COMPLETE, self.total_trials,
                             0, failed, rows=int_or(previous.get("rows"), 0))
        if failed:
            outcome.first_failure = first_failure(trials_file(self.folder.path),
                                                  list(self.config.sweep))
        if has_report(self.folder.path, previous):
            outcome.report = self.folder.path / INDEX_HTML
        elif self.plots:
            drawn = self._draw_report(load(self.folder.path), outcome)
            self.folder.write_manifest({**previous, **drawn})
        return outcome

    def _draw_report(self, run: RunData, outcome: RunOutcome) -> dict[str, Any]:
        """Write the run's report into ``outcome``; return what the manifest records of it
        (a run no report can be drawn from: that reason, as a figure error)."""
        self.on_phase("drawing figures and tables")
        try:
            report = write_report(run)
        except NothingToDraw as err:
            outcome.figure_errors = [str(err)]
            return {"figure_errors": outcome.figure_errors}
        if report.removed:
            self.warn(f"{run.path}: removed {removed_words(report.removed, run.path)}")
        outcome.figures, outcome.figure_errors = report.figures, report.errors
        outcome.not_drawn = report.not_drawn
        outcome.report = report.index
        return report.manifest_entries(run.path)

    def _note_other_code(self) -> None:
        """Say in one line when a run of the same config from other code or other library
        versions exists."""
        mine = config_hash(self.resolved)
        others = [m for m in sibling_manifests(self.folder.path)
                  if m.get("config_sha256") == mine and m.get("run_id") != self.run_id]
        if others:
            latest = max(others, key=lambda m: str(m.get("started")))
            self.warn(f"{self.folder.path.parent / str(latest.get('run_id'))} holds this config "
                      f"from {self._what_differs(latest)} ({len(others)} such run(s)); "
                      f"computing anew in {self.folder.path.name}")

    def _what_differs(self, manifest: dict[str, Any]) -> str:
        """"other code", or the Python and library versions that differ from ``manifest``'s."""
        versions, fingerprint = manifest.get("versions"), manifest.get("code_fingerprint")
        if not isinstance(versions, dict) or not isinstance(fingerprint, dict) or (
                fingerprint.get("sha256") != self.code.digest
                or versions.get("trackfuse") != trackfuse.__version__):
            return "other code"
        changed = [f"{lib} {_said(versions.get(lib))}, now {_said(now)}"
                   for lib, now in self.libraries.items() if versions.get(lib) != now]
        return "other versions (" + "; ".join(changed) + ")" if changed else "other code"

    def _note_other_cpu(self, previous: dict[str, Any]) -> None:
        """Say in one line when a run resumes on a CPU its saved batches were not computed
        on (another model, vector extensions or rounding settings: :func:`cpu`)."""
        before = recorded_cpus(previous.get("cpu"))
        if before and (new := unseen_cpus(self.cpus, before)):
            self.warn(f"{self.folder.path}: resuming on another CPU "
                      f"({'; '.join(map(cpu_words, new))}; "
                      f"the saved batches: {'; '.join(map(cpu_words, before))}); the last "
                      "bits of some results may differ from a run on one machine, and "
                      "amplified ones more (docs/runner.md, run id)")

    def _previous_manifest(self) -> dict[str, Any] | None:
        """The run folder's manifest, if readable. One that still says ``running`` (its lock
        is free, so its process is gone) is said: that session was killed, ran out of
        memory, crashed (in compiled code, or a trial run in its own process with
        ``--executor serial`` that ended it past :mod:`trackfuse.trial_guard`) or stopped on
        an error."""
        try:
            previous = self.folder.read_manifest()
        except RunFolderError as err:
            self.warn(f"{err}; writing a new one")
            return None
        if previous is not None and previous.get("status") == RunStatus.RUNNING:
            self.warn(f"{self.folder.path}: its last session (started "
                      f"{previous.get('started')}) stopped before the run ended without "
                      "recording why (killed, out of memory, a crash or an error); resuming "
                      "from its saved batches")
        return previous

    def _report(self, scan: PartScan) -> None:
        if scan.stray:
            more = f" and {len(scan.stray) - 3} more" if len(scan.stray) > 3 else ""
            self.warn(f"{self.folder.parts}: ignoring files that are not parts of this run: "
                      f"{', '.join(scan.stray[:3])}{more}")
        for message in scan.damaged[:5]:
            self.warn(f"{self.folder.path}/{message}; recomputing its batch")
        if len(scan.damaged) > 5:
            self.warn(f"{self.folder.parts}: {len(scan.damaged) - 5} more damaged parts, "
                      "recomputed too")

    def _compute_missing(self, session: _Session) -> None:
        """Verify the parts on disk, then compute every batch of the plan that has no whole
        part; a sequential run look by look (:mod:`trackfuse.sequential`)."""
        scan = self.folder.scan_parts(self.span)
        self._report(scan)
        finished = set(scan.finished)
        rule = self.config.sequential
        if rule is None:
            self._compute(session, finished)
            return
        self.sequential = SequentialCounts.start(rule, len(self.points),
                                                 self.config.batch_size)
        while not self.sequential.done:
            self._compute(session, finished)
            for point in self.sequential.open_points():
                self.sequential.decide(point, self._widest_half_width(point))

    def _widest_half_width(self, point: int) -> float:
        """The widest half-width of the rule's metric over the cells of ``point``, from the
        saved parts of its planned batches (:func:`trackfuse.sequential.widest_half_width`)."""
        frames = []
        for span in self.spans():
            if span.point == point:
                part = read_part(self.folder.part_path(span, "trials"), span, "trials")
                frames.append(pd.read_csv(io.StringIO(csv_line(part.columns) + part.data),
                                          low_memory=False))
        experiment = self.config.experiment
        summary, _ = summarize(pd.concat(frames, ignore_index=True),
                               ["point", *experiment.row_keys], experiment.binary_metrics,
                               skip=experiment.categorical_metrics,
                               bounds=experiment.metric_bounds, rms=experiment.rms_metrics)
        return widest_half_width(summary, self.config.sequential)

    def _compute(self, session: _Session, finished: set[BatchSpan]) -> None:
        """Compute every batch of the plan not in ``finished``, adding each to it."""
        size = self.config.batch_size
        session.done = sum(span.trials for span in finished  # never the whole plan: lazy
                           if span.batch < math.ceil(self.counts[span.point] / size))
        if session.done == self.total_trials:
            return
        todo = (span for span in self.spans() if span not in finished)
        executor = JobqueueExecutor(self.cluster, self.config.cluster) if self.cluster \
            else make_executor(self.executor_kind, self.workers, self.scheduler,
                               self.scheduler_file, self.config.experiment.preload)
        self.workers, self.executor_used = executor.workers, executor.kind
        if executor.kind == "dask":
            self._check_dask_workers(executor, session)
        self.folder.write_manifest(self._manifest(RunStatus.RUNNING, session))
        last = time.monotonic()
        label = f"{folder_name(self.config_file)} [{self.run_id}]"  # the config, not kind
        loading = self._load_finishing_code(executor.kind)
        stopped = True  # by an interrupt or an error, until the loop ends
        try:
            with RunProgress(self.total_trials, session.done, label, self.progress,
                             loading=executor.loading) as bar:
                for res in executor.imap_unordered(execute_batch, self._tasks(todo)):
                    self.folder.write_part(res.span, res.trials_csv, res.trial_rows,
                                           res.timings_csv, res.timing_rows)
                    finished.add(res.span)
                    point = res.span.point
                    session.per_point[point] = session.per_point.get(point, 0.0) + res.wall_s
                    session.done += res.span.trials
                    session.computed += res.span.trials
                    bar.advance(res.span.trials, res.wall_s)
                    if time.monotonic() - last > MANIFEST_EVERY_S:
                        last = time.monotonic()
                        self.folder.write_manifest(self._manifest(RunStatus.RUNNING, session))
            stopped = False
        finally:
            executor.close(abort=stopped)
            if loading is not None:
                loading.join()

    def _check_dask_workers(self, executor: Any, session: _Session) -> None:
        """Refuse dask workers that would compute with other code or library versions than
        the run id names (each worker imports its own installation), and record the
        workers' CPUs as the run's; workers that join later are not checked."""
        found = executor.worker_environments(partial(worker_environment,
                                                     self.config.experiment))
        for address, environment in sorted(found.items()):
            if why := environment_difference(self.code.digest, self.libraries, environment):
                executor.close(abort=True)
                raise ExecutorError(f"dask worker {address} {why}: install the same trackfuse "
                                    "and libraries on every worker")
        self.cpus = list({repr(e["cpu"]): e["cpu"] for e in found.values()}.values())
        if session.previous:
            self._note_other_cpu(session.previous)

    def _load_finishing_code(self, executor_kind: str) -> threading.Thread | None:
        """While the workers compute, load in this process the libraries the steps after
        them need first (scipy.special for the summary's intervals; matplotlib and the
        warmed-up house style for the report), no experiment code. Not when the batches run
        in this process (serial)."""
        if executor_kind == "serial":
            return None
        drawing = self.plots and bool(self.config.experiment.report)

        def load_ahead() -> None:
            importlib.import_module("scipy.special")
            if drawing:
                load_drawing(figure_formats(self.resolved))

        thread = threading.Thread(target=load_ahead, name="trackfuse-load-finishing-code",
                                  daemon=True)
        thread.start()
        return thread

    def _open_for_report(self, session: _Session) -> RunData:
        """The run folder as the report reads it, its manifest first written anew: a resume
        that computed nothing has not replaced a damaged one yet."""
        self.folder.write_manifest(self._manifest(RunStatus.RUNNING, session))
        return load(self.folder.path, require_complete=False)

    def _finish(self, session: _Session) -> RunOutcome:
        """Merge verified parts into the final CSVs, summarize, write the report
        (:func:`trackfuse.reports.write_report`), mark the run complete."""
        path = self.folder.path
        self.on_phase("merging parts into trials.csv")
        files = {CONFIG: session.config_file,
                 TRIALS: self.folder.merge(self.spans, "trials", TRIALS)}
        if self.config.store == "parquet":
            self.on_phase("writing trials.parquet")
            files[TRIALS_PARQUET] = write_parquet(path / TRIALS, path / TRIALS_PARQUET)
            del files[TRIALS]
        rows = files.get(TRIALS, files.get(TRIALS_PARQUET))["rows"]
        timings = self.folder.merge(self.spans, "timings", TIMINGS)
        if timings["rows"]:
            files[TIMINGS] = timings
        else:
            (path / TIMINGS).unlink()
        keys = ["point", *self.config.sweep, *self.config.experiment.row_keys]
        self.on_phase("summarising into summary.csv")
        run = self._open_for_report(session) if self.plots else None
        # a trials.csv of one summary chunk is read once, for the summary and the report
        source = run.trials if run is not None and rows <= CHUNK_ROWS else trials_file(path)
        experiment = self.config.experiment
        summary, failed_rows = summarize(source, keys, experiment.binary_metrics,
                                         skip=experiment.categorical_metrics,
                                         bounds=experiment.metric_bounds,
                                         rms=experiment.rms_metrics)
        if self.sequential is not None:  # each interval with the rule that stopped it
            summary["stopping"] = summary["point"].map(self.sequential.stopping)
        files[SUMMARY] = _write_record(path / SUMMARY, frame_csv(summary))
        if timings["rows"]:
            timing_summary, _ = summarize(path / TIMINGS, keys, suffix=TIME_SUFFIX,
                                          bounds=NON_NEGATIVE)
            files[TIMING_SUMMARY] = _write_record(path / TIMING_SUMMARY,
                                                  frame_csv(timing_summary))
        else:
            (path / TIMING_SUMMARY).unlink(missing_ok=True)
        outcome = RunOutcome(path, RunStatus.COMPLETE, self.total_trials, session.computed,
                             failed_rows, rows=rows)
        if failed_rows:
            outcome.first_failure = first_failure(source, list(self.config.sweep))
        drawn: dict[str, Any] = {"figure_errors": []}
        if run is not None:  # before "complete": a Ctrl-C while drawing leaves a resumable run
            drawn = self._draw_report(run, outcome)
        session.done = self.total_trials
        manifest = self._manifest(RunStatus.COMPLETE, session, failed_rows)
        manifest["rows"] = outcome.rows
        manifest.update(drawn)
        manifest["files"] = files
        self.folder.write_manifest(manifest)
        self.folder.drop_resume_state()
        return outcome


def _write_record(path: Path, text: str) -> dict[str, Any]:
    """Write ``text`` atomically; return its size and checksum for the manifest."""
    atomic_write(path, text)
    return {"bytes": path.stat().st_size, "sha256": sha256_file(path)}


def _per_point(previous: dict[str, Any] | None) -> dict[int, float]:
    """Wall time per point from an earlier session's manifest (ignoring anything malformed)."""
    recorded = (previous or {}).get("per_point_wall_s")
    if not isinstance(recorded, dict):
        return {}
    return {int(k): float(v) for k, v in recorded.items()
            if str(k).isdigit() and isinstance(v, (int, float)) and math.isfinite(v)}


__all__ = ["RunInterrupted", "RunOutcome", "Runner"]

"""Run a validated config: take the run folder, resume or start, execute, finish.

A run has three steps. The plan (:class:`trackfuse.plan.RunPlan`) follows from the config
alone: run id, sweep points, batches, the task of each. The execution sends the batches the
folder lacks to an :class:`~trackfuse.executors.Executor` (serial, process pool, dask or a
batch system's jobs) and stores each result as a verified part as it arrives, in whatever
order; the numbers depend on neither. The finish merges the parts into the final files and
summarises them (:mod:`trackfuse.finish`), draws the report, and writes the manifest
(:mod:`trackfuse.manifest`) that marks the run complete.

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
from pathlib import Path
from typing import Any

import pandas as pd

import trackfuse
from trackfuse.batch import BatchResult, watch_sigint
from trackfuse.config import Config
from trackfuse.environment import (
    cpu,
    cpu_words,
    library_versions,
    recorded_cpus,
    unseen_cpus,
    version,
)
from trackfuse.execution import Placement, check_dask_workers, stored_batches
from trackfuse.executors import DaskExecutor, Executor, ExecutorError, unpicklable
from trackfuse.experiments import plugin_folder
from trackfuse.failures import first_failure
from trackfuse.fingerprint import code_fingerprint
from trackfuse.finish import merge, summarise
from trackfuse.manifest import Manifest, read_manifest, sibling_manifests, write_manifest
from trackfuse.plan import RunPlan
from trackfuse.progress import RunProgress
from trackfuse.reports import NothingToDraw, figure_formats, load_drawing, write_report
from trackfuse.results import (
    CONFIG,
    INDEX_HTML,
    BatchSpan,
    PartDamaged,
    PartScan,
    RunFolder,
    RunFolderError,
    RunStatus,
    config_hash,
    csv_line,
    read_part,
    removed_words,
)
from trackfuse.rundata import RunData, load
from trackfuse.runlock import RunLock, busy_problem, creation_problem
from trackfuse.runstate import has_report
from trackfuse.sequential import SequentialCounts, widest_half_width
from trackfuse.store import trials_file
from trackfuse.summary import CHUNK_ROWS, summarize

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
        recorded = read_manifest(path.parent)
    except RunFolderError:  # an unreadable manifest: the file's own name
        return source
    return recorded.config_file if recorded is not None and recorded.config_file else source


def folder_name(source: str) -> str:
    """The run's folder under the output root: the stem of the config it is made from
    (:func:`config_origin`) without leading dots, so that a config called ``...yaml`` (stem
    ``..``) cannot name the root's parent."""
    return Path(config_origin(source)).stem.lstrip(".") or "config"


@dataclass
class _Session:
    """State of one ``run()`` call, for the manifest."""

    previous: Manifest | None
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
        self.plan = RunPlan.of(config, self.code.digest, self.libraries)
        self.cpus = [cpu()]  # of the machines that compute: this one, or the dask workers
        self.out = Path(out)
        self.config_file = config_origin(config.source)  # before --force empties the folder
        self.folder = RunFolder(self.out / folder_name(self.config_file) / self.run_id)
        #: Where a sequential run stands (``None`` for a fixed count, or before it starts).
        self.sequential: SequentialCounts | None = None
        self.placement = Placement(executor, workers, scheduler, scheduler_file, cluster)
        #: Where the batches ran, once the executor is open (the requested kind until then).
        self.workers, self.executor_used = workers, None
        self.plots, self.progress = plots, progress
        self.command = command if command is not None else sys.argv
        self.warn = warn
        self.force, self.name = force, name
        self.on_phase = on_phase or (lambda phase: None)  # told each step after the trials
        self.git = _git_state(Path.cwd())

    @property
    def run_id(self) -> str:
        return self.plan.run_id

    @property
    def points(self) -> list:
        return self.plan.points

    @property
    def counts(self) -> list[int]:
        """Trials planned per point: the fixed count, or a sequential run's current plan."""
        if self.sequential is not None:
            return self.sequential.counts
        return [self.config.trials] * len(self.points)

    @property
    def total_trials(self) -> int:
        return sum(self.counts)

    def spans(self) -> Iterator[BatchSpan]:
        """Every batch of the run's plan (:attr:`counts`), lazily, in output order."""
        return self.plan.spans(self.counts)

    # -- the manifest ------------------------------------------------------------------------
    def _record(self, status: RunStatus, session: _Session, failed: int = 0) -> Manifest:
        """The manifest of this session so far, with ``status``."""
        versions = {"trackfuse": trackfuse.__version__, **self.libraries,
                    "matplotlib": version("matplotlib")}  # None when not installed
        previous = session.previous or Manifest(status)
        return Manifest(
            status=status, run_id=self.run_id,
            name=self.name if self.name is not None else previous.name,
            experiment=self.config.experiment.name,
            plugin_folder=plugin_folder(self.config.experiment_ref),
            config_file=self.config_file, command=list(self.command), git=self.git,
            config_sha256=config_hash(self.resolved),
            code_fingerprint={"sha256": self.code.digest, "modules": list(self.code.modules)},
            trackfuse_path=str(Path(trackfuse.__file__).resolve().parent),
            versions=versions, platform=platform.platform(),
            cpu=_with_cpus(previous.cpu, self.cpus), host=platform.node(),
            root_seed=self.config.seed,
            executor=self.executor_used or previous.executor or self.placement.kind,
            executor_requested=self.placement.kind,
            cluster={"kind": self.placement.cluster, **dataclasses.asdict(self.config.cluster)}
            if self.placement.cluster else None,
            workers=self.workers, points=len(self.points),
            draw_points=list(self.plan.draw_points), trials_per_point=self.config.trials,
            batch_size=self.config.batch_size, trials_total=self.total_trials,
            trials_done=session.done, trials_failed=failed,
            first_started=previous.first_started or session.started,
            started=session.started,
            finished=_now() if status == RunStatus.COMPLETE else None,
            sessions=(previous.sessions or 0) + 1,
            per_point_wall_s={str(k): round(v, 6) for k, v in sorted(session.per_point.items())},
            report_files=previous.report_files or [],  # until drawn anew: ours to delete
            sequential=self.sequential.manifest_entry() if self.sequential else None)

    def _write_record(self, status: RunStatus, session: _Session) -> None:
        write_manifest(self.folder.path, self._record(status, session))

    def _read_manifest(self) -> Manifest | None:
        """The run folder's manifest; ``None`` for none or one that cannot be used."""
        try:
            return read_manifest(self.folder.path)
        except RunFolderError:
            return None

    # -- before the run ----------------------------------------------------------------------
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
            previous = read_manifest(self.folder.path)
        except RunFolderError:
            return "unreadable manifest; verifies the saved batches, computes the rest"
        if previous is None:
            return "no manifest; verifies the saved batches, computes the rest"
        if previous.status == RunStatus.COMPLETE:
            if problem := self.folder.check_final_files(previous.files):
                return f"complete, but {problem}; rebuilds the final files"
            if self.plots and not has_report(self.folder.path, previous):
                return "complete; nothing to compute, draws the report"
            return "complete; nothing to compute"
        if previous.status == RunStatus.INTERRUPTED:
            return f"interrupted, {previous.trials_done or 0} trials saved; resumes"
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
        if self.placement.pooled and (why := unpicklable(self.config.experiment)):
            raise ExecutorError(f"{self.config.source}: experiment {self.config.experiment.name}:"
                                f" {why}")

    def _run_locked(self) -> RunOutcome:
        self.folder.check_layout()
        if self.force:
            recorded = self._read_manifest()
            if removed := self.folder.clear(recorded.report_files if recorded else None):
                self.warn(f"{self.folder.path}: --force removed {removed_words(removed)}")
        previous = self._previous_manifest()
        if previous is None:
            self._note_other_code()
        elif previous.status != RunStatus.COMPLETE and not self.placement.on_dask:
            self._note_other_cpu(previous)  # on dask: once the workers' CPUs are known
        if previous is not None and previous.status == RunStatus.COMPLETE:
            problem = self.folder.check_final_files(previous.files)
            if problem is None:
                return self._already_complete(previous)
            self.warn(f"{problem}; rebuilding the final files (from parts/ where they are "
                      "still there, else by recomputing)")
        session = _Session(previous, _now(), self.folder.prepare(self.resolved),
                           _per_point(previous), done=self._saved_before(previous))
        try:
            return self._compute_and_finish(session)
        except KeyboardInterrupt:
            self._write_record(RunStatus.INTERRUPTED, session)
            raise RunInterrupted(self.folder.path, session.done, self.total_trials) from None
        except OSError:  # a full or failing disk: the saved batches stay resumable
            with contextlib.suppress(OSError):
                self._write_record(RunStatus.INTERRUPTED, session)
            raise

    def _compute_and_finish(self, session: _Session) -> RunOutcome:
        """Compute what is missing and finish; a part found damaged while merging is
        recomputed (at most :data:`MAX_REPAIRS` times)."""
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

    def _saved_before(self, previous: Manifest | None) -> int:
        """The trials an earlier session recorded as saved: what an interrupt says before
        the parts are verified (never 0 for a run whose parts are all there)."""
        recorded = previous.trials_done if previous is not None else None
        return min(max(recorded or 0, 0), self.total_trials)

    def _already_complete(self, previous: Manifest) -> RunOutcome:
        """The outcome of a run found complete; its report drawn if it has none (it finished
        with --no-plots, or its report files were removed)."""
        self.folder.remove_temporaries()
        self.folder.drop_resume_state()
        if self.name is not None and self.name != previous.name:
            previous = dataclasses.replace(previous, name=self.name)
            write_manifest(self.folder.path, previous)
        recorded = (previous.sequential or {}).get("trials")
        if self.config.sequential is not None and isinstance(recorded, list):
            self.sequential = SequentialCounts.recorded(self.config.sequential,
                                                        self.config.batch_size, recorded)
        failed = previous.trials_failed or 0
        outcome = RunOutcome(self.folder.path, RunStatus.ALREADY_COMPLETE, self.total_trials,
                             0, failed, rows=previous.rows or 0)
        if failed:
            outcome.first_failure = first_failure(trials_file(self.folder.path),
                                                  list(self.config.sweep))
        if has_report(self.folder.path, previous):
            outcome.report = self.folder.path / INDEX_HTML
        elif self.plots:
            drawn = self._draw_report(load(self.folder.path), outcome)
            write_manifest(self.folder.path, dataclasses.replace(previous, **drawn))
        return outcome

    def _note_other_code(self) -> None:
        """Say in one line when a run of the same config from other code or other library
        versions exists."""
        mine = config_hash(self.resolved)
        others = [m for m in sibling_manifests(self.folder.path)
                  if m.config_sha256 == mine and m.run_id != self.run_id]
        if others:
            latest = max(others, key=lambda m: str(m.started))
            self.warn(f"{self.folder.path.parent / str(latest.run_id)} holds this config "
                      f"from {self._what_differs(latest)} ({len(others)} such run(s)); "
                      f"computing anew in {self.folder.path.name}")

    def _what_differs(self, manifest: Manifest) -> str:
        """"other code", or the Python and library versions that differ from ``manifest``'s."""
        versions, fingerprint = manifest.versions, manifest.code_fingerprint
        if versions is None or fingerprint is None or (
                fingerprint.get("sha256") != self.code.digest
                or versions.get("trackfuse") != trackfuse.__version__):
            return "other code"
        changed = [f"{lib} {_said(versions.get(lib))}, now {_said(now)}"
                   for lib, now in self.libraries.items() if versions.get(lib) != now]
        return "other versions (" + "; ".join(changed) + ")" if changed else "other code"

    def _note_other_cpu(self, previous: Manifest) -> None:
        """Say in one line when a run resumes on a CPU its saved batches were not computed
        on (another model, vector extensions or rounding settings: :func:`cpu`)."""
        before = recorded_cpus(previous.cpu)
        if before and (new := unseen_cpus(self.cpus, before)):
            self.warn(f"{self.folder.path}: resuming on another CPU "
                      f"({'; '.join(map(cpu_words, new))}; "
                      f"the saved batches: {'; '.join(map(cpu_words, before))}); the last "
                      "bits of some results may differ from a run on one machine, and "
                      "amplified ones more (docs/runner.md, run id)")

    def _previous_manifest(self) -> Manifest | None:
        """The run folder's manifest, if readable. One that still says ``running`` (its lock
        is free, so its process is gone) is said: that session was killed, ran out of
        memory, crashed (in compiled code, or a trial run in its own process with
        ``--executor serial`` that ended it past :mod:`trackfuse.trial_guard`) or stopped on
        an error."""
        try:
            previous = read_manifest(self.folder.path)
        except RunFolderError as err:
            self.warn(f"{err}; writing a new one")
            return None
        if previous is not None and previous.status == RunStatus.RUNNING:
            self.warn(f"{self.folder.path}: its last session (started "
                      f"{previous.started}) stopped before the run ended without "
                      "recording why (killed, out of memory, a crash or an error); resuming "
                      "from its saved batches")
        return previous

    # -- the execution -----------------------------------------------------------------------
    def _warn_about_parts(self, scan: PartScan) -> None:
        """Say which files of parts/ are not this run's and which parts were damaged."""
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
        scan = self.folder.scan_parts(self.plan.span)
        self._warn_about_parts(scan)
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
        executor = self._open_executor(session)
        label = f"{folder_name(self.config_file)} [{self.run_id}]"  # the config, not kind
        loading = None
        stopped = True  # by an interrupt or an error, until the loop ends
        try:
            self._write_record(RunStatus.RUNNING, session)
            loading = self._load_finishing_code(executor.kind)
            with RunProgress(self.total_trials, session.done, label, self.progress,
                             loading=executor.loading) as bar:
                last = time.monotonic()
                for result in stored_batches(executor, self.plan.tasks(todo), self.folder):
                    self._count(result, session, finished)
                    bar.advance(result.span.trials, result.wall_s)
                    if time.monotonic() - last > MANIFEST_EVERY_S:
                        last = time.monotonic()
                        self._write_record(RunStatus.RUNNING, session)
            stopped = False
        finally:
            executor.close(abort=stopped)
            if loading is not None:
                loading.join()

    def _open_executor(self, session: _Session) -> Executor:
        """The executor :attr:`placement` names; dask workers checked and their CPUs
        recorded as the run's (:func:`~trackfuse.execution.check_dask_workers`)."""
        executor = self.placement.open(self.config.cluster, self.config.experiment.preload)
        self.workers, self.executor_used = executor.workers, executor.kind
        if isinstance(executor, DaskExecutor):
            try:
                self.cpus = check_dask_workers(executor, self.config.experiment,
                                               self.code.digest, self.libraries)
            except BaseException:
                executor.close(abort=True)
                raise
            if session.previous:
                self._note_other_cpu(session.previous)
        return executor

    @staticmethod
    def _count(result: BatchResult, session: _Session, finished: set[BatchSpan]) -> None:
        """Count a finished (and stored) batch."""
        finished.add(result.span)
        point = result.span.point
        session.per_point[point] = session.per_point.get(point, 0.0) + result.wall_s
        session.done += result.span.trials
        session.computed += result.span.trials

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

    # -- the finish: merge -> summary -> report -> manifest -----------------------------------
    def _finish(self, session: _Session) -> RunOutcome:
        """Merge the verified parts into the final files, summarise them, draw the report
        (:func:`trackfuse.reports.write_report`), then mark the run complete."""
        path = self.folder.path
        merged = merge(self.folder, self.spans, session.config_file, self.config.store,
                       self.on_phase)
        self.on_phase("summarising into summary.csv")
        run = self._open_for_report(session) if self.plots else None
        # a trials.csv of one summary chunk is read once, for the summary and the report
        source = run.trials if run is not None and merged.rows <= CHUNK_ROWS \
            else trials_file(path)
        keys = ["point", *self.config.sweep, *self.config.experiment.row_keys]
        summaries, failed_rows = summarise(path, source, keys, self.config.experiment,
                                           self.sequential, merged.timed)
        outcome = RunOutcome(path, RunStatus.COMPLETE, self.total_trials, session.computed,
                             failed_rows, rows=merged.rows)
        if failed_rows:
            outcome.first_failure = first_failure(source, list(self.config.sweep))
        drawn: dict[str, Any] = {"figure_errors": []}
        if run is not None:  # before "complete": a Ctrl-C while drawing leaves a resumable run
            drawn = self._draw_report(run, outcome)
        session.done = self.total_trials
        write_manifest(path, dataclasses.replace(
            self._record(RunStatus.COMPLETE, session, failed_rows), rows=outcome.rows,
            **drawn, files={**merged.files, **summaries}))
        self.folder.drop_resume_state()
        return outcome

    def _open_for_report(self, session: _Session) -> RunData:
        """The run folder as the report reads it, its manifest first written anew: a resume
        that computed nothing has not replaced a damaged one yet."""
        self._write_record(RunStatus.RUNNING, session)
        return load(self.folder.path, require_complete=False)

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


def _per_point(previous: Manifest | None) -> dict[int, float]:
    """Wall time per point from an earlier session's manifest."""
    recorded = previous.per_point_wall_s if previous is not None else None
    return {int(k): float(v) for k, v in (recorded or {}).items()
            if str(k).isdigit() and math.isfinite(v)}


__all__ = ["RunInterrupted", "RunOutcome", "Runner"]

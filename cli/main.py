"""The ``trackfuse`` command line: run, reproduce, plot, runs, compare, validate, list.

Exit status: 0 success; 1 figures or tables could not be drawn (or, for ``compare
--fail-on-regression``, a regression, a cell of BASE missing from NEW, or nothing compared
or gated); 2 bad input (config, override, option, run folder, output root) or a run folder
in use by another process; 3 the run finished but some trials failed; 130 interrupted
(re-run the same command to resume). Every error, usage errors included, is one line on
stderr starting with ``error:``; repairs are announced with one line starting with
``warning:``.

Start-up: the commands import the runner, pandas, scipy and matplotlib only inside the
functions that need them, so ``--help``, ``list`` and ``validate`` stay quick
(``benchmarks/startup.py``).
"""

from __future__ import annotations

import inspect
import json
import os
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

import trackfuse
from trackfuse_cli.options import (
    Cfg,
    ClusterOpt,
    DryRun,
    Executor,
    ExecutorOpt,
    Format,
    NoPlots,
    NoProgress,
    OneLineErrors,
    OutDir,
    Overrides,
    Scheduler,
    SchedulerFile,
    Sets,
    Sweeps,
    Workers,
    fail,
    out_folder,
    print_error,
    printable,
    warn,
    whole_number,
)

if TYPE_CHECKING:
    from rich.text import Text

    from trackfuse.compare import Comparison
    from trackfuse.config import Config
    from trackfuse.rundata import RunData
    from trackfuse.runner import Runner, RunOutcome


app = typer.Typer(cls=OneLineErrors, add_completion=True, pretty_exceptions_enable=False,
                  help="Monte Carlo experiment runner for passive multi-sensor tracking.")


def _show_version(value: bool) -> None:
    if value:
        print(f"trackfuse {trackfuse.__version__}")
        raise typer.Exit()


@app.callback(invoke_without_command=True)
def _main(
    ctx: typer.Context,
    version: Annotated[bool, typer.Option("--version", callback=_show_version, is_eager=True,
                                          metavar="", help="Print the version and exit.")]
    = False,
) -> None:
    """Monte Carlo experiment runner for passive multi-sensor tracking."""
    if ctx.invoked_subcommand is None:
        print(ctx.get_help())
        raise typer.Exit(2)
    # Like `python -m`, find plugin modules (experiment: module:ATTR) in the current folder;
    # appended, so a local file never shadows an installed library.
    if os.getcwd() not in sys.path:
        sys.path.append(os.getcwd())
    ctx.call_on_close(_exit_past_trial_threads)


def _exit_past_trial_threads() -> None:
    """As the command ends, with the status it ends with: exit without waiting for threads
    that trials run in this process (serial) left running (Python's exit waits for them,
    for ever). Called while the command's ``typer.Exit`` is being handled."""
    guard = sys.modules.get("trackfuse.trial_guard")  # imported only if trials ran here
    code = getattr(sys.exc_info()[1], "exit_code", None)
    if guard is None or code is None or not (left := guard.threads_left()):
        return
    names = ", ".join(sorted({t.name for t in left}))
    warn(f"trials left {len(left)} thread(s) running ({names}); exiting without waiting "
         "for them")
    sys.stdout.flush()
    os._exit(code)


def _complete_experiment(incomplete: str) -> list[str]:
    from trackfuse import experiments
    return [n for n in experiments.names() if n.startswith(incomplete)]


# ---------------------------------------------------------------------------- loading


def _overrides(sets: list[str], positional: list[str] | None) -> dict[str, Any]:
    """``--set`` items and positional ``key=value`` items as one mapping (one-line error)."""
    from trackfuse.sweep import SweepError, parse_sets
    try:
        return parse_sets([*(positional or []), *sets])
    except SweepError as err:
        fail(f"--set: {err}")


def _load(cfg: Path, sets: dict[str, Any], sweeps: list[str], **top) -> Config:
    from trackfuse.config import SET, ConfigError, load
    from trackfuse.shipped import config_path
    from trackfuse.sweep import SweepError, parse_sweeps
    try:
        axes = parse_sweeps(sweeps)
    except SweepError as err:
        fail(f"--sweep: {err}")
    for key in axes.keys() & sets.keys():
        fail(f"--sweep {key} and --set {key}: give one (a set fixes the value, a sweep "
             "varies it)")
    given = {k: v for k, v in top.items() if v is not None}
    for key in given.keys() & sets.keys():
        fail(f"--{key.replace('_', '-')} {given[key]} and --set {key}={sets[key]}: give {key} "
             "once")
    overrides = {**sets, **given}
    path = config_path(cfg)
    if not path.exists():
        fail(_no_config(cfg))
    try:
        return load(path, overrides, axes)
    except ConfigError as err:
        if err.source == SET and err.key in given:  # --trials, --seed: not a --set
            fail(f"--{err.key.replace('_', '-')}: {err.message}")
        fail(str(err))


def _no_config(given: Path) -> str:
    """One line for a CONFIG that is neither a file nor a config name, with the closest
    names (``ci/twin_sensor_ci`` for ``twin_sensor_ci``)."""
    from trackfuse.shipped import close_config_names
    close = close_config_names(given)
    names = ", ".join(f"'{n}'" for n in close)
    return (f"{given}: no such file, nor a config of that name in ./configs or the shipped "
            "configs; " + (f"did you mean {names}?" if close else "allowed: a YAML file or a "
                           "config name such as twin_sensor_orbit or ci/twin_sensor_ci"))


@dataclass(frozen=True)
class RunOptions:
    """How ``run`` and ``reproduce`` execute configs (everything but the config)."""

    out: Path
    workers: int = 0
    executor: str = "process"
    scheduler: str | None = None
    scheduler_file: str | None = None
    plots: bool = True
    progress: bool = True
    force: bool = False
    name: str | None = None
    cluster: str | None = None

    def check(self) -> None:
        """Refuse an empty ``--scheduler`` or ``--scheduler-file`` (an unset shell variable:
        it ran here, unsaid) and a scheduler file without an address in one line; warn about
        more local workers than cores."""
        from trackfuse.executors import ExecutorError, default_workers, scheduler_address
        for option, value in (("--scheduler", self.scheduler),
                              ("--scheduler-file", self.scheduler_file)):
            if value is not None and not value.strip():
                fail(f"{option}: got an empty value; allowed: a dask scheduler address such "
                     "as tcp://host:8786, or a scheduler file (leave it out to run here)")
        if self.scheduler_file:
            try:
                scheduler_address(self.scheduler_file)
            except ExecutorError as err:
                fail(str(err))
        cores = default_workers()
        if self.cluster and (self.scheduler or self.scheduler_file):
            fail("--cluster starts its own scheduler; allowed: --cluster, or --scheduler / "
                 "--scheduler-file, not both")
        if self.workers > cores and self.executor != "serial" and not self.scheduler \
                and not self.scheduler_file and not self.cluster:
            warn(f"--workers {self.workers}: more than the {cores} cores this process may use; "
                 "the extra workers share them and only add memory")

    def check_reports(self, configs: list[Config]) -> None:
        """Refuse, before the first trial, a run with a report whose report module is not on
        the Python path (it failed only after the last trial)."""
        from trackfuse.experiments import report_problem
        for config in configs if self.plots else []:
            if problem := report_problem(config.experiment):
                fail(f"{config.source}: {problem}; allowed: run from the folder that holds "
                     "it, add that folder to PYTHONPATH, or --no-plots")

    def start_workers(self, configs: list[Config]) -> None:
        """Start the process pool's fork server now, if the runs will use one: it loads the
        experiments' code while this process builds the runners (runs that turn out to be
        complete already leave it unused)."""
        from trackfuse.executors import default_workers, start_fork_server
        if self.executor == "process" and not (self.scheduler or self.scheduler_file
                                               or self.cluster) and \
                (self.workers or default_workers()) > 1:
            start_fork_server(list(dict.fromkeys(module for config in configs
                                                 for module in config.experiment.preload)))

    def runner(self, config: Config) -> Runner:
        from trackfuse.executors import default_workers
        from trackfuse.progress import PhaseLog
        from trackfuse.runner import Runner, folder_name
        return Runner(config, self.out, workers=self.workers or default_workers(),
                      executor=self.executor, scheduler=self.scheduler,
                      scheduler_file=self.scheduler_file, plots=self.plots,
                      progress=self.progress, command=sys.argv, warn=warn, force=self.force,
                      name=self.name, cluster=self.cluster,
                      on_phase=PhaseLog(folder_name(config.source), self.progress))


def _execute(runner: Runner) -> RunOutcome:
    """``runner.run()`` with every expected failure turned into one line and its exit code."""
    from trackfuse.executors import ExecutorError
    from trackfuse.results import RunFolderError
    from trackfuse.runner import RunInterrupted
    try:
        return runner.run()
    except RunInterrupted as err:
        print(f"interrupted: {err.done}/{err.total} trials saved in {err.folder}; run the same "
              "command again to resume", file=sys.stderr)
        raise typer.Exit(130) from None
    except (ExecutorError, RunFolderError) as err:
        fail(str(err))
    except OSError as err:
        where = f"{err.filename}: " if err.filename else ""
        fail(f"{where}{err.strerror or type(err).__name__} (while writing {runner.folder.path}); "
             "the batches saved so far are kept: fix the disk and run the same command again")


def exit_status(outcomes: list[RunOutcome]) -> int:
    """3 if a trial failed, else 1 if a figure or table could not be drawn, else 0."""
    if any(o.failed_trials for o in outcomes):
        return 3
    return 1 if any(o.figure_errors for o in outcomes) else 0


def _count(n: int, noun: str) -> str:
    """``"1 point"``, ``"2 points"``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _plan_line(runner: Runner) -> str:
    """The ``--dry-run`` line of one run; exit 2 with the run's own error line if its
    folder could not be created."""
    from trackfuse.results import RunFolderError
    config = runner.config
    try:
        start = runner.planned_start()
    except RunFolderError as err:
        fail(str(err))
    return (f"# {config.source}: {_count(len(runner.points), 'point')} x "
            f"{_trials_text(config)} = {'at most ' if config.sequential else ''}"
            f"{_count(len(runner.points) * config.trials, 'trial')} in "
            f"batches of {config.batch_size}; output: {runner.folder.path} ({start})")


def _trials_text(config: Config) -> str:
    """``50 trials``, or ``100 to 20000 trials (sequential: correct +-0.01)``."""
    rule = config.sequential
    if rule is None:
        return _count(config.trials, "trial")
    return f"{rule.min} to {rule.max} trials (sequential: {rule.metric} +-{rule.half_width:g})"


# ---------------------------------------------------------------------------- run


@app.command()
def run(
    cfg: Cfg,
    overrides: Overrides = None,
    trials: Annotated[int | None, typer.Option(metavar="N", parser=whole_number(1),
                                               help="Trials per sweep point.")] = None,
    workers: Workers = 0,
    seed: Annotated[int | None, typer.Option(metavar="N", parser=whole_number(0),
                                             help="Root seed.")] = None,
    out_dir: OutDir = "results",
    sets: Sets = [],  # noqa: B006 - typer reads the default
    sweeps: Sweeps = [],  # noqa: B006
    executor: ExecutorOpt = Executor.process,
    scheduler: Scheduler = None,
    scheduler_file: SchedulerFile = None,
    cluster: ClusterOpt = None,
    dry_run: DryRun = False,
    no_plots: NoPlots = False,
    no_progress: NoProgress = False,
    force: Annotated[bool, typer.Option("--force", metavar="", help="Recompute from scratch "
                                        "into the same folder: deletes the files trackfuse "
                                        "wrote there (named on stderr), never others.")]
    = False,
    name: Annotated[str | None, typer.Option(metavar="TEXT", help="A label for the run, kept "
                                             "in its manifest and shown by `trackfuse runs` "
                                             "(not part of the run id).")] = None,
    trial_timeout: Annotated[float | None, typer.Option(
        metavar="SECONDS", help="Fail a trial that runs longer (default: no limit; config "
        "key trial_timeout).")] = None,
) -> None:
    """Run CONFIG: every sweep point x trial, then trials.csv, summary.csv and the report."""
    config = _load(cfg, _overrides(sets, overrides), sweeps, trials=trials, seed=seed,
                   trial_timeout=trial_timeout)
    if config.source != str(cfg) and not dry_run:  # a name: say which file it found
        print(f"config: {config.source}")
    options = RunOptions(out_folder(out_dir), workers, executor.value, scheduler,
                         scheduler_file, not no_plots, not no_progress, force, name,
                         cluster.value if cluster else None)
    options.check()
    options.check_reports([config])
    if not dry_run:
        options.start_workers([config])
    runner = options.runner(config)
    if dry_run:
        import yaml
        plan = _plan_line(runner)
        print(yaml.safe_dump(config.to_dict(), sort_keys=False), end="")
        print(plan)
        if cluster:
            _print_job_script(cluster.value, config)
        return
    outcome = _execute(runner)
    _closing_lines(outcome, config)
    raise typer.Exit(exit_status([outcome]))


def _print_job_script(kind: str, config: Config) -> None:
    """The job script ``--cluster kind`` would submit (``--dry-run``), as comments."""
    from trackfuse.cluster import job_script
    from trackfuse.executors import ExecutorError
    try:
        script = job_script(kind, config.cluster)
    except ExecutorError as err:
        fail(str(err))
    print(f"# job script (--cluster {kind}; the scheduler's address is filled in at the run):")
    print("".join(f"#   {line}\n" for line in script.strip().splitlines()), end="")


def warn_not_drawn(source: str, wanted: Any, not_drawn: dict[str, str]) -> None:
    """One ``warning:`` line for each figure that ``outputs.figures`` lists by name (not
    ``all``, whose figures this config cannot draw only the report lists) and the report
    could not draw for this run, with the reason (``target.q is not swept``)."""
    if isinstance(wanted, list):
        for name, why in not_drawn.items():
            if name in wanted:
                warn(f"{source}: outputs.figures: {name} not drawn: {why}")


def _closing_lines(outcome: RunOutcome, config: Config) -> None:
    """What ``trackfuse run`` prints at the end of a run."""
    from trackfuse.results import RunStatus
    if outcome.status == RunStatus.ALREADY_COMPLETE:
        print(f"already complete: {outcome.folder}")
    else:
        print(f"wrote {outcome.folder}: {_count(outcome.rows, 'row')}, "
              f"{_count(outcome.total_trials, 'trial')} ({outcome.computed_trials} computed "
              f"now) in {outcome.seconds:.1f} s, {_count(len(outcome.figures), 'figure file')}")
    for message in outcome.figure_errors:
        warn(message)
    warn_not_drawn(config.source, config.figures, outcome.not_drawn)
    if outcome.report is not None:
        print(f"report: {outcome.report}")
    if outcome.failed_trials:
        print_error(failed_trials_line(outcome.failed_trials, outcome.total_trials,
                                       outcome.first_failure))


def failed_trials_line(failed: int, total: int, first: str | None) -> str:
    """``2 of 6 trials failed (status=failed in trials.csv); first: point 0 (...), trial 0:
    ValueError: ...``: what ``run``, ``reproduce`` and ``plot`` say of failed trials."""
    return (f"{failed} of {_count(total, 'trial')} failed (status=failed in trials.csv)"
            + (f"; first: {first}" if first else ""))


# ---------------------------------------------------------------------------- reproduce


def _config_paths(folder: Path | None) -> list[Path]:
    """The ``*.yaml`` configs ``reproduce`` runs (one-line error if there are none): by
    default the first folder a config name is looked up in (``./configs``, else the shipped
    configs: :func:`trackfuse.shipped.config_folders`)."""
    from trackfuse.regular_files import non_regular
    from trackfuse.shipped import config_folders
    if folder is None:
        folders = config_folders()
        if not folders:
            fail("no configs/ folder here and no shipped configs installed; name a folder")
        folder = folders[0]
    if not folder.is_dir():
        fail(f"{folder}: not a folder of configs")
    paths = sorted(folder.glob("*.yaml"))
    if not paths:
        fail(f"{folder}: no *.yaml configs")
    for path in paths:  # found, not named: a FIFO there is no one's pipe (it would hang)
        if kind := non_regular(path):
            fail(f"{path}: {kind}, not a config file; allowed: YAML files in {folder}")
    return paths


def _load_all(paths: list[Path], sets: dict[str, Any]) -> list[Config]:
    """Every config with the overrides that apply to it: top-level keys to all, a parameter
    to the configs whose experiment has it; a key no config accepts is an error."""
    from trackfuse.config import OVERRIDABLE_TOP_LEVEL, ConfigError, load
    from trackfuse.shipped import config_path
    configs, used, problems = [], set(), []
    for path in paths:  # every bad config is named, one line each, before any runs
        try:
            plain = load(config_path(path))
            mine = {k: v for k, v in sets.items()
                    if k in OVERRIDABLE_TOP_LEVEL or k in plain.experiment.schema}
            used |= set(mine)
            configs.append(load(config_path(path), mine) if mine else plain)
        except ConfigError as err:
            problems.append(str(err))
    problems = list(dict.fromkeys(problems))  # a bad --set fails every config alike
    for message in problems[:-1]:
        print_error(message)
    if problems:
        fail(problems[-1])
    unused = sorted(set(sets) - used)
    if unused:
        fail(f"--set: {unused[0]}: no config has this parameter (see `trackfuse list "
             "EXPERIMENT`)")
    return configs


def run_configs(configs: list[Config], options: RunOptions) -> list[RunOutcome]:
    """Run each config in turn (a finished one resumes at once) and return their outcomes,
    printing one line per config."""
    outcomes = []
    options.start_workers(configs)
    for config in configs:
        outcome = _execute(options.runner(config))
        outcomes.append(outcome)
        print(f"{config.source}: {outcome.folder} ({outcome.computed_trials} of "
              f"{outcome.total_trials} trials computed now, {outcome.failed_trials} failed)")
        if outcome.failed_trials:
            print_error(f"{config.source}: " + failed_trials_line(
                outcome.failed_trials, outcome.total_trials, outcome.first_failure))
        for message in outcome.figure_errors:
            warn(message)
        warn_not_drawn(config.source, config.figures, outcome.not_drawn)
        if outcome.report is not None:
            print(f"  report: {outcome.report}")
    return outcomes


@app.command()
def reproduce(
    folder: Annotated[Path | None, typer.Argument(
        metavar="[FOLDER]", show_default=False,
        help="Folder of configs (default: ./configs if present, else the shipped paper "
             "configs).")] = None,
    workers: Workers = 0,
    out_dir: OutDir = "results",
    sets: Sets = [],  # noqa: B006
    executor: ExecutorOpt = Executor.process,
    scheduler: Scheduler = None,
    scheduler_file: SchedulerFile = None,
    cluster: ClusterOpt = None,
    dry_run: DryRun = False,
    no_plots: NoPlots = False,
    no_progress: NoProgress = False,
) -> None:
    """Run every config in FOLDER (by default the shipped paper experiments).

    Finished configs resume at once; all configs are validated before the first one runs.
    A --set parameter applies to every config whose experiment has it."""
    out = out_folder(out_dir)
    configs = _load_all(_config_paths(folder), _overrides(sets, None))
    options = RunOptions(out, workers, executor.value, scheduler, scheduler_file,
                         not no_plots, not no_progress,
                         cluster=cluster.value if cluster else None)
    options.check()
    options.check_reports(configs)
    if dry_run:
        for plan in [_plan_line(options.runner(config)) for config in configs]:
            print(plan)
        return
    outcomes = run_configs(configs, options)
    finished = [o.folder for o in outcomes if o.report is not None]
    if finished:
        from trackfuse.reproduction import write_reproduction_report
        print(f"report: {write_reproduction_report(finished, out)}")
    raise typer.Exit(exit_status(outcomes))


# ---------------------------------------------------------------------------- plot, runs


@app.command()
def plot(run_dir: Annotated[Path, typer.Argument(metavar="RUN_DIR",
                                                 help="A finished run folder.")]) -> None:
    """Redraw every figure and table of RUN_DIR from its CSVs (nothing is recomputed).

    The final files are checked against the checksums in the run's manifest first. Only
    files an earlier draw wrote (the manifest lists them) are replaced or deleted.

    The figures show the successful trials; a run with none (or whose trials.csv lacks a
    column the runner writes) is refused and its earlier report removed. Plotting a run of a
    plugin experiment imports the plugin's module (a config is code)."""
    from trackfuse.failures import first_failure
    from trackfuse.manifest import write_manifest
    from trackfuse.reports import write_report
    from trackfuse.results import CONFIG, RunFolderError, removed_words
    from trackfuse.rundata import swept_keys
    from trackfuse.runlock import RunLock
    run = _load_run(run_dir)
    try:
        with RunLock(run.path, warn):
            report = write_report(run)
            write_manifest(run.path, replace(
                run.manifest, **report.manifest_entries(run.path)))
    except RunFolderError as err:
        fail(str(err))
    except OSError as err:
        fail(f"{err.filename or run_dir}: {err.strerror or type(err).__name__}")
    except KeyboardInterrupt:
        print("interrupted: run `trackfuse plot` again to redraw", file=sys.stderr)
        raise typer.Exit(130) from None
    if report.removed:
        print(f"removed {removed_words(report.removed, run.path)} (an earlier draw's)")
    print(f"drew {_count(len(report.figures), 'figure file')} in {run_dir / 'figures'}")
    failed, total = run.manifest.trials_failed, run.manifest.trials_total
    if failed and total is not None:
        first = first_failure(run.trials, swept_keys(run.config))
        warn(f"{failed_trials_line(failed, total, first)}; the report shows the other "
             f"{total - failed}")
    for message in report.errors:
        warn(message)
    warn_not_drawn(str(run.path / CONFIG), (run.config.get("outputs") or {}).get("figures"),
                   report.not_drawn)
    print(f"report: {report.index}")
    if report.errors:
        raise typer.Exit(1)


def _load_run(path: Path) -> RunData:
    """The complete run folder ``path`` (``plot``, ``compare``), or one line saying why not;
    a folder of runs is listed first."""
    from trackfuse.catalog import find_runs, is_run_folder
    from trackfuse.results import RunFolderError
    from trackfuse.rundata import load
    runs = find_runs(path) if path.is_dir() and not is_run_folder(path) else []
    if runs:
        _print_runs(runs)
        fail(f"{path}: a folder of {_count(len(runs), 'run')}, not a run; name one of them "
             "(listed above)")
    try:
        return load(path)
    except RunFolderError as err:
        fail(str(err))
    except OSError as err:
        fail(f"{err.filename or path}: {err.strerror or type(err).__name__}")


def _cell(value: Any) -> Text:
    """A table cell showing ``value`` as it is: rich markup (``[bold red]``, ``[/]``) is
    not interpreted and escape sequences are written out (:func:`printable`)."""
    from rich.text import Text
    return Text(printable(str(value)))


def _print_runs(runs) -> None:
    """The runs as a table, each with the parameters in which it differs from the others of
    its experiment listed (:func:`trackfuse.catalog.differences`)."""
    from rich.console import Console
    from rich.table import Table

    from trackfuse.catalog import differences
    table = Table("run folder", "experiment", "status", "trials", "started", "wall",
                  "differs in")
    names = [_cell(r.name) for r in runs]  # whole, never wrapped: a name is looked for
    table.add_column("name", min_width=min(max(map(len, names), default=4), 60))
    table.columns.insert(2, table.columns.pop())
    for r, differs in zip(runs, differences(runs), strict=True):
        wall = f"{r.wall_s:.0f} s" if r.wall_s is not None else ""
        table.add_row(*map(_cell, (r.path, r.experiment, r.name, r.status,
                                   f"{r.trials_done}/{r.trials_total}",
                                   r.started.replace("T", " ")[:19], wall,
                                   _differs_text(differs))))
    Console(width=max(Console().width, 160)).print(table)


def _differs_text(differs: dict[str, Any], longest: int = 24) -> str:
    """``clutter.mean=5 seed=2``: one run's differing values, each cut to ``longest``."""
    def short(value: Any) -> str:
        text = value if isinstance(value, str) else json.dumps(value, default=str)
        return text if len(text) <= longest else text[:longest - 1] + "…"

    return " ".join(f"{key}={short(value)}" for key, value in differs.items())


@app.command()
def runs(
    root: Annotated[Path, typer.Argument(metavar="[ROOT]", help="Output root, a config's "
                                         "folder of runs, or a run folder.")] = Path("results"),
    name: Annotated[str | None, typer.Option(
        "--name", metavar="PATTERN", show_default=False,
        help="Only the runs whose name (run --name) matches PATTERN (shell-style: * ?).")]
    = None,
    as_json: Annotated[bool, typer.Option("--json", metavar="", help="Print one JSON list "
                                          "instead of a table.")] = False,
) -> None:
    """List run folders under ROOT, newest first: experiment, name, status, trials, dates,
    and the parameters in which each run differs from the others of its experiment listed.

    In Python, trackfuse.runs(ROOT) returns the same runs as a pandas DataFrame."""
    import fnmatch

    from trackfuse.catalog import differences, find_runs
    if not root.is_dir():
        fail(f"{root}: {'not a folder' if root.exists() else 'no such file or folder'}; "
             "allowed: an output root, a config's folder of runs or a run folder")
    found = [r for r in find_runs(root)
             if name is None or fnmatch.fnmatchcase(r.name, name)]
    if as_json:
        print(json.dumps([{"path": str(r.path), "experiment": r.experiment, "name": r.name,
                           "status": r.status, "seed": r.seed,
                           "trials_per_point": r.trials_per_point,
                           "trials_done": r.trials_done, "trials_total": r.trials_total,
                           "started": r.started, "wall_s": r.wall_s, "differs": differs,
                           "params": r.params}
                          for r, differs in zip(found, differences(found), strict=True)],
                         default=str))
        return
    if not found:
        print(f"no runs under {root}" + (f" named {name!r}" if name is not None else ""))
        return
    _print_runs(found)


# ---------------------------------------------------------------------------- compare


def _tolerances(specs: list[str]) -> dict[str, float]:
    """``--tolerance METRIC=NUMBER`` options as a mapping (one-line error otherwise)."""
    found: dict[str, float] = {}
    for spec in specs:
        metric, _, value = spec.partition("=")
        metric = metric.strip()
        if metric in found:
            fail(f"--tolerance: {metric} given twice ({found[metric]:g} and {value.strip()}); "
                 "allowed: one tolerance per metric")
        try:
            if not metric:
                raise ValueError
            found[metric] = float(value)
        except ValueError:
            fail(f"--tolerance: got {spec!r}; allowed: METRIC=NUMBER (in the metric's unit)")
    return found


def _left_out_line(result: Comparison) -> str:
    """The cells only one run has, counted, with an example of each kind."""
    from trackfuse.compare import cell_name
    parts = []
    for count, frame, run in ((result.only_base, result.only_base_cells, "BASE"),
                              (result.only_new, result.only_new_cells, "NEW")):
        example = f" (e.g. {cell_name(frame.iloc[0], list(frame.columns))})" if count else ""
        parts.append(f"{count} cells only in {run}{example}")
    return f"{', '.join(parts)}: sweep points, row keys or metrics the other run lacks"


def _config_line(differences, shown: int = 6) -> str:
    """``config differs: trials (BASE 50, NEW 100); ...`` or that the configs are equal."""
    if not differences:
        return "config: the same in both runs"

    def short(value: Any) -> str:
        text = value if isinstance(value, str) else json.dumps(value, default=str)
        return text if len(text) <= 40 else text[:39] + "…"

    listed = [f"{key} (BASE {short(b)}, NEW {short(n)})" for key, b, n in differences[:shown]]
    more = f"; +{len(differences) - shown} more (--json lists them)" \
        if len(differences) > shown else ""
    return "config differs: " + "; ".join(listed) + more


def _print_comparison(result: Comparison, shown: int = 30) -> None:
    """The bottom line, the counts, then the cells that differ (most ``shown``), gated
    cells first."""
    import pandas as pd
    from rich.console import Console
    from rich.table import Table
    cells = result.cells
    if cells.empty:  # that is the bottom line
        print(f"nothing compared: the runs share no cell; {_left_out_line(result)}")
        return
    print(result.bottom_line())
    print(f"{'paired' if result.paired else 'unpaired'} comparison of "
          f"{_count(len(cells), 'cell')} {result.pairing}".rstrip())
    print(_config_line(result.config_differences))
    gated = cells["better"].isin(("lower", "higher"))
    for label, part in ((f"gated (the regression gate, family-wise alpha {result.alpha:g})",
                         cells[gated]),
                        ("not gated (no better direction declared; each cell's 95 % interval, "
                         "not adjusted)", cells[~gated])):
        counts = part["verdict"].value_counts().to_dict()
        print(f"{label}: {_count(len(part), 'cell')}"
              + "".join(f", {v} {k}" for k, v in sorted(counts.items())))
    if (cells["verdict"] == "differs").any():
        print(f"'differs' (not gated): about 5 % of the {(~gated).sum()} cells not gated would "
              "differ by chance when nothing has changed")
    if result.only_base or result.only_new:
        print(f"not compared: {_left_out_line(result)}")
    notable = cells[~cells["verdict"].str.startswith("no significant")]
    first = gated[notable.index]
    notable = pd.concat([notable[first], notable[~first]])  # the gate's verdicts first
    if notable.empty:
        return
    hidden = ("n_base", "n_new", "better")
    columns = [c for c in notable.columns if c not in hidden]
    table = Table(*columns)
    for row in notable.head(shown)[columns].itertuples(index=False):
        table.add_row(*(_cell(f"{v:.4g}" if isinstance(v, float) else v) for v in row))
    Console(width=max(Console().width, 160)).print(table)
    if len(notable) > shown:
        print(f"(+{len(notable) - shown} more cells; --json lists every cell)")


def _comparison_data(result: Comparison, failure: str | None) -> dict[str, Any]:
    """What ``compare --json`` prints: the bottom line, the counts and every cell."""
    def records(frame) -> list[dict[str, Any]]:
        return json.loads(frame.to_json(orient="records"))

    return {"bottom_line": result.bottom_line(), "paired": result.paired,
            "pairing": result.pairing,
            "config_differences": [{"key": key, "base": b, "new": n}
                                   for key, b, n in result.config_differences],
            "alpha": result.alpha, "compared": len(result.cells), "gated": result.gated,
            "regressions": len(result.regressions), "only_base": result.only_base,
            "only_new": result.only_new, "gate_failure": failure,
            "cells": records(result.cells), "only_base_cells": records(result.only_base_cells),
            "only_new_cells": records(result.only_new_cells)}


@app.command()
def compare(
    base: Annotated[Path, typer.Argument(metavar="BASE", help="The reference run folder.")],
    new: Annotated[Path, typer.Argument(metavar="NEW", help="The run folder to judge.")],
    fail_on_regression: Annotated[bool, typer.Option(
        "--fail-on-regression", metavar="", help="Exit 1 when a metric is significantly worse "
                                                 "than BASE by more than its tolerance, when a "
                                                 "cell of BASE is missing from NEW, or when "
                                                 "nothing is compared or gated.")]
    = False,
    tolerance: Annotated[list[str], typer.Option(
        metavar="METRIC=NUMBER", show_default=False,
        help="Accepted worsening of a metric, in its unit (repeatable; default 0).")] = [],  # noqa: B006
    alpha: Annotated[float, typer.Option(metavar="P", help="Family-wise false-alarm level of "
                                         "the regression gate.")] = 0.05,
    as_json: Annotated[bool, typer.Option("--json", metavar="", help="Print one JSON object "
                                          "instead of a table.")] = False,
    metric: Annotated[list[str], typer.Option(
        metavar="METRIC", show_default=False,
        help="Compare only this metric (repeatable; default every metric).")] = [],  # noqa: B006
    algorithm: Annotated[list[str], typer.Option(
        metavar="ALGORITHM", show_default=False,
        help="Compare only this algorithm's rows (repeatable; default all).")] = [],  # noqa: B006
) -> None:
    """Compare two complete runs of one experiment, cell by cell.

    A cell is a sweep point x row key x metric: both means, the difference NEW - BASE with
    its 95 % interval. Runs with the same seed are paired on the trials both have (paired t,
    Newcombe and McNemar for 0/1 metrics); otherwise unpaired (Welch, Newcombe hybrid
    score). The config values that differ between the runs are listed.

    A one-line bottom line comes first, the gated cells (metrics with a better direction)
    before the others; --metric and --algorithm narrow the comparison (and the gate's
    family) to those cells.

    Exit 0; 1 with --fail-on-regression on a regression, a cell of BASE missing from NEW,
    nothing compared or nothing gated (the reason in one line on stderr; cells only NEW has
    do not fail); 2 for bad input."""
    from trackfuse.compare import compare_runs
    if not 0 < alpha < 1:
        fail(f"--alpha: got {alpha}; allowed: a number in (0, 1)")
    tolerances = _tolerances(tolerance)
    runs = _load_run(base), _load_run(new)
    try:
        result = compare_runs(*runs, tolerances, alpha=alpha, metrics=metric or None,
                              algorithms=algorithm or None)
    except ValueError as err:
        fail(str(err))
    failure = result.gate_failure()
    if as_json:
        print(json.dumps(_comparison_data(result, failure)))
    else:
        _print_comparison(result)
    if fail_on_regression and failure:
        fail(failure, 1)


# ---------------------------------------------------------------------------- validate, list


@app.command()
def validate(
    cfg: Cfg,
    overrides: Overrides = None,
    sets: Sets = [],  # noqa: B006
    sweeps: Sweeps = [],  # noqa: B006
) -> None:
    """Check CONFIG and its overrides without running anything.

    Every key, value, sweep axis and figure name is checked. A config naming a plugin
    (package.module:ATTR) imports that module: a config is trusted like a script."""
    from trackfuse.experiments import report_problem
    from trackfuse.sweep import count_points
    config = _load(cfg, _overrides(sets, overrides), sweeps)
    if problem := report_problem(config.experiment):
        warn(f"{config.source}: {problem}: `run` refuses it unless --no-plots")
    points = count_points(config.sweep, config.sweep_mode)
    print(f"ok: {config.source}: {config.experiment.name}, {_count(points, 'point')} x "
          f"{_trials_text(config)}")


@app.command("list")
def list_experiments(
    name: Annotated[str | None, typer.Argument(
        metavar="[EXPERIMENT]", autocompletion=_complete_experiment, show_default=False,
        help="Show this experiment's parameters, metrics, algorithms and figures.")] = None,
    output: Annotated[Format, typer.Option(
        "--format", help="table; yaml (with EXPERIMENT): a commented config template that "
                         "`trackfuse validate` accepts as is; json: the same as the table, "
                         "machine-readable (with EXPERIMENT: every parameter, metric, "
                         "algorithm and figure).")]
    = Format.table,
) -> None:
    """List experiments, or one experiment's parameters, metrics, algorithms, figures.

    Without EXPERIMENT: the built-in experiments and installed plugins. With it: every
    parameter with its default, unit and allowed values, the metrics, algorithms and figure
    names (what outputs.figures may list)."""
    from trackfuse import experiments
    from trackfuse.config import unknown_experiment
    from trackfuse_cli import describe
    if name is None:
        if output is Format.yaml:
            fail("--format yaml: a config template is of one experiment; allowed without "
                 "EXPERIMENT: table, json (or name it: trackfuse list EXPERIMENT --format yaml)")
        if output is Format.json:
            print(json.dumps(describe.listing_data(experiments.listing()), indent=1))
        else:
            describe.print_listing(experiments.listing())
        return
    try:
        exp = experiments.get(name)
    except experiments.UnknownExperiment:
        fail(unknown_experiment(name))
    except experiments.PluginError as err:
        fail(str(err))
    if output is Format.yaml:
        print(describe.config_template(exp, name), end="")
    elif output is Format.json:
        print(json.dumps(describe.as_data(exp, name), indent=1))
    else:
        describe.print_experiment(exp)


def _reflowed(doc: str) -> str:
    """``doc`` with each paragraph on one line: typer keeps the line breaks of every paragraph
    after the first, which then break mid-sentence where the terminal wraps them again."""
    return "\n\n".join(" ".join(p.split()) for p in inspect.cleandoc(doc).split("\n\n"))


for _command in app.registered_commands:
    _command.help = _reflowed(_command.help or inspect.getdoc(_command.callback) or "")


if __name__ == "__main__":
    app()

"""The ``trackfuse`` command line: run, reproduce, plot, validate, list.

Exit status: 0 success; 1 figures or tables could not be drawn; 2 bad input (config,
override, option, run folder, output root) or a run folder in use by another process; 3 the
run finished but some trials failed; 130 interrupted (re-run the same command to resume).
Every error is one line on stderr starting with ``error:``; repairs are announced with one
line starting with ``warning:``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
import yaml
from rich.console import Console
from rich.table import Table

from trackfuse import experiments
from trackfuse.catalog import RunInfo, find_runs, is_run_folder
from trackfuse.compare import Comparison, compare_runs
from trackfuse.config import ConfigError, allowed_text, load
from trackfuse.executors import KINDS, ExecutorError, default_workers, scheduler_address
from trackfuse.reports import write_report
from trackfuse.reproduction import write_reproduction_report
from trackfuse.results import RunFolderError, RunStatus
from trackfuse.rundata import load as load_run
from trackfuse.runlock import RunLock
from trackfuse.runner import RunInterrupted, Runner
from trackfuse.shipped import config_path, configs_folder
from trackfuse.sweep import SweepError, count_points, parse_sets, parse_sweeps

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Monte Carlo experiment runner for passive multi-sensor tracking.")
out = Console()


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error to stderr and exit."""
    safe = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
    print(f"error: {safe}", file=sys.stderr)
    raise typer.Exit(code)


def warn(message: str) -> None:
    """Print a one-line warning to stderr."""
    safe = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
    print(f"warning: {safe}", file=sys.stderr, flush=True)


def _interrupted(err) -> None:
    print(f"interrupted: {err.done}/{err.total} trials saved in {err.folder}; run the same "
          "command again to resume", file=sys.stderr)
    raise typer.Exit(130)


def _execute(runner):
    """``runner.run()`` with every expected failure turned into one line and its exit code."""
    try:
        return runner.run()
    except RunInterrupted as err:
        _interrupted(err)
    except (ExecutorError, RunFolderError) as err:
        fail(str(err))
    except OSError as err:
        where = f"{err.filename}: " if err.filename else ""
        fail(f"{where}{err.strerror or type(err).__name__} (while writing {runner.folder.path})")


def _load(cfg: Path, sets: list[str], sweeps: list[str], **top):
    cfg = config_path(cfg)
    try:
        overrides = parse_sets(sets)
        overrides.update({k: v for k, v in top.items() if v is not None})
        return load(cfg, overrides, parse_sweeps(sweeps))
    except SweepError as err:
        fail(f"{cfg}: override: {err}")
    except ConfigError as err:
        fail(str(err))


Sets = Annotated[list[str], typer.Option("--set", help="Override a value: key=value "
                                                        "(repeatable).")]
Sweeps = Annotated[list[str], typer.Option("--sweep", help="Sweep an axis: key=v1,v2 or "
                                                           "key=range(a,b,s) (repeatable).")]


@app.command()
def run(
    cfg: Annotated[Path, typer.Argument(help="Scenario config (YAML).")],
    trials: Annotated[int | None, typer.Option(help="Trials per sweep point.")] = None,
    workers: Annotated[int, typer.Option(help="Parallel workers (default: all cores).")] = 0,
    seed: Annotated[int | None, typer.Option(help="Root seed.")] = None,
    out_dir: Annotated[Path, typer.Option("--out", help="Output root folder.")] = Path("results"),
    sets: Sets = [],  # noqa: B006 - typer reads the default
    sweeps: Sweeps = [],  # noqa: B006
    executor: Annotated[str, typer.Option(help="serial, process or dask.")] = "process",
    scheduler: Annotated[str | None, typer.Option(help="dask scheduler address, "
                                                       "e.g. tcp://host:8786.")] = None,
    scheduler_file: Annotated[str | None, typer.Option(help="dask scheduler file.")] = None,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Print the resolved config and "
                                                            "the work, run nothing.")] = False,
    no_plots: Annotated[bool, typer.Option("--no-plots", help="Skip figures.")] = False,
    no_progress: Annotated[bool, typer.Option("--no-progress", help="No progress output.")]
    = False,
    force: Annotated[bool, typer.Option("--force", help="Recompute from scratch into the "
                                                        "same folder (drops its old results).")]
    = False,
    name: Annotated[str | None, typer.Option(help="A label for the run, kept in its manifest "
                                                  "and shown by `trackfuse runs` (not part "
                                                  "of the run id).")] = None,
) -> None:
    """Run CFG: every sweep point x trial, then trials.csv, summary.csv and the report."""
    config = _load(cfg, sets, sweeps, trials=trials, seed=seed)
    _check_execution(executor, workers, scheduler_file)
    runner = Runner(config, out_dir, workers=workers or default_workers(), executor=executor,
                    scheduler=scheduler, scheduler_file=scheduler_file, plots=not no_plots,
                    progress=not no_progress, command=sys.argv, warn=warn, force=force,
                    name=name)
    if dry_run:
        print(yaml.safe_dump(config.to_dict(), sort_keys=False), end="")
        print(f"# {len(runner.points)} points x {config.trials} trials = "
              f"{runner.total_trials} trials in batches of {config.batch_size}; "
              f"output: {runner.folder.path}")
        return
    _closing_lines(_execute(runner))


def _check_execution(executor: str, workers: int, scheduler_file: str | None) -> None:
    """Refuse a bad ``--executor``, ``--workers`` or ``--scheduler-file`` in one line."""
    if executor not in KINDS:
        fail(f"--executor: got {executor!r}; allowed: {', '.join(KINDS)}")
    if workers < 0:
        fail(f"--workers: got {workers}; allowed: an integer >= 0 (0 = all cores)")
    if scheduler_file:
        try:
            scheduler_address(scheduler_file)
        except ExecutorError as err:
            fail(str(err))


def _closing_lines(outcome) -> None:
    """What ``trackfuse run`` prints at the end, and its exit status (see the module doc)."""
    if outcome.status == RunStatus.ALREADY_COMPLETE:
        print(f"already complete: {outcome.folder}")
    else:
        print(f"wrote {outcome.folder}: {outcome.rows} rows, {outcome.total_trials} trials "
              f"({outcome.computed_trials} computed now) in {outcome.seconds:.1f} s, "
              f"{len(outcome.figures)} figure files")
    for message in outcome.figure_errors:
        print(f"warning: {message}", file=sys.stderr)
    if outcome.report is not None:
        print(f"report: {outcome.report}")
    if outcome.failed_trials:
        print(f"error: {outcome.failed_trials} trials failed (status=failed in trials.csv)",
              file=sys.stderr)
        raise typer.Exit(3)
    if outcome.figure_errors:
        raise typer.Exit(1)


@app.command()
def reproduce(
    folder: Annotated[Path | None, typer.Argument(
        help="Folder of configs (default: ./configs if present, else the shipped paper "
             "configs).")] = None,
    workers: Annotated[int, typer.Option(help="Parallel workers (default: all cores).")] = 0,
    out_dir: Annotated[Path, typer.Option("--out", help="Output root folder.")] = Path("results"),
    executor: Annotated[str, typer.Option(help="serial, process or dask.")] = "process",
    no_progress: Annotated[bool, typer.Option("--no-progress", help="No progress output.")]
    = False,
) -> None:
    """Run every config in FOLDER (the shipped paper experiments by default), resuming any
    finished ones; all configs are validated before the first one runs."""
    if folder is None:
        folder = Path("configs") if Path("configs").is_dir() else configs_folder()
        if folder is None:
            fail("no configs/ folder here and no shipped configs installed; name a folder")
    if not folder.is_dir():
        fail(f"{folder}: not a folder of configs")
    paths = sorted(folder.glob("*.yaml"))
    if not paths:
        fail(f"{folder}: no *.yaml configs")
    configs = [_load(path, [], []) for path in paths]
    failed = 0
    finished = []
    for config in configs:
        runner = Runner(config, out_dir, workers=workers or default_workers(),
                        executor=executor, progress=not no_progress, command=sys.argv,
                        warn=warn)
        outcome = _execute(runner)
        failed += outcome.failed_trials + len(outcome.figure_errors)
        print(f"{config.source}: {outcome.folder} ({outcome.computed_trials} of "
              f"{outcome.total_trials} trials computed now, {outcome.failed_trials} failed)")
        if outcome.report is not None:
            print(f"  report: {outcome.report}")
            finished.append(outcome.folder)
    if finished:
        print(f"report: {write_reproduction_report(finished, out_dir)}")
    if failed:
        raise typer.Exit(3)


@app.command()
def plot(run_dir: Annotated[Path, typer.Argument(help="A finished run folder.")]) -> None:
    """Redraw every figure and table of RUN_DIR from its CSVs (nothing is recomputed).

    The final files are checked against the checksums in the run's manifest first. Plotting
    a run of a plugin experiment imports the plugin's module (a config is code)."""
    runs = find_runs(run_dir) if run_dir.is_dir() and not is_run_folder(run_dir) else []
    if runs:
        print(f"{run_dir} is a folder of runs; plot one of them:")
        _print_runs(runs)
        return
    try:
        run = load_run(run_dir)
        with RunLock(run.path, warn):
            report = write_report(run)
    except RunFolderError as err:
        fail(str(err))
    except OSError as err:
        fail(f"{err.filename or run_dir}: {err.strerror or type(err).__name__}")
    except KeyboardInterrupt:
        print("interrupted: run `trackfuse plot` again to redraw", file=sys.stderr)
        raise typer.Exit(130) from None
    print(f"drew {len(report.figures)} figure files in {run_dir / 'figures'}")
    for message in report.errors:
        print(f"warning: {message}", file=sys.stderr)
    print(f"report: {report.index}")
    if report.errors:
        raise typer.Exit(1)


def _print_runs(runs: list[RunInfo]) -> None:
    table = Table("run folder", "experiment", "name", "status", "trials", "started", "wall")
    for r in runs:
        wall = f"{r.wall_s:.0f} s" if r.wall_s is not None else ""
        table.add_row(str(r.path), r.experiment, r.name, r.status,
                      f"{r.trials_done}/{r.trials_total}", r.started.replace("T", " ")[:19],
                      wall)
    Console(width=max(out.width, 160)).print(table)


@app.command()
def runs(
    root: Annotated[Path, typer.Argument(help="Output root, a config's folder of runs, or a "
                                              "run folder.")] = Path("results"),
) -> None:
    """List run folders under ROOT, newest first: experiment, name, status, trials, dates."""
    if not root.is_dir():
        fail(f"{root}: not a folder")
    found = find_runs(root)
    if not found:
        print(f"no runs under {root}")
        return
    _print_runs(found)


def _tolerances(specs: list[str]) -> dict[str, float]:
    """``--tolerance METRIC=NUMBER`` options as a mapping (one-line error otherwise)."""
    found = {}
    for spec in specs:
        metric, _, value = spec.partition("=")
        try:
            if not metric.strip():
                raise ValueError
            found[metric.strip()] = float(value)
        except ValueError:
            fail(f"--tolerance: got {spec!r}; allowed: METRIC=NUMBER (in the metric's unit)")
    return found


def _print_comparison(result: Comparison, shown: int = 30) -> None:
    """One summary line, then the cells that differ (most ``shown``)."""
    cells = result.cells
    counts = cells["verdict"].value_counts().to_dict()
    print(f"{'paired' if result.paired else 'unpaired'} comparison, {len(cells)} cells, "
          f"{result.gated} gated (family-wise alpha {result.alpha:g}): "
          + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())))
    notable = cells[~cells["verdict"].str.startswith("no significant")]
    if notable.empty:
        return
    hidden = ("n_base", "n_new", "better")
    columns = [c for c in notable.columns if c not in hidden]
    table = Table(*columns)
    for row in notable.head(shown)[columns].itertuples(index=False):
        table.add_row(*(f"{v:.4g}" if isinstance(v, float) else str(v) for v in row))
    Console(width=max(out.width, 160)).print(table)
    if len(notable) > shown:
        print(f"(+{len(notable) - shown} more cells; --json lists every cell)")


@app.command()
def compare(
    base: Annotated[Path, typer.Argument(help="The reference run folder.")],
    new: Annotated[Path, typer.Argument(help="The run folder to judge.")],
    fail_on_regression: Annotated[bool, typer.Option(
        "--fail-on-regression", help="Exit 1 when a metric is significantly worse than BASE "
                                     "by more than its tolerance.")] = False,
    tolerance: Annotated[list[str], typer.Option(
        help="Accepted worsening of a metric: METRIC=NUMBER (repeatable; default 0).")] = [],  # noqa: B006
    alpha: Annotated[float, typer.Option(help="Family-wise false-alarm level of the "
                                              "regression gate.")] = 0.05,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object instead of "
                                                         "a table.")] = False,
) -> None:
    """Compare two complete runs of one experiment cell by cell (sweep point x row key x
    metric): both means, the difference NEW - BASE with its 95 % interval. Runs with the same
    seed and trial count are paired (paired t, Newcombe and McNemar for 0/1 metrics);
    otherwise unpaired (Welch, Newcombe hybrid score). Exit 0, 1 (regression, with
    --fail-on-regression) or 2 (bad input)."""
    if not 0 < alpha < 1:
        fail(f"--alpha: got {alpha}; allowed: a number in (0, 1)")
    tolerances = _tolerances(tolerance)
    try:
        result = compare_runs(load_run(base), load_run(new), tolerances, alpha=alpha)
    except (RunFolderError, ValueError) as err:
        fail(str(err))
    if as_json:
        print(json.dumps({"paired": result.paired, "alpha": result.alpha,
                          "gated": result.gated, "regressions": len(result.regressions),
                          "cells": json.loads(result.cells.to_json(orient="records"))}))
    else:
        _print_comparison(result)
    if fail_on_regression and len(result.regressions):
        if not as_json:
            print(f"error: {len(result.regressions)} regressions", file=sys.stderr)
        raise typer.Exit(1)


@app.command()
def validate(
    cfg: Annotated[Path, typer.Argument(help="Scenario config (YAML).")],
    sets: Sets = [],  # noqa: B006
    sweeps: Sweeps = [],  # noqa: B006
) -> None:
    """Check CFG (and overrides) without running anything. A config naming a plugin
    (package.module:ATTR) imports that module: a config is trusted like a script."""
    config = _load(cfg, sets, sweeps)
    points = count_points(config.sweep, config.sweep_mode)
    print(f"ok: {cfg}: {config.experiment.name}, {points} points x {config.trials} trials")


@app.command("list")
def list_experiments(
    name: Annotated[str | None, typer.Argument(help="Show this experiment's parameters.")]
    = None,
) -> None:
    """List experiments, or one experiment's parameters with defaults and units."""
    if name is None:
        table = Table("experiment", "title", "parameters")
        for exp_name in experiments.names():
            try:
                exp = experiments.get(exp_name)
                table.add_row(exp_name, exp.title, str(len(exp.params)))
            except Exception as err:  # noqa: BLE001 - one broken experiment, listed as such
                table.add_row(exp_name, f"(unavailable: {type(err).__name__}: {err})", "")
        out.print(table)
        return
    try:
        exp = experiments.get(name)
    except experiments.UnknownExperiment:
        fail(f"unknown experiment {name[:80]!r}; allowed: {', '.join(experiments.names())}")
    except experiments.PluginError as err:
        fail(str(err))
    table = Table("parameter", "default", "unit", "allowed", "meaning", title=exp.title)
    for p in exp.params:
        table.add_row(p.key, str(p.default), p.unit, allowed_text(p), p.doc)
    out.print(table)
    figures = Table("figure", "paper", "caption", title="figures (outputs.figures)")
    for fig_name, spec in exp.figures.items():
        figures.add_row(fig_name, spec.paper or "-", spec.caption)
    out.print(figures)


if __name__ == "__main__":
    app()

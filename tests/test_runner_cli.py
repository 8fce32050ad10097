"""`trackfuse run` and `reproduce` around the runner: phases after the last trial, exit
status, reproduce's options."""

from __future__ import annotations

import re
from types import SimpleNamespace

import pandas as pd
import pytest
from conftest import trackfuse

from trackfuse_cli.main import exit_status

pytestmark = pytest.mark.slow  # runs through the real command line


def _configs(tmp_path):
    folder = tmp_path / "configs"
    folder.mkdir()
    (folder / "a_gauss.yaml").write_text("experiment: toy_experiments:GAUSSIAN\ntrials: 4\n"
                                         "seed: 1\n")
    (folder / "b_trivial.yaml").write_text("experiment: toy_experiments:TRIVIAL\ntrials: 3\n"
                                           "seed: 2\n")
    return folder


def test_exit_status_prefers_failed_trials_over_figure_errors():
    ok = SimpleNamespace(failed_trials=0, figure_errors=[])
    figure = SimpleNamespace(failed_trials=0, figure_errors=["estimate: boom"])
    failed = SimpleNamespace(failed_trials=2, figure_errors=[])
    assert exit_status([ok]) == 0 and exit_status([ok, figure]) == 1
    assert exit_status([figure, failed]) == 3


def test_run_announces_the_phases_after_the_last_trial(write_config, tmp_path):
    path = write_config("experiment: toy_experiments:GAUSSIAN\ntrials: 5\nseed: 1\n")
    result = trackfuse("run", path, "--out", tmp_path / "out", "--workers", "1")
    assert result.returncode == 0, result.stderr
    phases = [line for line in result.stderr.splitlines() if line.endswith("...")
              or "...(" in line or "... (" in line]
    assert [p.split(": ")[1].split("...")[0] for p in phases] == [
        "merging parts into trials.csv", "summarising into summary.csv",
        "drawing figures and tables"]
    assert "nan" not in result.stderr
    quiet = trackfuse("run", path, "--out", tmp_path / "out2", "--workers", "1",
                      "--no-progress")
    assert quiet.stderr == ""


def test_reproduce_dry_run_and_set_apply_per_experiment(tmp_path):
    folder = _configs(tmp_path)
    result = trackfuse("reproduce", folder, "--dry-run", "--set", "trials=2", "--set",
                       "sigma=3", "--out", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2 and all("1 point x 2 trials" in line for line in lines)
    assert not (tmp_path / "out").exists()
    unknown = trackfuse("reproduce", folder, "--dry-run", "--set", "sigam=1")
    assert unknown.returncode == 2
    assert unknown.stderr.startswith("error: --set: sigam: no config has this parameter")


def test_reproduce_runs_every_config_and_resumes(tmp_path):
    folder = _configs(tmp_path)
    args = ["reproduce", folder, "--out", tmp_path / "out", "--workers", "1", "--no-plots",
            "--no-progress"]
    first = trackfuse(*args)
    assert first.returncode == 0, first.stderr
    assert "(4 of 4 trials computed now, 0 failed)" in first.stdout
    assert "(3 of 3 trials computed now, 0 failed)" in first.stdout
    again = trackfuse(*args)
    assert again.returncode == 0 and again.stdout.count("(0 of ") == 2


FAILING = "experiment: toy_experiments:GAUSSIAN\ntrials: 12\nseed: 11\nparams: {fail_every: 3}\n" \
          "sweep: {mu: [0, 2.5]}\n"


def test_failed_trials_are_reported_with_the_first_ones_point_trial_and_error(write_config,
                                                                              tmp_path):
    """`trackfuse run` said only `error: 4 trials failed (status=failed in trials.csv)`,
    the same again when the run was found complete."""
    path = write_config(FAILING)
    result = trackfuse("run", path, "--out", tmp_path, "--workers", "2", "--no-progress")
    assert result.returncode == 3, result.stderr
    trials = pd.read_csv(next(tmp_path.glob("cfg/*/trials.csv")))
    failed = trials[trials["status"] == "failed"]
    first = failed.iloc[0]
    mu = f"{first['mu']:g}"
    want = (f"error: {len(failed)} of 24 trials failed (status=failed in trials.csv); first: "
            f"point {first['point']} (mu={mu}), trial {first['trial']}: "
            "FloatingPointError: synthetic divergence")
    assert result.stderr.strip() == want
    again = trackfuse("run", path, "--out", tmp_path, "--no-progress")
    assert again.returncode == 3 and again.stderr.strip() == want


def test_plot_of_a_run_with_failed_trials_draws_from_the_others_and_says_so(write_config,
                                                                            tmp_path):
    path = write_config(FAILING)
    assert trackfuse("run", path, "--out", tmp_path, "--no-plots").returncode == 3
    folder = next(tmp_path.glob("cfg/*"))
    failed = int((pd.read_csv(folder / "trials.csv")["status"] == "failed").sum())
    result = trackfuse("plot", folder)
    assert result.returncode == 0, result.stderr
    assert result.stderr.startswith(f"warning: {failed} of 24 trials failed (status=failed in "
                                    "trials.csv); first: point ")
    assert result.stderr.strip().endswith(f"; the report shows the other {24 - failed}")
    assert (folder / "figures" / "estimate.png").exists()
    facts = next(part for part in (folder / "index.md").read_text().split("\n## ")
                 if part.startswith("Run\n"))
    assert f"{failed} failed; first: point " in facts and "synthetic divergence" in facts


def test_a_run_whose_every_trial_failed_has_no_report_and_plot_refuses(write_config,
                                                                      tmp_path):
    """Every trial failed: a report was drawn from no data (empty figures, a matplotlib
    warning on stderr); now no report, the reason given once, and `plot` refuses in one
    line."""
    path = write_config("experiment: toy_experiments:GAUSSIAN\ntrials: 3\nseed: 1\n"
                        "params: {fail_every: 1}\n")
    result = trackfuse("run", path, "--out", tmp_path, "--no-progress")
    assert result.returncode == 3
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 2 and lines[1].startswith("error: 3 of 3 trials failed")
    assert lines[0].startswith("warning: every trial failed (3 of 3; first: point 0, trial 0:")
    folder = next(tmp_path.glob("cfg/*"))
    assert not (folder / "index.html").exists() and not any((folder / "figures").glob("*"))
    plotted = trackfuse("plot", folder)
    assert plotted.returncode == 2 and plotted.stderr.count("\n") == 1
    assert plotted.stderr.startswith("error: every trial failed (3 of 3; first: point 0")


def test_phase_lines_name_the_config_and_a_short_phase_in_tenths(tmp_path):
    """Under `reproduce`, six lines in a row read "toy_gaussian: merging..." whichever
    config they were about, a phase took "0 s", and one figure was "1 figure files"."""
    folder = tmp_path / "configs"
    folder.mkdir()
    for name, seed in (("first", 1), ("second", 2)):
        (folder / f"{name}.yaml").write_text(f"experiment: toy_experiments:GAUSSIAN\n"
                                             f"trials: 3\nseed: {seed}\n"
                                             "outputs: {formats: [png]}\n")
    result = trackfuse("reproduce", folder, "--out", tmp_path / "out", "--workers", "1")
    assert result.returncode == 0, result.stderr
    phases = [line for line in result.stderr.splitlines() if re.search(r"\.\.\.( \(|$)", line)]
    assert [line.split(": ")[0] for line in phases] == ["first"] * 3 + ["second"] * 3
    took = re.findall(r" took (.*)\)$", "\n".join(phases), re.MULTILINE)
    assert len(took) == 4 and all(re.fullmatch(r"\d\.\d s", t) for t in took), took
    single = trackfuse("run", folder / "first.yaml", "--out", tmp_path / "again",
                       "--workers", "1", "--no-progress")
    assert re.search(r", 3 trials \(3 computed now\) in \S+ s, 1 figure file$",
                     single.stdout.splitlines()[0]), single.stdout


PICKY = "experiment: toy_experiments:PICKY\ntrials: 3\nseed: 1\noutputs: {figures: %s}\n"


def test_a_listed_figure_the_run_cannot_draw_is_one_warning_line(write_config, tmp_path):
    """A figure named in outputs.figures that the run could not draw showed only under "Not
    drawn" in index.md; `run` exited 0 without a word."""
    path = write_config(PICKY % "[estimate, estimate_vs_sigma]")
    want = (f"warning: {path}: outputs.figures: estimate_vs_sigma not drawn: sigma is not "
            "swept")
    ran = trackfuse("run", path, "--out", tmp_path / "out", "--no-progress")
    assert ran.returncode == 0, ran.stderr
    assert ran.stderr.splitlines() == [want]
    assert "estimate_vs_sigma" in (next(tmp_path.glob("out/cfg/*")) / "index.md").read_text()
    plotted = trackfuse("plot", next(tmp_path.glob("out/cfg/*")))
    assert plotted.returncode == 0
    assert plotted.stderr.splitlines() == [want.replace(
        str(path), str(next(tmp_path.glob("out/cfg/*")) / "config.yaml"))]
    reproduced = trackfuse("reproduce", tmp_path, "--out", tmp_path / "again",
                           "--no-progress")
    assert reproduced.stderr.splitlines() == [want]
    every = write_config(PICKY % "all", name="every")  # `all`: index.md lists it, no warning
    quiet = trackfuse("run", every, "--out", tmp_path / "out", "--no-progress")
    assert quiet.returncode == 0 and quiet.stderr == ""

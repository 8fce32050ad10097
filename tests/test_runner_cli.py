"""`trackfuse run` and `reproduce` around the runner: phases after the last trial, exit
status, reproduce's options."""

from __future__ import annotations

from types import SimpleNamespace

from conftest import trackfuse

from trackfuse_cli.main import exit_status


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

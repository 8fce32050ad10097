"""The runner: determinism across executors, resume, failures, outputs, plot."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import cli_env, ctrl_c_at_part, trackfuse
from typer.testing import CliRunner

from trackfuse.config import load
from trackfuse.manifest import Manifest, write_manifest
from trackfuse.results import RunFolder
from trackfuse.runlock import HOLDER_FILE, RunLock
from trackfuse.runner import RunInterrupted, Runner
from trackfuse.seeding import trial_streams
from trackfuse_cli.main import app

CFG = """
experiment: toy_experiments:GAUSSIAN
trials: 23
seed: 11
params: {n: 4}
sweep:
  mu: [0, 2]
  sigma: [0.5, 1.0]
"""


def run(path, out, **kw):
    kw.setdefault("progress", False)
    return Runner(load(path), out, **kw).run()


def test_trials_csv_identical_for_serial_and_two_workers(write_config, tmp_path):
    path = write_config(CFG)
    serial = run(path, tmp_path / "a", executor="serial")
    pooled = run(path, tmp_path / "b", executor="process", workers=2)
    a = (serial.folder / "trials.csv").read_bytes()
    assert a == (pooled.folder / "trials.csv").read_bytes()
    assert (serial.folder / "summary.csv").read_bytes() == (pooled.folder /
                                                            "summary.csv").read_bytes()
    trials = pd.read_csv(serial.folder / "trials.csv")
    assert len(trials) == 4 * 23 * 2  # points x trials x algorithms
    assert list(trials.columns[:4]) == ["point", "trial", "mu", "sigma"]


def test_common_stream_depends_on_trial_and_seed_the_point_stream_also_on_the_point():
    a, b = trial_streams(11, 1, 3), trial_streams(11, 2, 3)
    assert (a.common.random(4) == b.common.random(4)).all()  # same at every sweep point
    assert not (a.point.random(4) == b.point.random(4)).any()
    again = trial_streams(11, 1, 3)
    assert (again.point.random(4) == trial_streams(11, 1, 3).point.random(4)).all()
    # no stream equals another trial's, another seed's, or the other kind's
    draws = {(s, p, t, kind): getattr(trial_streams(s, p, t), kind).random()
             for s in (0, 1) for p in (0, 1, 2) for t in (0, 1, 2) for kind in ("point",)}
    draws |= {(s, -1, t, "common"): trial_streams(s, 0, t).common.random()
              for s in (0, 1) for t in (0, 1, 2)}
    assert len(set(draws.values())) == len(draws)


CLUTTERED = """
experiment: toy_experiments:CLUTTERED
trials: 10
seed: 3
sweep: {density: [1.0, 2.0], gain: [1.0, 2.0, 3.0]}
"""


def test_points_differing_only_in_a_non_drawing_parameter_share_their_point_stream(
        write_config, tmp_path):
    """Points 0-2 (density 1) draw the point stream of point 0, points 3-5 (density 2) that
    of point 3, exactly as the runner drew them before draw points existed; rows keep their
    own point index."""
    path = write_config(CLUTTERED)
    trials = pd.read_csv(run(path, tmp_path, executor="process", workers=2).folder /
                         "trials.csv")
    assert trials["point"].tolist() == [p for p in range(6) for _ in range(10)]
    uniform = trials.pivot(index="trial", columns="point", values="uniform")
    for point in range(6):
        own = [trial_streams(3, 3 * (point // 3), t).point.random() for t in range(10)]
        assert uniform[point].tolist() == own
    assert not np.isin(uniform[0], uniform[3]).any()
    noise = trials.pivot(index="trial", columns="point", values="noise")
    assert (noise.nunique(axis=1) == 1).all()  # the common stream, as always
    estimate = trials.pivot(index="trial", columns="point", values="estimate")
    np.testing.assert_allclose(estimate[2], 3 * estimate[0], rtol=1e-12)  # gain only


def test_a_run_sharing_point_streams_resumes_to_the_same_bytes(write_config, tmp_path):
    path = write_config(CLUTTERED)
    reference = run(path, tmp_path / "ref", executor="serial")
    with ctrl_c_at_part(7), pytest.raises(RunInterrupted):
        run(path, tmp_path / "res", executor="serial")
    resumed = run(path, tmp_path / "res", executor="process", workers=2)
    assert 0 < resumed.computed_trials < 60
    assert (resumed.folder / "trials.csv").read_bytes() == (reference.folder /
                                                            "trials.csv").read_bytes()


def test_points_differing_only_in_a_parameter_the_trial_ignores_give_identical_rows(
        write_config, tmp_path):
    path = write_config("""
experiment: toy_experiments:GAUSSIAN
trials: 9
seed: 5
sweep: {label: [a, b]}
""")
    trials = pd.read_csv(run(path, tmp_path, executor="serial").folder / "trials.csv")
    a, b = (trials[trials["label"] == v].drop(columns=["point", "label"]).reset_index(drop=True)
            for v in ("a", "b"))
    pd.testing.assert_frame_equal(a, b)


def test_points_compare_on_common_random_numbers(write_config, tmp_path):
    """Two noise levels see the same standard-normal draws: estimates scale exactly."""
    path = write_config("""
experiment: toy_experiments:GAUSSIAN
trials: 9
seed: 5
sweep: {sigma: [1.0, 2.0]}
""")
    trials = pd.read_csv(run(path, tmp_path, executor="serial").folder / "trials.csv")
    est = trials.pivot_table(index=["trial", "algorithm"], columns="sigma", values="estimate")
    np.testing.assert_allclose(est[2.0], 2 * est[1.0], rtol=1e-12)


def test_batch_size_is_part_of_the_run_id_and_fixes_the_bytes(write_config, tmp_path):
    """What is promised about ``batch_size`` (docs/runner.md, Batches).

    A vectorized ``run_batch`` (here one matrix product over the batch, as in twin_sensor)
    may round the last bits differently when a batch holds other trials, so the batch size is
    part of the run id: changing it starts a new run folder, never mixing parts of two batch
    sizes. For one batch size the bytes are identical across executors and worker counts.
    Across batch sizes the numbers agree to floating-point reassociation (relative 1e-12),
    not to the byte.
    """
    path = write_config("experiment: toy_experiments:PROJECTED\ntrials: 60\nseed: 4\n"
                        "sweep: {scale: [1.0, 2.0]}\n")
    small = Runner(load(path, sets={"batch_size": 7}), tmp_path / "a", progress=False,
                   executor="serial")
    default = Runner(load(path), tmp_path / "a", progress=False, executor="serial")
    assert small.folder.path != default.folder.path
    a, b = small.run(), default.run()
    pooled = run(path, tmp_path / "b", executor="process", workers=2)
    assert (b.folder / "trials.csv").read_bytes() == (pooled.folder / "trials.csv").read_bytes()
    x, y = (pd.read_csv(o.folder / "trials.csv") for o in (a, b))
    np.testing.assert_allclose(x[["y0", "y1", "y2"]], y[["y0", "y1", "y2"]], rtol=1e-12)


def test_resume_after_interrupt_equals_uninterrupted(write_config, tmp_path):
    path = write_config(CFG)
    reference = run(path, tmp_path / "ref", executor="serial")
    with ctrl_c_at_part(5), pytest.raises(RunInterrupted) as err:
        run(path, tmp_path / "res", executor="serial")
    folder = err.value.folder
    assert json.loads((folder / "manifest.json").read_text())["status"] == "interrupted"
    assert not (folder / "trials.csv").exists()
    resumed = run(path, tmp_path / "res", executor="process", workers=2)
    assert resumed.computed_trials == 4 * 23 - 23  # point 0 (batches of 7, 7, 7, 2) was kept
    assert (resumed.folder / "trials.csv").read_bytes() == (reference.folder /
                                                            "trials.csv").read_bytes()
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["sessions"] == 2


def test_a_full_disk_leaves_an_interrupted_run_that_resumes(write_config, tmp_path,
                                                           monkeypatch):
    """A disk that fills up while the parts are merged: the manifest says interrupted (not
    running) with every trial counted, and the same command finishes the run once there is
    room."""
    path = write_config(CFG)
    original = RunFolder.merge

    def full(self, *args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(RunFolder, "merge", full)
    with pytest.raises(OSError):
        run(path, tmp_path / "out", executor="serial")
    folder = next((tmp_path / "out").rglob("manifest.json")).parent
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["status"] == "interrupted" and manifest["trials_done"] == 4 * 23
    monkeypatch.setattr(RunFolder, "merge", original)
    assert run(path, tmp_path / "out", executor="serial").computed_trials == 0


def test_failed_trials_are_recorded_and_the_run_goes_on(write_config, tmp_path):
    path = write_config(CFG + "  fail_every: [3]\n")
    result = trackfuse("run", path, "--out", tmp_path, "--workers", "2", "--no-plots")
    assert result.returncode == 3, result.stderr
    assert "trials failed" in result.stderr and "Traceback" not in result.stderr
    folder = next((tmp_path / "cfg").iterdir())
    trials = pd.read_csv(folder / "trials.csv")
    failed = trials[trials["status"] == "failed"]
    assert 0 < len(failed) < 4 * 23
    assert failed["error"].str.contains("FloatingPointError: synthetic divergence").all()
    ok_trials = trials[trials["status"] != "failed"].groupby(["point", "trial"]).size()
    assert (ok_trials == 2).all()  # both algorithms of every successful trial
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["trials_failed"] == len(failed)
    summary = pd.read_csv(folder / "summary.csv")
    assert summary.groupby("point")["n"].max().sum() + len(failed) == 4 * 23


def test_cli_run_writes_outputs_and_plot_redraws_them(write_config, tmp_path):
    path = write_config(CFG)
    result = trackfuse("run", path, "--out", tmp_path, "--workers", "2")
    assert result.returncode == 0, result.stderr
    folder = next((tmp_path / "cfg").iterdir())
    for name in ("config.yaml", "manifest.json", "trials.csv", "summary.csv",
                 "figures/estimate.png", "figures/estimate.pdf"):
        assert (folder / name).exists(), name
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["root_seed"] == 11
    assert manifest["trials_done"] == manifest["trials_total"] == 92
    assert set(manifest["versions"]) >= {"trackfuse", "python", "numpy", "scipy", "numba"}
    assert set(manifest["per_point_wall_s"]) == {"0", "1", "2", "3"}
    png = (folder / "figures/estimate.png").read_bytes()
    pdf = (folder / "figures/estimate.pdf").read_bytes()
    for f in (folder / "figures").iterdir():
        f.unlink()
    result = trackfuse("plot", folder)
    assert result.returncode == 0, result.stderr
    assert (folder / "figures/estimate.png").read_bytes() == png
    assert (folder / "figures/estimate.pdf").read_bytes() == pdf
    again = trackfuse("run", path, "--out", tmp_path)
    assert again.returncode == 0 and "already complete" in again.stdout


def test_dry_run_runs_nothing(write_config, tmp_path):
    result = trackfuse("run", write_config(CFG), "--dry-run", "--out", tmp_path,
                       "--sweep", "n=range(1,4)")
    assert result.returncode == 0, result.stderr
    assert "12 points x 23 trials = 276 trials" in result.stdout
    assert "experiment: toy_experiments:GAUSSIAN" in result.stdout
    assert not any(tmp_path.glob("cfg/*"))


@pytest.mark.slow
def test_dry_run_says_what_the_run_would_start_from(write_config, tmp_path):
    path = write_config(CFG)
    out = tmp_path / "out"

    def plan(*flags):
        result = trackfuse("run", path, "--dry-run", "--out", out, *flags)
        assert result.returncode == 0, result.stderr
        return result.stdout.splitlines()[-1]

    assert plan().endswith("(new)")
    runner = Runner(load(path), out, progress=False)
    runner.folder.prepare(runner.resolved)
    write_manifest(runner.folder.path, Manifest("interrupted", trials_done=46))
    assert plan().endswith("(interrupted, 46 trials saved; resumes)")
    run(path, out)
    assert plan().endswith("(complete; nothing to compute)")
    assert plan("--force").endswith("(exists; --force recomputes every trial)")
    (runner.folder.path / "summary.csv").write_text("point\n")
    assert "summary.csv" in plan() and plan().endswith("rebuilds the final files)")
    run(path, out)  # rebuilt
    for name in ("index.html", "manifest.json"):  # a report to draw; then no manifest
        (runner.folder.path / name).unlink()
        assert plan().endswith({"index.html": "(complete; nothing to compute, draws the report)",
                                "manifest.json": "(no manifest; verifies the saved batches, "
                                                 "computes the rest)"}[name])
    (runner.folder.path / "manifest.json").write_text(json.dumps({"status": "running"}))
    assert plan().endswith("(stopped before it ended; resumes from its saved batches)")


@pytest.mark.slow
def test_dry_run_refuses_an_output_folder_the_run_could_not_create(write_config, tmp_path):
    path = write_config(CFG)
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    for out, words in ((blocker, "the output root is not a folder"),
                       (blocker / "below", f"({blocker} is not a folder)")):
        result = trackfuse("run", path, "--dry-run", "--out", out)
        assert result.returncode == 2 and result.stdout == ""
        assert result.stderr.startswith("error: ") and words in result.stderr
        assert len(result.stderr.splitlines()) == 1
        real = trackfuse("run", path, "--out", out, "--no-plots", "--no-progress")
        assert real.returncode == 2 and str(out) in real.stderr
    (tmp_path / "nowhere").symlink_to(tmp_path / "missing")  # a link to nothing: refused too
    dangling = trackfuse("run", path, "--dry-run", "--out", tmp_path / "nowhere")
    assert dangling.returncode == 2 and "is not a folder" in dangling.stderr


@pytest.mark.slow
def test_dry_run_refuses_a_folder_the_run_could_not_use(write_config, tmp_path):
    """--dry-run promised a resume or a complete run where the run then stopped: a final file
    that is a folder, a run folder another process holds."""
    path = write_config(CFG)
    runner = Runner(load(path), tmp_path, progress=False, plots=False)
    runner.run()
    dry = ("run", path, "--dry-run", "--out", tmp_path)
    with RunLock(runner.folder.path, print):
        held = trackfuse(*dry)
    assert held.returncode == 2 and f"in use by trackfuse pid {os.getpid()}" in held.stderr
    (runner.folder.path / HOLDER_FILE).write_text('{"pid": 1, "host": "elsewhere"}')
    assert trackfuse(*dry).returncode == 0  # a holder file alone: the run takes over
    (runner.folder.path / "summary.csv").unlink()
    (runner.folder.path / "summary.csv").mkdir()
    for result in (trackfuse(*dry), trackfuse(*dry[:2], "--out", tmp_path, "--no-progress")):
        assert result.returncode == 2 and "summary.csv: exists but is not a regular file" \
            in result.stderr


def test_plot_refuses_an_incomplete_run(write_config, tmp_path):
    path = write_config(CFG)
    runner = Runner(load(path), tmp_path, progress=False)
    runner.folder.prepare(runner.resolved)
    write_manifest(runner.folder.path, Manifest("interrupted"))
    result = trackfuse("plot", runner.folder.path)
    assert result.returncode == 2 and "not complete" in result.stderr


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_and_the_run_resumes(write_config, tmp_path):
    path = write_config("experiment: toy_experiments:BURN\ntrials: 400\nseed: 1\n"
                        "params: {work: 30}\n", "burn")
    command = [sys.executable, "-m", "trackfuse", "run", str(path), "--out", str(tmp_path),
               "--workers", "2", "--no-plots"]
    # A shell that runs the tests in the background ignores SIGINT, and children inherit
    # that; restore the default so the CLI sees Ctrl-C as a user would.
    proc = subprocess.Popen(command, env=cli_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not list(tmp_path.glob("burn/*/parts/*.trials.csv")):
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "run the same command again to resume" in err and "Traceback" not in err
    resumed = subprocess.run(command, env=cli_env(), capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 0, resumed.stderr
    assert "computed now" in resumed.stdout
    reference = trackfuse("run", path, "--out", tmp_path / "ref", "--executor", "serial",
                          "--no-plots")
    assert reference.returncode == 0
    got = next((tmp_path / "burn").iterdir()) / "trials.csv"
    want = next((tmp_path / "ref" / "burn").iterdir()) / "trials.csv"
    assert got.read_bytes() == want.read_bytes()


@pytest.mark.slow
def test_reproduce_runs_every_config_of_a_folder_and_resumes(tmp_path):
    configs = tmp_path / "configs"
    configs.mkdir()
    (configs / "a.yaml").write_text(CFG)
    (configs / "b.yaml").write_text(CFG.replace("seed: 11", "seed: 12"))
    first = trackfuse("reproduce", configs, "--out", tmp_path / "out", "--workers", "2",
                      "--no-progress")
    assert first.returncode == 0, first.stderr
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["REPORT.md", "a", "b",
                                                                   "notes", "report.html"]
    assert first.stdout.splitlines()[-1] == f"report: {tmp_path / 'out' / 'report.html'}"
    again = trackfuse("reproduce", configs, "--out", tmp_path / "out", "--no-progress")
    assert again.returncode == 0 and again.stdout.count("(0 of 92 trials computed now") == 2
    (configs / "c.yaml").write_text("experiment: toy_gaussian\nparams: {sigma: -1}\n")
    bad = trackfuse("reproduce", configs, "--out", tmp_path / "out")
    assert bad.returncode == 2 and "c.yaml: params.sigma" in bad.stderr


def cli(*args):
    return CliRunner().invoke(app, [str(a) for a in args], catch_exceptions=True)


def test_cli_run_with_a_trial_calling_sys_exit_exits_3(write_config, tmp_path):
    path = write_config("experiment: toy_experiments:UNRULY\ntrials: 20\nseed: 3\n")
    result = cli("run", path, "--out", tmp_path, "--executor", "serial", "--no-progress")
    assert result.exit_code == 3, result.stderr
    assert result.stderr.startswith("error: ") and "trials failed" in result.stderr
    again = cli("run", path, "--out", tmp_path, "--no-progress")
    assert again.exit_code == 3 and "already complete" in again.stdout


def test_a_config_called_dot_dot_dot_yaml_writes_under_the_output_root(tmp_path):
    root = tmp_path / "inner"
    path = root / "...yaml"
    root.mkdir()
    path.write_text(CFG)
    out = root / "out"
    result = trackfuse("run", path, "--out", out, "--no-plots", "--executor", "serial")
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in root.iterdir()) == ["...yaml", "out"]
    assert [p.name for p in out.iterdir()] == ["config"]


def test_out_that_is_a_file_or_not_writable_is_one_line(write_config, tmp_path):
    path = write_config(CFG)
    afile = tmp_path / "afile"
    afile.write_text("x")
    unwritable = Path("/proc/trackfuse-out")  # not creatable, even by root
    for out in (afile, afile / "below", unwritable):
        result = cli("run", path, "--out", out, "--no-plots")
        assert result.exit_code == 2, result.stderr
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
        assert str(out) in lines[0]


def test_a_billion_trials_in_batches_of_one_start_at_once_in_flat_memory(write_config,
                                                                         tmp_path, monkeypatch):
    """The plan is lazy: no list of 10^9 batches is built, on the first run or on resume."""
    path = write_config("experiment: toy_experiments:TRIVIAL\ntrials: 1000000000\n"
                        "batch_size: 1\nseed: 1\n")
    original = RunFolder.write_part
    written = []

    def stop_after_20(self, span, *args):
        original(self, span, *args)
        written.append(span)
        if len(written) % 20 == 0:
            raise KeyboardInterrupt

    monkeypatch.setattr(RunFolder, "write_part", stop_after_20)

    tracemalloc.start()
    t0 = time.perf_counter()
    for expected_done in (20, 40):
        with pytest.raises(RunInterrupted) as err:
            run(path, tmp_path, executor="serial", plots=False)
        # the part of the interrupted batch is on disk, but was not yet counted
        assert err.value.done == expected_done - 1 and err.value.total == 10**9
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert time.perf_counter() - t0 < 30
    assert peak < 20e6, f"{peak / 1e6:.0f} MB"
    assert [s.first for s in written] == list(range(40))  # resume recomputed nothing


def test_a_trials_own_interrupt_is_contained_when_ctrl_c_is_ignored(write_config, tmp_path):
    """A background job (SIGINT ignored) cannot get Ctrl-C: a KeyboardInterrupt raised by a
    trial fails that trial instead of stopping the run."""
    path = write_config("experiment: toy_experiments:UNRULY\ntrials: 12\nseed: 3\n"
                        "params: {how: interrupt}\n")
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        outcome = run(path, tmp_path / "s", executor="serial")
    finally:
        signal.signal(signal.SIGINT, previous)
    assert 0 < outcome.failed_trials < 12


def test_a_runs_own_config_runs_again_into_that_run(write_config, tmp_path):
    """Running a run folder's config.yaml (the natural "re-run this result") computed the
    same run id anew under <out>/config/; with --force the manifest then named the run's
    own config.yaml, and the next run went to config/ too."""
    first = run(write_config(CFG, "study"), tmp_path, executor="serial", plots=False)
    own = first.folder / "config.yaml"
    assert run(own, tmp_path, executor="serial").status == "already complete"
    for _ in range(2):
        again = run(own, tmp_path, executor="serial", plots=False, force=True)
        assert again.folder == first.folder and again.computed_trials == 92
    manifest = json.loads((first.folder / "manifest.json").read_text())
    assert manifest["config_file"] == str(tmp_path / "study.yaml")
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_dir()) == ["study"]

"""Sequential trial counts: looks, per-point stopping, identical for any worker count,
executor and resume, stopped-at-max reported, --trials still fixes the count; coverage of
the final interval by simulation (examples/sequential_coverage.py)."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, cli_env, ctrl_c_at_part

from trackfuse.config import ConfigError, load
from trackfuse.runner import RunInterrupted, Runner
from trackfuse.sequential import SequentialRule

CFG = ("experiment: toy_experiments:GAUSSIAN\nseed: 4\n"
       "trials: {min: 20, max: 1000, until: {metric: estimate, half_width: 0.05}}\n"
       "sweep: {sigma: [0.5, 1.0, 4.0]}\n")
HALF_WIDTH = 0.05


def _run(config, out, **kw):
    return Runner(config, out, progress=False, plots=False, **kw).run()


def test_looks_double_on_batch_boundaries_up_to_max():
    rule = SequentialRule(20, 1000, "estimate", 0.05)
    assert rule.looks(7) == [21, 42, 84, 168, 336, 672, 1000]
    assert SequentialRule(100, 20000, "correct", 0.01).looks(25) == \
        [100, 200, 400, 800, 1600, 3200, 6400, 12800, 20000]
    assert SequentialRule(5, 5, "x", 1.0).looks(25) == [5]


def test_each_point_stops_when_every_cell_is_narrow_enough_or_at_max(write_config, tmp_path):
    config = load(write_config(CFG, "seq"))
    serial = _run(config, tmp_path / "one", workers=1, executor="serial")
    pooled = _run(config, tmp_path / "two", workers=2, executor="process")
    for name in ("trials.csv", "summary.csv"):
        assert (serial.folder / name).read_bytes() == (pooled.folder / name).read_bytes()
    manifest = json.loads((serial.folder / "manifest.json").read_text())["sequential"]
    counts = manifest["trials"]
    assert counts[0] < counts[1] < counts[2] == 1000  # more spread, more trials
    assert manifest["stopped_at_max"] == [2]
    summary = pd.read_csv(serial.folder / "summary.csv")
    estimate = summary[summary["metric"] == "estimate"]
    width = (estimate["ci_high"] - estimate["ci_low"]) / 2
    met = estimate["point"] != 2
    assert (width[met] <= HALF_WIDTH).all() and (width[~met] > HALF_WIDTH).all()
    assert (estimate.groupby("point")["n"].first().tolist()) == counts
    assert estimate["stopping"].str.endswith("stopped at max 1000").tolist() == \
        (~met).tolist()
    trials = pd.read_csv(serial.folder / "trials.csv")
    assert trials.groupby("point")["trial"].nunique().tolist() == counts


def test_a_sequential_point_holds_the_rows_of_a_fixed_run_of_its_count(write_config,
                                                                       tmp_path):
    """The rule only decides how many trials: point 1's rows are those of a fixed run."""
    sequential = _run(load(write_config(CFG, "seq")), tmp_path / "s", executor="serial")
    count = json.loads((sequential.folder / "manifest.json").read_text())["sequential"][
        "trials"][1]
    fixed = _run(load(write_config(CFG, "seq"), {"trials": count}), tmp_path / "f",
                 executor="serial")
    assert json.loads((fixed.folder / "manifest.json").read_text()).get("sequential") is None
    rows = pd.read_csv(sequential.folder / "trials.csv")
    again = pd.read_csv(fixed.folder / "trials.csv")
    pd.testing.assert_frame_equal(rows[rows["point"] == 1].reset_index(drop=True),
                                  again[again["point"] == 1].reset_index(drop=True))


def test_an_interrupted_sequential_run_resumes_to_the_same_bytes(write_config, tmp_path):
    config = load(write_config(CFG, "seq"))
    reference = _run(config, tmp_path / "ref", executor="serial")
    out = tmp_path / "out"
    for at in (5, 30, 60):  # inside the first look, and in later looks
        with ctrl_c_at_part(at), pytest.raises(RunInterrupted):
            _run(config, out, executor="serial")
    resumed = _run(config, out, executor="serial")
    for name in ("trials.csv", "summary.csv"):
        assert (resumed.folder / name).read_bytes() == (reference.folder / name).read_bytes()


def test_a_sequential_run_killed_9_resumes_to_the_same_bytes(write_config, tmp_path):
    path = write_config(CFG.replace("max: 1000", "max: 4000"), "seq")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "trackfuse", "run", str(path), "--out", str(out),
               "--workers", "2", "--no-plots", "--no-progress"]
    proc = subprocess.Popen(command, env=cli_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline and \
            len(list(out.glob("seq/*/parts/*.trials.csv"))) < 40:
        time.sleep(0.02)
    killed = proc.poll() is None
    if killed:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    assert killed, "the run finished before it could be killed"
    final = subprocess.run(command, env=cli_env(), capture_output=True, text=True, timeout=300)
    assert final.returncode == 0, final.stderr
    reference = _run(load(path), tmp_path / "ref", executor="serial")
    got = next(out.glob("seq/*/trials.csv")).read_bytes()
    assert got == (reference.folder / "trials.csv").read_bytes()


def test_trials_on_the_command_line_fixes_the_count(write_config):
    config = load(write_config(CFG, "seq"), {"trials": 30})
    assert config.sequential is None and config.trials == 30
    assert load(write_config(CFG, "seq")).to_dict()["trials"] == {
        "min": 20, "max": 1000, "until": {"metric": "estimate", "half_width": 0.05}}


@pytest.mark.parametrize(("trials", "key"), [
    ("{min: 20, max: 10, until: {metric: estimate, half_width: 0.1}}", "trials.max"),
    ("{min: 20, max: 100, until: {metric: estimat, half_width: 0.1}}", "trials.until.metric"),
    ("{min: 20, max: 100, until: {metric: estimate, half_width: 0}}",
     "trials.until.half_width"),
    ("{min: 20, max: 100}", "trials.until"),
    ("{min: 20, max: 100, until: {metric: estimate, half_width: 1}, step: 3}", "trials.step"),
])
def test_a_bad_rule_is_one_line_naming_its_key(write_config, trials, key):
    with pytest.raises(ConfigError) as err:
        load(write_config(f"experiment: toy_experiments:GAUSSIAN\ntrials: {trials}\n"))
    assert err.value.key == key and "allowed" in err.value.message


def _coverage_script():
    spec = importlib.util.spec_from_file_location(
        "sequential_coverage", ROOT / "examples" / "sequential_coverage.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("p", [0.1, 0.5, 0.95])
def test_the_final_wilson_interval_covers_about_95_percent(p):
    """2000 simulated sequential runs (the rule min 100, max 20000, half-width 0.01):
    coverage within 3 Monte Carlo standard errors (0.015) of what the script measures with
    20,000 runs (0.943-0.951 at these p), and the rule reached before max."""
    script = _coverage_script()
    coverage, trials = script.binary_coverage(script.RULE, p, 2000,
                                              np.random.default_rng(7))
    assert 0.925 <= coverage <= 0.97
    assert trials < script.RULE.max

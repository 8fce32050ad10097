"""`trackfuse compare`: a planted shift is found, an unchanged run passes, bad input is 2."""

from __future__ import annotations

import json

import pytest
from conftest import trackfuse
from typer.testing import CliRunner

from trackfuse.config import load
from trackfuse.harness import run_data
from trackfuse.runner import Runner
from trackfuse_cli.main import app


def _run(write_config, tmp_path, shift: float, seed: int, name: str):
    cfg = write_config(f"experiment: toy_shifted\ntrials: 200\nseed: {seed}\n"
                       f"params: {{shift: {shift}}}\n", name=name)
    return Runner(load(cfg), tmp_path / "out", progress=False, plots=False).run().folder


def _compare(*args):
    return CliRunner().invoke(app, ["compare", *map(str, args)])


def test_a_planted_regression_is_found_and_an_unchanged_run_passes(write_config, tmp_path):
    base = _run(write_config, tmp_path, 0.0, 1, "base")
    same = _run(write_config, tmp_path, 0.0, 1, "same")
    worse = _run(write_config, tmp_path, 0.3, 1, "worse")
    unpaired = _run(write_config, tmp_path, 0.5, 2, "other_seed")
    ok = _compare(base, same, "--fail-on-regression")
    assert ok.exit_code == 0 and "paired comparison" in ok.stdout
    found = _compare(base, worse, "--fail-on-regression", "--json")
    assert found.exit_code == 1
    report = json.loads(found.stdout)
    assert report["paired"] and report["regressions"] == 1
    assert abs(report["cells"][0]["diff"] - 0.3) < 1e-12
    tolerated = _compare(base, worse, "--fail-on-regression", "--tolerance", "miss=0.5")
    assert tolerated.exit_code == 0
    far = _compare(base, unpaired, "--fail-on-regression", "--json")
    assert far.exit_code == 1 and not json.loads(far.stdout)["paired"]


def test_bad_input_is_one_line_exit_2(write_config, tmp_path):
    base = _run(write_config, tmp_path, 0.0, 1, "base")
    other = write_config("experiment: toy_gaussian\ntrials: 3\nseed: 1\n", name="gauss")
    gauss = Runner(load(other), tmp_path / "out", progress=False, plots=False).run().folder
    for args in ((base, gauss), (base, tmp_path / "missing"), (base, base, "--tolerance", "x"),
                 (base, base, "--alpha", "2")):
        result = _compare(*args)
        assert result.exit_code == 2, (args, result.stdout)
        assert len(result.stderr.strip().splitlines()) == 1 and "error:" in result.stderr


def _swept(write_config, tmp_path, shifts: str, name: str):
    cfg = write_config(f"experiment: toy_shifted\ntrials: 20\nseed: 1\n"
                       f"sweep: {{shift: {shifts}}}\n", name=name)
    return Runner(load(cfg), tmp_path / "out", progress=False, plots=False).run().folder


def test_a_cell_of_base_missing_from_new_fails_the_gate_and_one_only_in_new_does_not(
        write_config, tmp_path):
    """NEW without BASE's point shift=0.5 (a sweep point lost to failed trials or a smaller
    sweep) passed the gate: the missing cells were one line on stdout and exit 0."""
    base = _swept(write_config, tmp_path, "[0.0, 0.5]", "base")
    fewer = _swept(write_config, tmp_path, "[0.0]", "fewer")
    gated = _compare(base, fewer, "--fail-on-regression")
    assert gated.exit_code == 1, gated.stdout
    assert gated.stderr.strip().splitlines() == [
        "error: 1 cells of BASE missing from NEW, e.g. shift=0.5, algorithm=a, metric=miss"]
    report = json.loads(_compare(base, fewer, "--fail-on-regression", "--json").stdout)
    assert (report["compared"], report["only_base"], report["only_new"]) == (1, 1, 0)
    assert report["only_base_cells"] == [{"shift": 0.5, "algorithm": "a", "metric": "miss"}]
    assert report["gate_failure"].startswith("1 cells of BASE missing from NEW")
    plain = _compare(base, fewer)
    assert plain.exit_code == 0 and plain.stderr == ""
    assert "not compared: 1 cells only in BASE (e.g. shift=0.5, algorithm=a" in plain.stdout
    more = _compare(fewer, base, "--fail-on-regression", "--json")
    assert more.exit_code == 0, more.stderr
    assert json.loads(more.stdout)["only_new"] == 1
    assert json.loads(more.stdout)["gate_failure"] is None


def test_comparing_nothing_fails_the_gate(write_config, tmp_path):
    """Two runs over disjoint sweeps share no cell: '0 cells, 0 gated' and exit 0 with
    --fail-on-regression, "cells": [] with --json."""
    base = _swept(write_config, tmp_path, "[0.0]", "base")
    other = _swept(write_config, tmp_path, "[0.5, 1.0]", "other")
    gated = _compare(base, other, "--fail-on-regression")
    assert gated.exit_code == 1
    assert len(gated.stderr.strip().splitlines()) == 1
    assert gated.stderr.startswith("error: nothing compared (the runs share no cell); 1 cells "
                                   "of BASE missing from NEW, e.g. shift=0.0")
    report = json.loads(_compare(base, other, "--fail-on-regression", "--json").stdout)
    assert report["compared"] == 0 and report["cells"] == []
    assert (report["only_base"], report["only_new"]) == (1, 2)
    plain = _compare(base, other)
    assert plain.exit_code == 0
    assert plain.stdout.startswith("nothing compared: the runs share no cell; 1 cells only "
                                   "in BASE (e.g. shift=0.0, algorithm=a, metric=miss), 2 cells "
                                   "only in NEW (e.g. shift=0.5")


@pytest.mark.slow
def test_plot_and_compare_say_the_same_accurate_line_for_what_is_no_run(write_config,
                                                                         tmp_path):
    """`plot` said "(no manifest.json)" and `compare` "(not a directory)" for paths of one
    kind, and a path that does not exist was "not a directory"."""
    run = _run(write_config, tmp_path, 0.0, 1, "base")
    (tmp_path / "file.txt").write_text("x")
    (tmp_path / "empty").mkdir()
    reasons = {tmp_path / "missing": "no such file or folder",
               tmp_path / "file.txt": "not a run folder: a file",
               tmp_path / "empty": "not a run folder: no manifest.json",
               tmp_path / "out": "a folder of 1 run, not a run; name one of them"}
    for path, reason in reasons.items():
        plotted = trackfuse("plot", path)
        compared = trackfuse("compare", path, run)
        assert plotted.returncode == compared.returncode == 2, (path, compared.stderr)
        assert plotted.stderr == compared.stderr, path
        assert plotted.stderr.splitlines() == [compared.stderr.strip()]
        assert compared.stderr.startswith(f"error: {path}: {reason}"), compared.stderr
        assert trackfuse("compare", run, path).stderr == compared.stderr


def test_the_summary_says_how_trials_pair_what_config_differs_and_what_is_gated(tmp_path):
    """Two runs differing only in the trial count were compared unpaired, the output did
    not say how the runs differ, and "4 no significant change, 4 no significant difference"
    did not say which cells the regression gate judged."""
    sweep = {"mu": [0.0, 1.0]}
    base = run_data(tmp_path / "a", "toy_gaussian", {}, sweep, trials=30, seed=3).path
    more = run_data(tmp_path / "b", "toy_gaussian", {}, sweep, trials=45, seed=3).path
    lines = _compare(base, more).stdout.splitlines()
    assert lines[0] == ("bottom line: no significant change in any of the 4 gated cells; "
                        "0 of 4 cells not gated differ")
    assert lines[1:5] == [
        "paired comparison of 8 cells on the trial indices both runs have (same seed 3; 30 "
        "trials per point in BASE, 45 in NEW: the others are left out)",
        "config differs: trials (BASE 30, NEW 45)",
        "gated (the regression gate, family-wise alpha 0.05): 4 cells, 4 no significant change",
        "not gated (no better direction declared; each cell's 95 % interval, not adjusted): "
        "4 cells, 4 no significant difference"]
    report = json.loads(_compare(base, more, "--json").stdout)
    assert report["paired"] and report["config_differences"] == [
        {"key": "trials", "base": 30, "new": 45}]
    assert {c["n_new"] for c in report["cells"]} == {30}
    again = run_data(tmp_path / "c", "toy_gaussian", {}, sweep, trials=30, seed=3).path
    same = _compare(base, again).stdout.splitlines()[1:]
    assert same[0].endswith("trial by trial (same seed 3, 30 trials per point)")
    assert same[1] == "config: the same in both runs"

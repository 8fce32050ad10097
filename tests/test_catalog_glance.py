"""Runs at a glance: `trackfuse runs` says how runs differ, --json, --name;
trackfuse.runs() as a DataFrame; compare's bottom line, gated cells first, filters."""

from __future__ import annotations

import json

import pandas as pd
from typer.testing import CliRunner

import trackfuse
from trackfuse.config import load
from trackfuse.experiments import register
from trackfuse.experiments.base import Experiment, Metric, Param
from trackfuse.runner import Runner
from trackfuse_cli.main import app


def _ten_runs(write_config, tmp_path):
    """Ten toy_gaussian runs under one root: five values of mu x two seeds, named."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 3\nseed: 1\n", name="gauss")
    out = tmp_path / "out"
    for mu in range(5):
        for seed in (1, 2):
            Runner(load(cfg, {"mu": float(mu), "seed": seed}), out, progress=False,
                   plots=False, name=f"mu{mu}-s{seed}").run()
    return out


def test_runs_frame_has_one_row_per_run_with_every_parameter(write_config, tmp_path):
    out = _ten_runs(write_config, tmp_path)
    table = trackfuse.runs(out)
    assert isinstance(table, pd.DataFrame) and len(table) == 10
    for column in ("experiment", "status", "name", "seed", "trials", "start", "wall_s",
                   "params.mu", "params.sigma", "params.label"):
        assert column in table, column
    assert set(table["experiment"]) == {"toy_gaussian"}
    assert set(table["trials"]) == {3}
    by_name = table.set_index("name")
    assert by_name.loc["mu3-s2", "params.mu"] == 3.0 and by_name.loc["mu3-s2", "seed"] == 2
    assert (table["wall_s"] >= 0).all()
    assert pd.api.types.is_datetime64_any_dtype(table["start"])
    assert table["start"].is_monotonic_decreasing  # newest first


def test_runs_shows_what_differs_and_lists_json_and_filters_by_name(write_config, tmp_path):
    out = _ten_runs(write_config, tmp_path)
    listed = CliRunner().invoke(app, ["runs", str(out), "--json"])
    assert listed.exit_code == 0, listed.output
    runs = json.loads(listed.stdout)
    assert len(runs) == 10
    for run in runs:  # mu and seed tell them apart; sigma, trials, label are common
        mu, seed = run["name"][2], run["name"][-1]
        assert run["differs"] == {"seed": int(seed), "mu": float(mu)}
    named = json.loads(CliRunner().invoke(app, ["runs", str(out), "--json",
                                                "--name", "mu2-*"]).stdout)
    assert sorted(r["name"] for r in named) == ["mu2-s1", "mu2-s2"]
    assert [r["differs"] for r in named if r["name"] == "mu2-s1"] == [{"seed": 1}]
    table = CliRunner().invoke(app, ["runs", str(out), "--name", "mu4-s1"])
    assert table.exit_code == 0 and "differs in" in table.stdout
    none = CliRunner().invoke(app, ["runs", str(out), "--name", "nothing"])
    assert none.exit_code == 0 and "no runs under" in none.stdout


def _two_kinds_trial(params, streams) -> list[dict]:
    """Two algorithms, each a gated miss and an ungated diagnostic, both moved by ``shift``
    (the diagnostic's metric name sorts before the gated one's)."""
    noise = float(streams.common.normal())
    return [{"algorithm": name, "a_spread": params["shift"] + noise + offset,
             "miss": params["shift"] + noise + offset} for name, offset in (("x", 0), ("y", 1))]


register(Experiment(
    name="toy_two_kinds", title="A gated and an ungated metric",
    params=(Param("shift", 0.0, "added to every value", "m"),),
    run_trial=_two_kinds_trial,
    metrics=(Metric("a_spread", "m", "a diagnostic"),
             Metric("miss", "m", "a miss distance", better="lower"))))


def _shifted_run(write_config, tmp_path, shift: float, name: str):
    cfg = write_config(f"experiment: toy_two_kinds\ntrials: 40\nseed: 1\n"
                       f"params: {{shift: {shift}}}\n", name=name)
    return Runner(load(cfg), tmp_path / "out", progress=False, plots=False).run().folder


def test_compare_prints_a_bottom_line_first_gated_cells_first_and_filters(write_config,
                                                                         tmp_path):
    base = _shifted_run(write_config, tmp_path, 0.0, "base")
    new = _shifted_run(write_config, tmp_path, 1.0, "new")  # every value moves by 1
    shown = CliRunner().invoke(app, ["compare", str(base), str(new)])
    assert shown.exit_code == 0, shown.output
    lines = shown.stdout.splitlines()
    assert lines[0] == ("bottom line: 2 regressions and 0 improvements in 2 gated cells; "
                        "2 of 2 cells not gated differ")
    rows = [line for line in shown.stdout.splitlines() if line.startswith("│")]
    assert [row.split("│")[2].strip() for row in rows] == ["miss", "miss", "a_spread",
                                                             "a_spread"]
    only = json.loads(CliRunner().invoke(app, ["compare", str(base), str(new), "--json",
                                               "--metric", "a_spread", "--algorithm",
                                               "y"]).stdout)
    assert [(c["metric"], c["algorithm"]) for c in only["cells"]] == [("a_spread", "y")]
    assert only["gated"] == 0 and only["bottom_line"].startswith("bottom line: nothing gated")
    for args, option in ((["--metric", "mis"], "--metric"),
                         (["--algorithm", "z"], "--algorithm")):
        bad = CliRunner().invoke(app, ["compare", str(base), str(new), *args])
        assert bad.exit_code == 2 and option in bad.stderr
        assert len(bad.stderr.strip().splitlines()) == 1

"""`trackfuse compare`: a planted shift is found, an unchanged run passes, bad input is 2."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from trackfuse.config import load
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

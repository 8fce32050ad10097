"""`trackfuse list` (cli/describe.py): names never cut, template that validates, JSON."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest
import yaml
from conftest import cli_env, trackfuse

from trackfuse import experiments
from trackfuse.config import load
from trackfuse_cli.describe import config_template


@pytest.fixture(scope="module")
def twin():
    return experiments.get("twin_sensor")


def test_list_experiment_prints_every_key_whole_when_piped_at_80_columns(twin):
    result = subprocess.run([sys.executable, "-m", "trackfuse", "list", "twin_sensor"],
                            env={**cli_env(), "COLUMNS": "80"}, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    lines = [line.strip() for line in result.stdout.splitlines()]
    wrapped = [line for line in result.stdout.splitlines() if not line.startswith("  ") or
               line.startswith("    ")]  # all but the name lines, which are never cut
    assert max(len(line) for line in wrapped) <= 80
    for p in twin.params:  # each key heads its own line, in full, with its default
        assert any(line.startswith(f"{p.key} = ") for line in lines), p.key
    for m in twin.metrics:
        assert any(line.startswith(f"{m.name} [{m.unit}]") for line in lines), m.name
    for name in twin.figures:
        assert any(line.split(" (paper")[0] == name for line in lines), name
    joined = result.stdout.replace("\n    ", " ")
    assert all(a in joined for a in twin.algorithms)
    assert joined.count("share their simulated data") == sum(not p.draws for p in twin.params) > 0
    assert "…" not in result.stdout


@pytest.mark.parametrize("name", list(experiments.BUILTIN) + ["toy_experiments:GAUSSIAN"])
def test_yaml_template_validates_as_is_and_holds_the_defaults(name, tmp_path):
    result = trackfuse("list", name, "--format", "yaml")
    assert result.returncode == 0, result.stderr
    path = tmp_path / "template.yaml"
    path.write_text(result.stdout)
    assert trackfuse("validate", path).returncode == 0
    config = load(path)
    assert config.params == experiments.get(name).defaults()
    assert config.figures == "all" and config.experiment_ref == name
    commented = [line for line in result.stdout.splitlines() if line.startswith("  # ")]
    assert len(commented) == len(config.experiment.params) + 1  # one per key + figures


def test_json_lists_params_metrics_algorithms_and_figures(twin):
    result = trackfuse("list", "twin_sensor", "--format", "json")
    data = json.loads(result.stdout)
    assert [p["key"] for p in data["params"]] == [p.key for p in twin.params]
    assert [p["draws"] for p in data["params"]] == [p.draws for p in twin.params]
    assert {m["name"]: (m["unit"], m["binary"], m["better"]) for m in data["metrics"]} == \
        {m.name: (m.unit, m.binary, m.better) for m in twin.metrics}
    assert data["algorithms"] == list(twin.algorithms) and data["algorithms"]
    assert [f["name"] for f in data["figures"]] == list(twin.figures)


def test_list_names_every_experiment_in_a_table_or_json_and_refuses_a_yaml_template():
    """`list --format json` was refused although the help promised json; `list` showed
    "(twin_sensor)" after two descriptions and cut passive_assoc's before its name."""
    result = trackfuse("list")
    assert result.returncode == 0
    assert all(name in result.stdout for name in experiments.BUILTIN)
    data = json.loads(trackfuse("list", "--format", "json").stdout)
    assert [d["name"] for d in data][:len(experiments.BUILTIN)] == list(experiments.BUILTIN)
    for item in data[:len(experiments.BUILTIN)]:
        assert item["reference"] == experiments.BUILTIN[item["name"]]
        doc = importlib.import_module(item["reference"]).__doc__
        summary = " ".join(doc.split("\n\n")[0].split()).replace("``", "")
        assert summary.startswith(item["description"]) and item["description"]
        assert f"({item['name']})" not in item["description"]  # the listing names it
        assert " ".join(item["description"].split()) in " ".join(result.stdout.split())
    refused = trackfuse("list", "--format", "yaml")
    assert refused.returncode == 2 and refused.stderr.startswith("error: --format yaml")


def test_yaml_template_writes_lists_and_strings_as_yaml(twin):
    data = yaml.safe_load(config_template(twin, "twin_sensor"))
    assert data["params"]["target.position"] == [0.0, 128558.0, 4000.0]
    assert data["params"]["platform.motion"] == "orbit" and data["experiment"] == "twin_sensor"

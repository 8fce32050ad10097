"""The Table 3 robustness study (examples/esm_radar_robustness_lhs.{yaml,py}): the config
holds the design its recipe draws, inside the declared ranges, on a seed no other config
uses, and the verdicts read the run's counts against the paper's as two samples."""

from __future__ import annotations

import importlib.util
import math
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml
from conftest import cli_env

from trackfuse.config import load

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "examples" / "esm_radar_robustness_lhs.yaml"
SCRIPT = ROOT / "examples" / "esm_radar_robustness_lhs.py"


def _study():
    spec = importlib.util.spec_from_file_location("esm_radar_robustness_lhs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


STUDY = _study()


def test_the_config_holds_the_design_its_recipe_draws_under_both_radar_models():
    sweep = load(CONFIG).sweep
    settings = STUDY.design()
    assert len(settings) == STUDY.N_SETTINGS
    assert sweep["radar.factor_model"] == ["derived"] * 40 + ["table"] * 40
    for key in settings.columns:
        assert [float(v) for v in sweep[key]] == [float(v) for v in settings[key]] * 2, key


def test_every_setting_lies_in_its_declared_range():
    s = STUDY.design()
    peak_g = s["snake.amplitude"] * (2 * math.pi / s["snake.period"]) ** 2 / STUDY.G
    assert peak_g.between(0.99, 4.01).all()  # the period is rounded to 0.1 s
    for key, (low, high, _) in STUDY.RANGES.items():
        if key in s:
            slack = 0.01 * high if key in ("snake.amplitude", "geometry.baseline") else 0
            assert s[key].between(low - slack, high + slack).all(), key
    # a Latin hypercube: each integer-valued key reaches both ends of its range
    assert {3, 10} <= set(s["alpha.window"])
    assert s["scan.count"].min() <= 31 and s["scan.count"].max() >= 95


def test_its_seed_is_used_by_no_other_config():
    seeds = {}
    for path in [*ROOT.glob("configs/**/*.yaml"), *ROOT.glob("examples/**/*.yaml")]:
        raw = yaml.safe_load(path.read_text())
        if isinstance(raw, dict) and "seed" in raw:
            seeds.setdefault(raw["seed"], []).append(path.name)
    assert seeds[load(CONFIG).seed] == [CONFIG.name]


def test_verdicts_compare_our_count_with_the_papers_as_two_samples(tmp_path):
    rows = [(0, "derived", "improved", 500, 370 / 500), (0, "derived", "traditional", 500,
                                                        276 / 500),
            (1, "table", "improved", 500, 499 / 500), (1, "table", "traditional", 4000,
                                                       0.5275)]
    pd.DataFrame([{"point": p, "radar.factor_model": m, "algorithm": a, "metric": "correct",
                   "n": n, "mean": mean, "ci_low": 0.0, "ci_high": 1.0}
                  for p, m, a, n, mean in rows]).to_csv(tmp_path / "summary.csv", index=False)
    table = STUDY.judged(tmp_path).set_index(["point", "algorithm"])
    assert table.loc[(0, "improved"), "consistent"]
    assert table.loc[(0, "traditional"), "consistent"]
    assert not table.loc[(1, "improved"), "consistent"]  # +25.8 points
    # 2110 of 4000 against 276 of 500: outside our own Wilson interval, yet consistent
    assert table.loc[(1, "traditional"), "correct"] == 2110
    assert table.loc[(1, "traditional"), "consistent"]
    assert "consistent under 1 of 1 settings" in STUDY.shares(table.reset_index())


@pytest.mark.slow
def test_judge_runs_on_a_small_run_and_draws_its_figure(tmp_path):
    env = cli_env()
    proc = subprocess.run([sys.executable, "-m", "trackfuse", "run", str(CONFIG), "--trials",
                           "4", "--out", str(tmp_path), "--workers", "1", "--no-plots",
                           "--no-progress"], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    folder = re.search(r"^wrote (.+?): \d+ rows", proc.stdout, flags=re.M).group(1)
    png = tmp_path / "lhs.png"
    proc = subprocess.run([sys.executable, str(SCRIPT), "judge", folder, "--png", str(png)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 4 and all("of 40 settings" in line for line in lines)
    assert png.stat().st_size > 0

"""Figures and tables of passive_sd runs (trackfuse/experiments/passive_sd/report.py,
docs/papers/sd_assignment.md): every figure declared and drawn by the report kit to the
journal rules, the exact optimum beside the methods, the stopping gap where it is set."""

from pathlib import Path

import matplotlib
import numpy as np
import pytest
from figure_checks import alike_legend_entries, internal_names, journal_problems

from trackfuse import harness
from trackfuse.config import load
from trackfuse.experiments import get
from trackfuse.experiments.passive_sd import LOOKS, report
from trackfuse.reportkit.style import context

EXPERIMENT = get("passive_sd")
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def geometry_run(tmp_path_factory):
    """Two target counts by two baselines, 4 trials each."""
    return harness.run_data(tmp_path_factory.mktemp("sd"), "passive_sd",
                            {"noise.sigma": 0.01, "sd.max_gap": 0.02},
                            {"targets.n": [4, 6], "sensor3.baseline": [0.05, 20.0]},
                            trials=4, seed=3)


def drawn(run, names):
    with context():
        return report.figures(run, names)


def test_every_figure_meets_the_journal_rules(geometry_run):
    """Every declared figure is drawn at a slot's width, fits a page, keeps its text inside
    the canvas and at least 7 pt, has a short legend, TrueType fonts, no internal name, and
    one panel per target count titled by its symbol."""
    figs = drawn(geometry_run, list(EXPERIMENT.figures))
    assert set(figs) == set(EXPERIMENT.figures)
    for name, fig in figs.items():
        assert isinstance(fig, matplotlib.figure.Figure), (name, fig)
        assert journal_problems(fig) == [], name
        assert alike_legend_entries(fig) == [], name
        assert internal_names(fig, EXPERIMENT) == [], name
        assert [ax.get_title() for ax in fig.axes if ax.get_visible()] == ["N = 4", "N = 6"]


def test_the_exact_optimum_is_dashed_beside_both_methods(geometry_run):
    """accuracy draws the relaxation and the two-sensor assignment in their looks and the
    exact S-D optimum dashed, at the summary's means (in %)."""
    fig = drawn(geometry_run, ["accuracy"])["accuracy"]
    labels = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    assert {LOOKS[n].label for n in ("sd_lagrangian", "exact_2d", "sd_exact")} <= set(labels)
    assert labels[LOOKS["sd_exact"].label].get_linestyle() == "--"
    s = geometry_run.summary
    want = s[(s["metric"] == "accuracy") & (s["algorithm"] == "exact_2d")
             & (s["targets.n"] == 4)].sort_values("sensor3.baseline")["mean"]
    assert np.allclose(labels[LOOKS["exact_2d"].label].get_ydata(), 100 * want.to_numpy())


def test_the_duality_gap_figure_marks_the_configured_stopping_gap(geometry_run):
    fig = drawn(geometry_run, ["duality_gap"])["duality_gap"]
    levels = [ln.get_ydata()[0] for ln in fig.axes[0].get_lines()
              if ln.get_label() == "stopping gap"]
    assert levels == [pytest.approx(0.02)]


def test_without_a_swept_key_the_figures_say_why(tmp_path):
    run = harness.run_data(tmp_path, "passive_sd", {"targets.n": 3}, trials=2, seed=1)
    figs = drawn(run, list(EXPERIMENT.figures))
    assert all(isinstance(f, str) and "\n" not in f for f in figs.values())


def test_the_shipped_configs_draw_against_the_baseline():
    """Both shipped configs sweep the sensor-3 baseline: every figure's x."""
    for path in (ROOT / "configs/passive_3sensor.yaml",
                 ROOT / "configs/ci/passive_3sensor_ci.yaml"):
        cfg = load(path)
        assert report.x_key({"sweep": cfg.sweep}) == "sensor3.baseline", path


def test_versus_exact_summarises_the_relaxation_per_point(geometry_run):
    table = report.tables(geometry_run)["versus_exact"]
    assert list(table["point"]) == [0, 1, 2, 3]
    assert (table["trials"] == 4).all()
    assert table["at_opt"].between(0, 1).all() and (table["max_gap"] >= table["mean_gap"]).all()

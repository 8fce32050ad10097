"""twin_sensor's figures, drawn by the report kit, judged as a journal prints them: a slot's
width, a page's height, text inside the canvas and at least 7 pt, at most six legend entries,
TrueType fonts, no internal names; and what each figure must show (the paper's claim,
the bound, both panels of paper 000's Fig. 1)."""

from pathlib import Path

import numpy as np
import pytest
from figure_checks import internal_names, journal_problems
from matplotlib.collections import PolyCollection

from trackfuse import harness
from trackfuse.config import load
from trackfuse.experiments.twin_sensor import EXPERIMENT, LOOKS, report
from trackfuse.reportkit.style import context
from trackfuse.rundata import RunData

ROOT = Path(__file__).resolve().parents[1]
EVERY = ["nn/mgekf", "nn/ekf", "mspda_parallel/mgekf", "mspda_parallel/ekf",
         "mspda_sequential/mgekf", "mspda_sequential/ekf", "paper_approx/mgekf",
         "paper_approx/ekf", "ipda/mgekf"]


@pytest.fixture(scope="module")
def run_every(tmp_path_factory) -> RunData:
    """Every association with both filters (twin_sensor_orbit's eight curves) and IPDA,
    three clutter levels, short runs."""
    base = {**EXPERIMENT.defaults(), "algorithms": EVERY, "scan.count": 5}
    return harness.run_data(tmp_path_factory.mktemp("every"), EXPERIMENT, base,
                            {"clutter.mean": [0.0, 8.0, 15.0]}, trials=6, seed=3)


@pytest.fixture(scope="module")
def run_grid(tmp_path_factory) -> RunData:
    """twin_sensor_range's 3 x 3 grid (range cue x filter q), without clutter."""
    base = {**EXPERIMENT.defaults(), "algorithms": EVERY[2:4], "scan.count": 5}  # no IPDA
    return harness.run_data(tmp_path_factory.mktemp("grid"), EXPERIMENT, base,
                            {"init.sigma_range": [2000.0, 20000.0, 50000.0],
                             "filter.q": [0.0, 1.0, 900.0]}, trials=4, seed=3)


@pytest.fixture(scope="module")
def run_hard(tmp_path_factory) -> RunData:
    """twin_sensor_hard's zipped sweep (truth and filter q with clutter), short runs."""
    base = {**EXPERIMENT.defaults(), "algorithms": EVERY[2:5:2], "scan.count": 5,
            "clutter.model": "window", "clutter.window": 0.1}
    q = [0.0, 160000.0, 0.0, 900.0, 10000.0, 40000.0, 160000.0]
    return harness.run_data(tmp_path_factory.mktemp("hard"), EXPERIMENT, base,
                            {"target.q": q, "filter.q": q,
                             "clutter.mean": [0.0, 0.0, 40.0, 40.0, 40.0, 40.0, 40.0]},
                            trials=4, seed=3, sweep_mode="zip")


def _legend(fig) -> list[str]:
    return [t.get_text() for legend in fig.legends for t in legend.get_texts()]


@pytest.mark.parametrize("fixture", ["run_every", "run_grid", "run_hard"])
def test_every_figure_meets_the_journal_rules(fixture, request):
    """Every drawn figure: 3.5 or 7.16 in wide, at most 8.5 in tall (twin_sensor_range's
    nine time panels were 10.1 in), every text inside the canvas and at least 7 pt at that
    size, at most six legend entries (eight curves of four associations and two filters
    included), TrueType fonts, no internal name (config key, algorithm id, ASCII unit)."""
    run = request.getfixturevalue(fixture)
    with context():
        drawn = {name: fig for name, fig in report.figures(run, EXPERIMENT.figures).items()
                 if not isinstance(fig, str)}
        assert len(drawn) >= 3
        for name, fig in drawn.items():
            assert journal_problems(fig) == [], name
            assert internal_names(fig, EXPERIMENT) == [], name


def test_the_existence_figure_keeps_ipda_among_nine_algorithms(run_every):
    """Nine algorithms run, six legend entries at most: IPDA's curves, the figure's point,
    are kept."""
    fig = report.figures(run_every, ["existence_vs_clutter"])["existence_vs_clutter"]
    assert LOOKS["ipda/mgekf"].label in _legend(fig) and len(_legend(fig)) <= 6


def test_a_count_axis_has_integer_ticks(run_every):
    """The scan axis of a time figure is a count: ticks 1, 2, ..., never 2.5."""
    fig = report.figures(run_every, ["range_error_vs_time"])["range_error_vs_time"]
    fig.canvas.draw()
    ticks = fig.axes[0].get_xticks()
    inside = ticks[(ticks >= 1) & (ticks <= 5)]
    assert len(inside) >= 2 and np.allclose(inside, np.round(inside))


def test_the_range_figure_draws_the_bound_on_the_scans(run_every):
    """The square-root PCRLB is drawn in every panel on the same scans as the RMSE curves,
    in km, below the curves' scale's top."""
    fig = report.figures(run_every, ["range_error_vs_time"])["range_error_vs_time"]
    assert any("PCRLB" in t for t in _legend(fig))
    for ax in (a for a in fig.axes if a.get_visible()):
        bound = [ln for ln in ax.get_lines() if "PCRLB" in ln.get_label()]
        assert bound and list(bound[0].get_xdata()) == [1, 2, 3, 4, 5]
        assert 0.1 < float(np.max(bound[0].get_ydata())) < 100.0  # km, not m


def test_fig1_headline_draws_the_papers_scenario_beside_the_close_analogue(tmp_path):
    """Paper 000's Fig. 1 is flat at 0 % at the paper's scenario (the true result there):
    the headline puts the close geometry, where loss rises with clutter, beside it on one
    y axis; the paper's claim (below 5 % up to 9) is shaded in both panels, from 0 to 9
    false returns; only the paper's panel is titled "redrawn"."""
    pairs = ["paper_approx/mgekf", "mspda_parallel/mgekf"]
    paper = harness.run_data(tmp_path / "paper", EXPERIMENT,
                             {**EXPERIMENT.defaults(), "algorithms": pairs},
                             {"clutter.mean": [0.0, 5.0]}, trials=4, seed=1)
    close = load(ROOT / "configs" / "twin_sensor_close.yaml")
    analogue = harness.run_data(tmp_path / "close", EXPERIMENT,
                                {**close.params, "algorithms": pairs},
                                {"sensors.count": [1, 2], "clutter.mean": [0.0, 40.0]},
                                trials=4, seed=2)
    with context():
        fig = report.fig1_headline(paper, analogue)
        assert journal_problems(fig) == []
    left, right = fig.axes
    assert "redrawn" in left.get_title() and "redrawn" not in right.get_title()
    assert "analogue" in right.get_title() and "redrawn" not in fig.get_suptitle()
    assert left.get_shared_y_axes().joined(left, right)
    for ax in (left, right):
        claim = [c for c in ax.collections if isinstance(c, PolyCollection)
                 and c.get_label() == report.CLAIM_LABEL]
        assert len(claim) == 1, ax.get_title()
        x, y = claim[0].get_paths()[0].vertices.T
        assert (x.min(), x.max()) == (0.0, 9.0) and (y.min(), y.max()) == (0.0, 5.0)
    # the close run's one-sensor points are left out: each curve has one point per level
    labels = {LOOKS[n].label for n in pairs}
    for ax in (left, right):
        curves = [ln for ln in ax.get_lines() if ln.get_label() in labels]
        assert len(curves) == 2 and all(len(ln.get_xdata()) == 2 for ln in curves)


def test_curves_shifted_beside_equal_ones_stay_in_view(tmp_path):
    """configs/ci/twin_sensor_ci.yaml: every curve of the ablation lies at 0 %, so each is
    drawn a little beside the one it hides, and every one stays inside the x axis."""
    cfg = load(ROOT / "configs" / "ci" / "twin_sensor_ci.yaml")
    run = harness.run_data(tmp_path, EXPERIMENT, cfg.params, cfg.sweep, trials=cfg.trials,
                           seed=cfg.seed)
    with context():
        fig = report.figures(run, ["loss_vs_clutter_ablation"])["loss_vs_clutter_ablation"]
        fig.canvas.draw()
    for ax in (a for a in fig.axes if a.get_visible() and a.has_data()):
        low, high = sorted(ax.get_xlim())
        curves = [ln for ln in ax.get_lines() if ln.get_label() in _legend(fig)]
        for line in curves:
            x = np.asarray(line.get_xdata(), dtype=float)
            assert ((x >= low) & (x <= high)).all(), line.get_label()
        firsts = {round(float(ln.get_xdata()[0]), 9) for ln in curves}
        assert len(firsts) == len(curves)  # none hidden under another

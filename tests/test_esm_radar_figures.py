"""The ``esm_radar`` figures say what they draw: every curve with its interval and the
legend naming it, the references apart from each other and from chance, equal curves said to
coincide, titles and legends that follow the run, no panel without data."""

import copy

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.colors import to_rgb

from trackfuse import harness
from trackfuse.experiments.esm_radar import report
from trackfuse.plots.algorithms import look
from trackfuse.plots.style import context
from trackfuse.rundata import RunData

ALGORITHMS = ["traditional", "improved", "improved_static", "improved_3f", "chi2", "chi2_lrt"]
BANDED = "shaded band: 95 % Wilson interval"
BARRED = "error bar: 95 % Wilson interval, shifted sideways"
SAME = "chi-square reference, may abstain coincides with chi-square ML reference"



def house_figures(run: RunData, names: list[str]) -> dict:
    """The report's figures drawn as the report draws them: inside the house style."""
    with context():
        return report.figures(run, names)


@pytest.fixture(scope="module")
def curves(tmp_path_factory) -> RunData:
    """Ablations and references against separation (three values: two are categories),
    both radar-factor models."""
    return harness.run_data(tmp_path_factory.mktemp("curves"), "esm_radar",
                            {"algorithms": ALGORITHMS},
                            {"target.separation": [100.0, 300.0, 1000.0],
                             "radar.factor_model": ["table", "derived"]}, trials=6, seed=3)


@pytest.fixture(scope="module")
def baseline_only(tmp_path_factory) -> RunData:
    """The paper's baseline alone at the Table 3 setting (no dynamic weights)."""
    return harness.run_data(tmp_path_factory.mktemp("baseline"), "esm_radar",
                            {"algorithms": ["traditional"]}, None, trials=3, seed=1)


def _legend_texts(fig) -> list[str]:
    (legend,) = fig.legends
    return [t.get_text() for t in legend.get_texts()]


def test_every_curve_has_its_interval_and_the_legend_names_it(curves):
    """Banded (the paper's methods) or error bars (ablations, references: they were bare
    lines), and the legend says which interval each is."""
    for group in ("correct_rate_ablations", "correct_rate_references"):
        fig = house_figures(curves, [group])[group]
        names = [n for n in report.GROUPS[group] if n in ALGORITHMS]
        for ax in fig.axes:
            bands = {to_rgb(c.get_facecolor()[0]) for c in ax.collections
                     if isinstance(c, PolyCollection)}
            bars = {to_rgb(c.lines[0].get_color()) for c in ax.containers}
            assert len(bands) + len(bars) == len(names), group
            for name in names:
                assert to_rgb(look(name).colour) in (bands if look(name).emphasised else bars)
        assert {BANDED, BARRED} <= set(_legend_texts(fig)), group


def test_barred_curves_sit_beside_and_above_the_banded_one(curves):
    """An ablation at the paper's rate was hidden under its thick line: the barred curves'
    markers are drawn beside it and each other, above it, their data kept; and close to
    their setting (they were shifted about 15 % on the log axis, almost meeting 750 m from
    1000 m): a few % of x, the same on the page at every x."""
    fig = house_figures(curves, ["correct_rate_ablations"])["correct_rate_ablations"]
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    ax = fig.axes[0]
    (paper,) = [ln for ln in ax.get_lines() if ln.get_label() == look("improved").label]
    xs = [paper.get_transform().transform(paper.get_xydata())[:, 0]]
    for container in ax.containers:
        line = container.lines[0]
        assert list(line.get_xdata()) == [100.0, 300.0, 1000.0]
        assert line.get_zorder() > paper.get_zorder()
        shown = line.get_transform().transform(line.get_xydata())[:, 0]
        xs.append(shown)
        aside_pt = (shown - ax.transData.transform(line.get_xydata())[:, 0]) * 72 / fig.dpi
        assert np.ptp(aside_pt) < 1e-6 and 2.5 <= abs(aside_pt[0]) <= 3.5, aside_pt
    gaps = np.diff(np.sort(np.array(xs), axis=0), axis=0)
    assert len(xs) == 3 and (gaps >= 2.5 * fig.dpi / 72).all()


def test_references_and_chance_are_told_apart(curves, baseline_only, tmp_path):
    """"ML reference", "may abstain" and chance were three grey/black dashed lines: each
    has its own line style and marker, the references the same markers in both layouts."""
    fig = house_figures(curves, ["correct_rate_references"])["correct_rate_references"]
    ax = fig.axes[0]
    refs = {to_rgb(c.lines[0].get_color()): c.lines[0] for c in ax.containers}
    lines = [refs[to_rgb(look(n).colour)] for n in ("chi2", "chi2_lrt")]
    lines += [ln for ln in ax.get_lines() if ln.get_label().startswith("chance")]
    assert len({ln.get_linestyle() for ln in lines}) == 3
    assert len({ln.get_marker() for ln in lines}) == 3
    table = harness.run_data(tmp_path, "esm_radar", {"algorithms": ALGORITHMS}, None,
                             trials=3, seed=1)
    dots = house_figures(table, ["correct_rate_references"])["correct_rate_references"]
    markers = {to_rgb(c.lines[0].get_color()): c.lines[0].get_marker()
               for c in dots.axes[0].containers}
    assert [markers[to_rgb(look(n).colour)] for n in ("chi2", "chi2_lrt")] == \
        [ln.get_marker() for ln in lines[:2]]


def test_exactly_equal_curves_are_said_to_coincide(curves):
    rows = {"algorithm": ["chi2"] * 2 + ["chi2_lrt"] * 2, "x": [1.0, 2.0] * 2}
    same = pd.DataFrame({**rows, "mean": [1.0, 0.9, 1.0, 0.9]})
    apart = pd.DataFrame({**rows, "mean": [1.0, 0.9, 1.0, 0.8]})
    names = ["chi2", "chi2_lrt"]
    assert report._coincidences([("a", same), ("b", apart)], "x", names, 2) == [
        f"left panel: {SAME}"]
    assert report._coincidences([("a", same)], "x", names, 1) == [SAME]
    assert report._coincidences([("b", apart)], "x", names, 1) == []
    # in a figure: the two references of the left panel made equal (and unlike the paper's
    # methods), the legend says so above its entries
    run = copy.copy(curves)
    s = curves.summary.copy()
    left = (s["radar.factor_model"] == "table") & (s["metric"] == "correct")
    for name in names:
        s.loc[left & (s["algorithm"] == name), ["mean", "ci_low", "ci_high"]] = [0.6, 0.5, 0.7]
    run.__dict__["summary"] = s
    fig = house_figures(run, ["correct_rate_references"])["correct_rate_references"]
    (legend,) = fig.legends
    assert f"left panel: {SAME}" in legend.get_title().get_text().split("\n")


def test_titles_and_legends_follow_what_the_run_contains(baseline_only, tmp_path):
    """Not "ours" when ours was not run, not "Table 3 redrawn" for the baseline alone, not
    "Figs. 1-2 redrawn" nor "weaving" for straight tracks; the trajectory is drawn at the
    paper's weave where the run has it, though its first point flies straight."""
    methods = {"algorithms": ["traditional", "improved"]}
    weave = harness.run_data(tmp_path / "weave", "esm_radar", methods,
                             {"snake.amplitude": [0.0, 1000.0]}, trials=3, seed=2)
    title = house_figures(weave, ["correct_rate"])["correct_rate"].get_suptitle()
    assert "ours" not in title and "the paper's methods" in title
    at_weave = house_figures(weave, ["trajectory"])["trajectory"]
    assert "Figs. 1-2 redrawn" in at_weave.get_suptitle()
    assert "T1 (weaving)" in _legend_texts(at_weave)
    other = harness.run_data(tmp_path / "other", "esm_radar", methods,
                             {"snake.amplitude": [0.0, 500.0]}, trials=3, seed=2)
    straight = house_figures(other, ["trajectory"])["trajectory"]
    assert "redrawn" not in straight.get_suptitle() and "0 m" in straight.get_suptitle()
    assert not any("weaving" in t for t in _legend_texts(straight))
    assert "T1 (straight)" in _legend_texts(straight)
    title = house_figures(baseline_only, ["correct_rate"])["correct_rate"].get_suptitle()
    assert "redrawn" not in title and "baseline only" in title
    weaving = house_figures(baseline_only, ["trajectory"])["trajectory"]
    assert "Figs. 1-2 redrawn" in weaving.get_suptitle()
    assert "T1 (weaving)" in _legend_texts(weaving)


def test_no_panel_is_drawn_without_data(baseline_only):
    """Without a dynamic-weight algorithm the manoeuvre figure is its index panel alone (the
    range-weight panel was an empty axis), and no title promises a range weight."""
    figs = house_figures(baseline_only, ["manoeuvre", "trajectory"])
    (ax,) = figs["manoeuvre"].axes
    assert ax.has_data() and "range weight" not in figs["manoeuvre"].get_suptitle()
    titles = [a.get_title() for a in figs["trajectory"].axes]
    assert not any("index and range weight" in t for t in titles)

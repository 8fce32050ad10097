"""The ``esm_radar`` report: figures of every shipped config from a small real run, the
headline table, and the per-scan columns the per-scan figures read instead of re-simulating."""

import re
from pathlib import Path

import matplotlib.figure
import numpy as np
import pandas as pd
import pytest
from figure_checks import alike_legend_entries, internal_names, journal_problems
from matplotlib.collections import PolyCollection

from trackfuse import harness
from trackfuse.config import load
from trackfuse.experiments.esm_radar import EXPERIMENT, LOOKS, model, paper, report
from trackfuse.reportkit.style import context
from trackfuse.reports import HEADLINE_COLUMNS, VERDICTS
from trackfuse.rundata import RunData

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted(ROOT.glob("configs/esm_radar_*.yaml"))
UNIT = re.compile(r"\(.+\)")



def house_figures(run: RunData, names: list[str]) -> dict:
    """The report's figures drawn as the report draws them: inside the house style."""
    with context():
        return report.figures(run, names)


#: Table 3's config runs in the fast suite; the sweeps and ablations in the slow one.
PARAMS = [p if p.stem == "esm_radar_snake_cross" else pytest.param(p, marks=pytest.mark.slow)
          for p in CONFIGS]


@pytest.fixture(scope="module", params=PARAMS, ids=lambda p: p.stem)
def shipped_run(request, tmp_path_factory) -> RunData:
    """A shipped config run by the real runner with 6 trials per point."""
    cfg = load(request.param)
    return harness.run_data(tmp_path_factory.mktemp(request.param.stem), "esm_radar",
                            cfg.params, cfg.sweep, trials=6, seed=cfg.seed,
                            sweep_mode=cfg.sweep_mode)


def categorical(axis) -> bool:
    """An axis ticked with names (methods) rather than numbers: no unit to state."""
    fmt = axis.get_major_formatter()
    texts = [fmt(v, i) for i, v in enumerate(axis.get_majorticklocs())]
    return any(re.search(r"[a-df-z]", t) for t in texts)


def test_every_figure_of_every_shipped_config_meets_the_journal_rules(shipped_run):
    """Every figure is drawn (or a one-line reason says why: a group none of whose own
    algorithms was run) at a slot's width, fits a page, keeps its text inside the canvas
    and at least 7 pt, has a short legend, embeds TrueType fonts, says nothing of the host
    and shows no internal name; its methods' legend entries are told apart."""
    figs = house_figures(shipped_run, list(EXPERIMENT.figures))
    assert set(figs) == set(EXPERIMENT.figures)
    run_algorithms = set(shipped_run.params["algorithms"])
    for name, fig in figs.items():
        if isinstance(fig, str):
            assert "\n" not in fig, (name, fig)
            own = set(report.HISTORY_TESTS) if name == "history_rates" else \
                set(report.GROUPS[name]) - set(paper.PAPER_PAIR)
            assert not run_algorithms & own, (name, fig)
            continue
        assert journal_problems(fig) == [], name
        assert alike_legend_entries(fig) == [], name
        assert internal_names(fig, EXPERIMENT) == [], name


def _stars(fig) -> list:
    """The paper's values drawn (open stars with data)."""
    return [ln for ax in fig.axes for ln in ax.get_lines()
            if ln.get_marker() == "*" and len(ln.get_xdata())]


def test_main_figure_draws_the_papers_values_only_at_its_setting(shipped_run):
    """The paper's Table 3 values (74.0 % improved, 55.2 % traditional) are drawn as stars
    where some point of the run is at its setting (200 m, 1 %, the 1 km weave), else not;
    chance is drawn at 50 %."""
    fig = house_figures(shipped_run, ["correct_rate"])["correct_rate"]
    at = [p for p in shipped_run.points if paper.at_paper_setting(p)]
    paired = set(paper.PAPER_PAIR) & set(shipped_run.params["algorithms"])
    stars = _stars(fig)
    assert bool(stars) == bool(at and paired)
    assert {float(y) for ln in stars for y in ln.get_ydata()} <= {74.0, 55.2}
    assert any(np.allclose(ln.get_ydata(), 50.0) for ax in fig.axes for ln in ax.get_lines())


def test_curves_are_the_summary_means(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "improved"]},
                           {"target.separation": [100.0, 300.0, 1000.0, 2000.0]}, trials=10,
                           seed=3)
    fig = house_figures(run, ["correct_rate"])["correct_rate"]
    (line,) = _lines(fig, LOOKS["improved"].label)
    s = run.summary.query("metric == 'correct' and algorithm == 'improved'")
    np.testing.assert_allclose(line.get_ydata(), 100 * s.sort_values("target.separation")["mean"])
    assert fig.axes[0].get_xscale() == "log"
    ticks = [t.get_text() for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert "100" in ticks and "1000" in ticks  # plain numbers, not only powers of ten


def _lines(fig, prefix: str) -> list:
    return [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_label().startswith(prefix)]


def test_groups_without_their_algorithms_give_a_reason(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "improved"]},
                           None, trials=4, seed=1)
    figs = house_figures(run, list(EXPERIMENT.figures))
    assert isinstance(figs["correct_rate_references"], str)
    assert isinstance(figs["correct_rate_ablations"], str)
    assert isinstance(figs["correct_rate"], matplotlib.figure.Figure)


def test_headline_table_schema_verdicts_and_docs_links(shipped_run):
    table = report.tables(shipped_run)["paper_vs_reproduced"]
    assert tuple(table.columns) == HEADLINE_COLUMNS
    assert set(table["verdict"]) <= set(VERDICTS)
    assert (table["reason"].str.len() > 0).all() and not table["reason"].str.contains("\n").any()
    t3 = table[table["paper_item"] == "Table 3"]
    assert set(t3["algorithm"]) == {"improved", "traditional"} & set(
        shipped_run.params["algorithms"])
    assert ((t3["ci_low"] <= t3["reproduced"]) & (t3["reproduced"] <= t3["ci_high"])).all()
    inside = (t3["ci_low"] <= t3["paper_value"]) & (t3["paper_value"] <= t3["ci_high"])
    assert ((t3["verdict"] == "agrees") == inside).all()
    headings = re.findall(r"^#+ (.+)$", (ROOT / paper.DOCS).read_text(), flags=re.M)
    anchors = {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in headings}
    for link in set(table["docs"]):
        page, _, anchor = link.partition("#")
        assert page == paper.DOCS and anchor in anchors, link


def test_curve_claims_follow_the_paired_intervals(tmp_path):
    """With radar factors of their own noise the improved method is higher than the
    traditional one at 300 m by a wide margin, and both are near 1 at 3 km."""
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "improved"]},
                           {"target.separation": [300.0, 3000.0]}, trials=40, seed=2)
    table = paper.paper_vs_reproduced(run).set_index("quantity")
    close = table.loc[table.index.str.startswith("improved - traditional at the closest")]
    assert close["verdict"].iloc[0] == "agrees" and close["ci_low"].iloc[0] > 0
    always = table[table["paper_item"] == "Abstract"].iloc[0]
    # equal (both ~1) at 3 km: not shown higher there, but not shown lower either
    assert always["verdict"] == "inconclusive"
    assert always["ci_low"] <= 0 <= always["ci_high"]


def _outcomes(rates: dict[float, float | tuple[float, float]], n: int) -> pd.DataFrame:
    """0/1 outcomes (trial x point): at the i-th value the first ``round(n * rate)`` trials
    are 1 (nested across points and methods: strongly paired, as common random numbers), or
    for ``(rate, start)`` as many trials from ``round(n * start)`` on."""
    out = {}
    for i, r in enumerate(rates.values()):
        rate, start = r if isinstance(r, tuple) else (r, 0.0)
        k, first = round(n * rate), round(n * start)
        out[i] = ((np.arange(n) >= first) & (np.arange(n) < first + k)).astype(float)
    return pd.DataFrame(out)


def _gap_verdicts(trad: dict[float, float], imp: dict[float, float], n: int) -> dict:
    xs = [(x, i) for i, x in enumerate(trad)]
    rows = paper._gap_rows("Fig. 3", "fig-3-separation", "target.separation", "",
                            _outcomes(imp, n), _outcomes(trad, n), xs)
    return {key: row for key, row in zip(("closest", "narrows", "always"), rows, strict=True)}


def test_only_the_comparison_fixed_in_advance_decides_the_narrowing():
    """The `derived` shape: the gap is +0.01 at 50 m, +0.30 at 300 m and 0 at 2 km. The
    comparison fixed in advance, 50 m against 2 km, neither shows nor excludes a narrowing
    of 5 points, the paper item's declared margin: inconclusive. The widening from 50 to
    300 m, found by searching all pairs, is reported as exploration and decides nothing
    (it once decided the row, which then said "differs")."""
    rows = _gap_verdicts({50: 0.49, 300: 0.58, 2000: 1.0},
                         {50: (0.50, 0.2), 300: 0.88, 2000: 1.0}, 500)
    narrows = rows["narrows"]
    assert narrows["verdict"] == "inconclusive"
    assert narrows["quantity"].startswith("gap at 50 m minus gap at 2000 m")
    assert narrows["reproduced"] == pytest.approx(0.01)
    assert narrows["ci_low"] < 0 < 0.05 < narrows["ci_high"]
    assert "exploration only, not the verdict (searched 3 pairs): the gap widens from 50 m " \
        "to 300 m" in narrows["reason"]
    assert rows["closest"]["verdict"] == "inconclusive"  # +0.01: neither shown nor refuted
    monotone = _gap_verdicts({50: 0.5, 300: 0.7, 2000: 1.0}, {50: 0.9, 300: 0.95, 2000: 1.0},
                             500)
    assert [monotone[k]["verdict"] for k in ("closest", "narrows")] == ["agrees", "agrees"]


def test_the_narrowing_verdict_agrees_exactly_when_its_interval_lies_above_zero():
    """The pre-specified comparison (closest against widest) was judged on a Holm-adjusted
    p beside its unadjusted interval: at 40 and 50 trials the row showed an interval above 0
    and said inconclusive. The verdict now reads the interval it shows."""
    for n in (30, 40, 50, 60):
        row = _gap_verdicts({50: 0.5, 300: 0.5, 2000: 0.9}, {50: 0.6, 300: 0.55, 2000: 0.9},
                            n)["narrows"]
        assert row["reproduced"] == pytest.approx(0.1)
        assert (row["verdict"] == "agrees") == (row["ci_low"] > 0), n
        assert row["verdict"] in ("agrees", "inconclusive")
    assert row["verdict"] == "agrees"


def test_the_narrowing_verdict_differs_when_its_interval_lies_below_zero():
    """The mirror case: over 9 separations the gap widens from 0 at the closest to +0.1 at
    the widest: differs exactly when the interval excludes the declared narrowing of 5
    points."""
    xs = [50, 100, 150, 200, 300, 500, 800, 1200, 2000]
    imp = {x: 0.5 if x == 50 else 0.6 if x == 2000 else 0.55 for x in xs}
    for n in (40, 60, 100):
        row = _gap_verdicts(dict.fromkeys(xs, 0.5), imp, n)["narrows"]
        assert row["reproduced"] == pytest.approx(-0.1)
        assert (row["verdict"] == "differs") == (row["ci_high"] < 0.05), n  # the margin
        assert row["verdict"] in ("differs", "inconclusive")
    assert row["verdict"] == "differs" and "a narrowing of 5 points or more" in row["reason"]
    assert "exploration" not in row["reason"]  # the widening pair is the fixed one


def test_curve_verdicts_with_too_few_trials_never_say_differs():
    """30 trials and a small widening (+0.03 to +0.10): no verdict can be reached."""
    rows = _gap_verdicts({50: 0.5, 300: 0.5, 2000: 1.0}, {50: 0.53, 300: 0.6, 2000: 1.0}, 30)
    assert {k: r["verdict"] for k, r in rows.items()} == {
        "closest": "inconclusive", "narrows": "inconclusive", "always": "inconclusive"}


def test_always_higher_differs_only_where_the_improved_method_is_shown_lower():
    tied = _gap_verdicts({50: 0.5, 2000: 1.0}, {50: 0.8, 2000: 1.0}, 200)["always"]
    assert tied["verdict"] == "inconclusive"
    assert "2000 m (the same outcome in every trial)" in tied["reason"]
    lower = _gap_verdicts({50: 0.5, 2000: 0.9}, {50: 0.8, 2000: 0.6}, 200)["always"]
    assert lower["verdict"] == "differs" and "shown lower at 2000 m" in lower["reason"]


# --------------------------------------------------------------------------- per-scan columns


def test_per_scan_columns_are_written_once_per_trial_and_decode(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar",
                           {"algorithms": ["chi2", "improved", "improved_static"]}, None,
                           trials=5, seed=4)
    t = run.trials
    first = t[t["algorithm"] == "chi2"]
    assert first["alpha_per_scan"].notna().all()
    assert t.loc[t["algorithm"] != "chi2", "alpha_per_scan"].isna().all()
    assert t.loc[t["algorithm"] != "improved", "range_weight_per_scan"].isna().all()
    imp = t[t["algorithm"] == "improved"]
    a1 = model.decode_series(imp["range_weight_per_scan"])
    assert a1.shape == (5, EXPERIMENT.defaults()["scan.count"])
    np.testing.assert_allclose(a1.mean(axis=1), imp["range_weight_mean"], atol=2e-3)
    alpha = model.decode_series(first["alpha_per_scan"])
    np.testing.assert_allclose(np.nanmax(alpha, axis=1), first["alpha_peak"], rtol=5e-3)


def test_trajectory_places_the_esm_track_on_the_truth_without_noise(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"noise.scale": 0.0}, None, trials=2,
                           seed=4)
    errors = model.decode_series(run.trials["esm_range_error_per_scan_m"].dropna())
    assert np.all(np.abs(errors) <= 0.5)  # written to the metre
    fig = house_figures(run, ["trajectory"])["trajectory"]
    (esm,) = _lines(fig, "ESM TDOA-DF location")
    t = model.esm_times(run.point_params(0))
    truth = model.scenario(run.point_params(0)).states(t)[0][:, model.TRUE_TRACK] / 1e3
    np.testing.assert_allclose(esm.get_xydata(), truth, atol=1e-3)


def test_per_scan_figures_never_simulate(shipped_run, monkeypatch):
    """trajectory and manoeuvre read the run folder only: the report module holds no
    reference to the simulator, and drawing works with the simulator disabled."""
    for name in ("simulate", "run_batch", "run_trial", "evaluate", "differences",
                 "trial_streams", "manoeuvre_alpha"):
        assert not hasattr(report, name), name

    def refuse(*args, **kwargs):
        raise AssertionError("the report re-ran the simulation")

    for name in ("simulate", "run_batch", "evaluate", "manoeuvre_alpha"):
        monkeypatch.setattr(model, name, refuse)
    figs = house_figures(shipped_run, ["trajectory", "manoeuvre"])
    assert all(isinstance(f, matplotlib.figure.Figure) for f in figs.values())


def test_runs_without_per_scan_columns_say_why(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["improved"]}, None,
                           trials=2, seed=1)
    old = run.trials.drop(columns=[c for c in run.trials if c.endswith("_per_scan")
                                   or "_per_scan_" in c])
    run.__dict__["trials"] = old
    figs = house_figures(run, ["trajectory", "manoeuvre"])
    assert figs == {"trajectory": report.NO_SERIES, "manoeuvre": report.NO_SERIES}


def test_headline_rows_name_the_radar_factor_model(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "improved"]},
                           {"target.separation": [50.0, 2000.0],
                            "radar.factor_model": ["table", "derived"]}, trials=10, seed=2)
    table = paper.paper_vs_reproduced(run)
    close = table[table["quantity"].str.startswith("improved - traditional at the closest")]
    models = [re.search(r"radar factors '(\w+)'", q)[1] for q in close["quantity"]]
    assert sorted(models) == ["derived", "table"]  # one row, and one verdict, per model


def test_straight_flight_is_not_compared_with_the_papers_table_3(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "improved"]},
                           {"snake.amplitude": [0.0, 1000.0]}, trials=4, seed=2)
    t3 = paper.paper_vs_reproduced(run).query("paper_item == 'Table 3'")
    assert len(t3) == 2 and t3["quantity"].str.contains("1 km weave").all()


def test_manoeuvre_table_gives_the_index_and_range_weight_per_point(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar",
                           {"algorithms": ["traditional", "improved"]},
                           {"snake.amplitude": [0.0, 1000.0]}, trials=20, seed=5)
    table = report.manoeuvre_table(run.summary, run.config).set_index("snake.amplitude")
    s = run.summary.query("metric == 'alpha_mean' and algorithm == 'traditional'")
    np.testing.assert_allclose(table["alpha_mean"], s["mean"])
    assert (table["alpha_mean_ci_low"] <= table["alpha_mean"]).all()
    assert table.loc[1000.0, "alpha_mean"] > 10 * table.loc[0.0, "alpha_mean"]  # sees the weave
    assert table.loc[1000.0, "improved_range_weight"] < table.loc[0.0, "improved_range_weight"]


ABLATION_WORDS = {"traditional_5f": "5 factors", "improved_static": "static weights",
                  "improved_no_range": "no range factor", "improved_3f": "3 factors",
                  "improved_l2": "L2 membership"}


def test_ablation_caption_names_only_ablations_every_drawing_config_runs():
    """The caption is shared by every run: an ablation it names must be drawn in each
    shipped config that draws the figure (snake_cross and separation do not run
    improved_no_range)."""
    assert set(ABLATION_WORDS) == set(report.GROUPS["correct_rate_ablations"][1:])
    caption = EXPERIMENT.figures["correct_rate_ablations"].caption
    for path in CONFIGS:
        cfg = load(path)
        if cfg.figures != "all" and "correct_rate_ablations" not in cfg.figures:
            continue
        for name, words in ABLATION_WORDS.items():
            assert words not in caption or name in cfg.params["algorithms"], (path.stem, name)


def test_two_settings_are_drawn_as_categories_not_joined(shipped_run):
    """"No weave" and "weave" (and the two d/λ) were joined by a line as if a trend ran
    between them: a swept value with two settings is a category, each method's rate a
    marker with its error bar and no line, ticked with the setting's name."""
    x, categories = report.rate_axis(shipped_run)
    if not categories:
        return
    fig = house_figures(shipped_run, ["correct_rate"])["correct_rate"]
    labels = {LOOKS[n].label for n in report.GROUPS["correct_rate"]}
    for ax in (a for a in fig.axes if a.get_visible()):
        methods = [ln for ln in ax.get_lines() if ln.get_label() in labels]
        assert methods and all(ln.get_linestyle() == "None" for ln in methods)
        assert ax.containers  # each rate with its error bar
        assert not any(isinstance(c, PolyCollection) for c in ax.collections)  # no band
    ticks = [t.get_text() for t in fig.axes[-1].get_xticklabels()]
    if x == "snake.amplitude":
        assert ticks == ["no weave", "1 km weave"]


def test_history_rates_are_the_trials_outcomes_with_the_counting_design_rate(tmp_path):
    """The false- and missed-association panels are each method's share of trials that
    chose a wrong radar track / none (missed only for the tests that may abstain), and the
    counting test's binomial design false-association rate is a level in the false panel
    alone."""
    names = ["traditional", "improved", "chi2", "counting", "sprt"]
    params = {"algorithms": names, "counting.window": 10, "history.alpha": 0.05}
    run = harness.run_data(tmp_path, "esm_radar", params,
                           {"target.separation": [0.0, 50.0, 200.0]}, trials=8, seed=5)
    fig = house_figures(run, ["history_rates"])["history_rates"]
    assert journal_problems(fig) == [] and internal_names(fig, EXPERIMENT) == []
    correct, wrong, missed = (ax for ax in fig.axes if ax.get_visible())
    t = run.trials[run.trials["algorithm"] == "counting"].sort_values(["target.separation",
                                                                        "trial"])
    by_x = t.groupby("target.separation")
    false_rate = by_x.apply(lambda g: ((g["decided"] == 1) & (g["correct"] == 0)).mean())
    (line,) = [ln for ln in wrong.get_lines() if ln.get_label() == LOOKS["counting"].label]
    np.testing.assert_allclose(line.get_ydata(), 100 * false_rate.to_numpy())
    missed_labels = {ln.get_label() for ln in missed.get_lines()}
    assert LOOKS["sprt"].label in missed_labels and LOOKS["improved"].label not in missed_labels
    design = 100 * report.counting_design_rate(run.params)
    assert 0 < design <= 5.0
    levels = [ax for ax in (correct, wrong, missed) for ln in ax.get_lines()
              if ln.get_linestyle() == ":" and np.allclose(ln.get_ydata(), design)]
    assert levels == [wrong]


def test_history_rates_say_why_without_a_history_test(tmp_path):
    run = harness.run_data(tmp_path, "esm_radar", {"algorithms": ["traditional", "chi2"]},
                           {"target.separation": [0.0, 50.0, 200.0]}, trials=2, seed=5)
    fig = house_figures(run, ["history_rates"])["history_rates"]
    assert isinstance(fig, str) and "\n" not in fig

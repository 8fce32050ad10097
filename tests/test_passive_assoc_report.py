"""The ``passive_assoc`` report on every shipped config: figures drawn from a small real run
(no text overlap, inside the canvas, units, the paper's layout) and the headline table."""

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from figure_checks import (
    alike_legend_entries,
    inside_canvas,
    smallest_printed_text,
    text_overlaps,
)
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex
from matplotlib.text import Text

from trackfuse import harness
from trackfuse.config import load
from trackfuse.experiments.passive_assoc import EXPERIMENT, report
from trackfuse.plots.algorithms import look
from trackfuse.plots.style import context
from trackfuse.reported import PASSIVE_ASSOC
from trackfuse.reports import HEADLINE_COLUMNS, VERDICTS
from trackfuse.rundata import RunData
from trackfuse.stats import bootstrap_t_mean_intervals

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted(ROOT.glob("configs/passive_*.yaml"))
UNIT = re.compile(r"\(.+\)", re.S)  # a unit in brackets, over 1 or 2 lines
#: Small versions of the shipped configs: fewer runs, a smaller operation budget (checkpoints
#: above it are ignored, the budget itself is scored), and the scale study's points above
#: 50 targets left out.
SMALL = {"pga.ops": 200}


#: The paper's own config runs in the fast suite; the other studies' configs in the slow one.
PARAMS = [p if p.stem == "passive_association" else pytest.param(p, marks=pytest.mark.slow)
          for p in CONFIGS]


@pytest.fixture(scope="module", params=PARAMS, ids=lambda p: p.stem)
def shipped_run(request, tmp_path_factory) -> RunData:
    cfg = load(request.param)
    params = {**cfg.params, **SMALL}
    sweep = {k: [v for v in vals if not (k == "targets.n" and v > 50)]
             for k, vals in cfg.sweep.items()}
    return harness.run_data(tmp_path_factory.mktemp(request.param.stem), "passive_assoc",
                            params, sweep, trials=3, seed=cfg.seed, sweep_mode=cfg.sweep_mode)


def drawn(fig):
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig


def _column_xlabel(fig, ax) -> str:
    """The x label of ``ax``'s column: its own, or the one under the column's lowest panel."""
    return " ".join(a.get_xlabel() for a in fig.axes
                    if np.isclose(a.get_position().x0, ax.get_position().x0))


def test_every_figure_of_every_shipped_config_is_drawn_or_explained(shipped_run):
    figs = report.figures(shipped_run, list(EXPERIMENT.figures))
    assert set(figs) == set(EXPERIMENT.figures)  # nothing silently left out
    swept = shipped_run.sweep
    assert isinstance(figs["noise"], str) == ("noise.sigma" not in swept)
    # scale: one curve per N, so only when N is the one swept key (passive_noise sweeps sigma)
    assert isinstance(figs["scale"], str) == (set(swept) - {"algorithms"} != {"targets.n"})
    for name, fig in figs.items():
        if isinstance(fig, str):
            assert fig and "\n" not in fig
            continue
        drawn(fig)
        assert text_overlaps(fig) == [], name
        assert inside_canvas(fig), name
        assert alike_legend_entries(fig) == [], name
        assert fig.get_suptitle().count("\n") <= 1, name
        supy = fig._supylabel.get_text() if fig._supylabel else ""
        for ax in (a for a in fig.axes if a.has_data()):
            assert UNIT.search(_column_xlabel(fig, ax)), (name, _column_xlabel(fig, ax))
            row = [a.get_ylabel() for a in fig.axes
                   if np.isclose(a.get_position().y0, ax.get_position().y0)]
            assert UNIT.search(ax.get_ylabel() or supy or " ".join(row)), (name, row)


def test_fig2_layout_one_column_per_target_count(shipped_run):
    fig = report.figures(shipped_run, ["convergence"])["convergence"]
    if isinstance(fig, str):
        assert "checkpoint" in fig  # the noise study scores one checkpoint only
        return
    targets = shipped_run.sweep["targets.n"]
    panels = [ax for ax in fig.axes if ax.has_data()]
    assert len(panels) == len(shipped_run.points)
    assert fig.get_suptitle().startswith("Paper 002 Fig. 2 redrawn:")  # all at its setting
    titles = [ax.get_title() for ax in panels[:len(targets)]]
    assert [int(re.match(r"N = (\d+)", t).group(1)) for t in titles] == targets
    paper = look("pga_paper")
    for ax in panels:
        lines = {ln.get_label(): ln for ln in ax.get_lines()}
        assert lines[paper.label].get_linewidth() > 1.5  # the paper's PGA emphasised
        assert lines[paper.label].get_color() == paper.colour
        assert any(lab.startswith(look("exact").label) for lab in lines)
        assert ax.get_ylim() == panels[0].get_ylim()  # one scale for every panel


def test_every_log_axis_says_so_in_its_label(shipped_run):
    """A log axis says 'log scale' in its label; a symlog one (which reaches 0) says
    'symlog' and where it is linear."""
    for name, fig in report.figures(shipped_run, list(EXPERIMENT.figures)).items():
        if isinstance(fig, str):
            continue
        for ax in (a for a in fig.axes if a.has_data()):
            for scale, label in ((ax.get_xscale(), _column_xlabel(fig, ax)),
                                 (ax.get_yscale(), ax.get_ylabel())):
                assert scale != "log" or "log scale" in label, (name, label)
                assert scale != "symlog" or ("symlog" in label and "linear" in label), \
                    (name, label)


def _marker_room(fig) -> float:
    """Least room (pixels) between a drawn marker's edge and its panel's edges; < 0 when a
    marker is cut by a spine."""
    drawn(fig)
    room = []
    for ax in fig.axes:
        for line in (ln for ln in ax.get_lines() if ln.get_marker() not in (None, "None", "")):
            xy = ax.transData.transform(np.c_[line.get_xdata(), line.get_ydata()])
            radius = (line.get_markersize() + line.get_markeredgewidth()) / 2 * fig.dpi / 72
            box = ax.bbox
            room += [xy[:, 0].min() - box.x0 - radius, box.x1 - xy[:, 0].max() - radius,
                     xy[:, 1].min() - box.y0 - radius, box.y1 - xy[:, 1].max() - radius]
    return min(room)


def test_convergence_markers_are_drawn_whole(shipped_run):
    """The first (0) and last checkpoints' markers, and rates of 0 or 1, clear the spines."""
    for name, fig in report.figures(shipped_run, ["convergence", "at_optimum"]).items():
        if not isinstance(fig, str):
            assert _marker_room(fig) >= 0, name


@pytest.fixture(scope="module")
def random_run(tmp_path_factory) -> RunData:
    """The scale study's shape: random scenes, 4 target counts, checkpoints past 0."""
    return harness.run_data(tmp_path_factory.mktemp("random"), "passive_assoc",
                            {"scene.mode": "random", "pga.ops": 200,
                             "pga.checkpoints": [20, 50, 200],
                             "algorithms": ["exact", "pga_paper", "pga_evict"]},
                            {"targets.n": [5, 10, 20, 50]}, trials=2, seed=5)


@pytest.mark.slow
def test_checkpoints_past_0_fill_log_axes_in_rows_legible_7_inches_wide(random_run):
    """No empty stretch from 0 to the first checkpoint: a log axis ticked at the checkpoints,
    which span it; at most 3 panels a row; no text under 7 pt when printed 7 in wide; the
    title does not call random scenes paper 002's Fig. 2."""
    for name in ("convergence", "at_optimum"):
        fig = drawn(report.figures(random_run, [name])[name])
        panels = [ax for ax in fig.axes if ax.get_visible()]
        assert len(panels) == 4
        assert len({round(ax.get_position().y0, 3) for ax in panels}) == 2  # 3 + 1
        for ax in panels:
            assert ax.get_xscale() == "log"
            low, high = ax.get_xlim()
            assert [t for t in ax.get_xticks() if low <= t <= high] == [20, 50, 200]
            ends = ax.transAxes.inverted().transform(ax.transData.transform([[20, 0], [200, 0]]))
            assert ends[0, 0] < 0.1 and ends[1, 0] > 0.9
        texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
        assert min(t.get_fontsize() for t in texts) * 7 / fig.get_figwidth() >= 7, name
        assert _marker_room(fig) >= 0 and text_overlaps(fig) == [] and inside_canvas(fig)
        title = fig.get_suptitle()
        assert "Fig. 2 redrawn" not in title and title.startswith("No paper figure"), title
        assert "M1-MN scenes" in title and "N = 5, 7, 10" in title


def test_title_marks_the_panels_at_fig2_setting_when_only_some_are(tmp_path):
    """8 targets is not one of Fig. 2's counts: only the 5-target panel is marked as at its
    setting, and the title points to the mark."""
    mixed = harness.run_data(tmp_path, "passive_assoc",
                             {"pga.ops": 50, "pga.checkpoints": [0, 50],
                              "algorithms": ["exact", "pga_paper"]},
                             {"targets.n": [5, 8]}, trials=2, seed=1)
    for name, fig in report.figures(mixed, ["convergence", "at_optimum"]).items():
        assert f"panels marked '{report.FIG2_MARK}'" in fig.get_suptitle(), name
        titles = [ax.get_title() for ax in fig.axes if ax.has_data()]
        assert [t.endswith(report.FIG2_MARK) for t in titles] == [True, False], titles


def test_scale_axis_is_linear_for_few_random_targets(tmp_path):
    run = harness.run_data(tmp_path, "passive_assoc", {"pga.ops": 50, "scene.mode": "random",
                           "pga.checkpoints": [50], "algorithms": ["exact", "pga_paper"]},
                           {"targets.n": [5, 7, 10]}, trials=2, seed=1)
    fig = report.figures(run, ["scale"])["scale"]
    for ax in fig.axes:
        assert ax.get_xscale() == "linear"
        np.testing.assert_array_equal(ax.get_xticks(), [5, 7, 10])
    # N is a real axis here: the paper's PGA is one curve through the three N
    joined = [line for line in fig.axes[2].get_lines()
              if line.get_label() == look("pga_paper").label]
    assert len(joined) == 1 and joined[0].get_linestyle() == "-"
    np.testing.assert_array_equal(joined[0].get_xdata(), [5, 7, 10])


@pytest.fixture(scope="module")
def scene_run(tmp_path_factory) -> RunData:
    """The paper's scenes M1-M5, M1-M7, M1-M10 with a thin variant (pga_repair)."""
    return harness.run_data(tmp_path_factory.mktemp("scenes"), "passive_assoc",
                            {"pga.ops": 50, "pga.checkpoints": [50],
                             "algorithms": ["exact", "pga_paper", "pga_repair"]},
                            {"targets.n": [5, 7, 10]}, trials=3, seed=1)


def test_paper_scenes_are_categories_whose_points_are_not_joined(scene_run):
    """5, 7 and 10 targets are different fixed scenes of the paper: one tick per scene
    labelled with its N, and no line runs from one scene to the next (the exact optimum's
    dashed level stays inside its scene's slot)."""
    fig = drawn(report.figures(scene_run, ["scale"])["scale"])
    for ax in fig.axes:
        assert list(ax.get_xticks()) == [0, 1, 2]
        assert [t.get_text() for t in ax.get_xticklabels()] == ["5", "7", "10"]
        for line in ax.get_lines():
            if line.get_linestyle() not in ("None", "none", "") and len(line.get_xdata()) > 1:
                assert np.ptp(line.get_xdata()) < 1, (ax.get_ylabel(), line.get_label())


def test_every_drawn_gap_has_its_interval_and_an_open_one_an_arrow(scene_run, monkeypatch):
    """Every PGA variant in the gap panel, the thin pga_repair too, gets interval bars; an
    infinite upper end is drawn as an arrow to the panel's top, and the notes above the
    legend say what the arrow means and why the bound is infinite."""
    metrics = report.checkpoint_metrics

    def one_open(trials, config):
        table = metrics(trials, config).assign(gap_ci_low=0.0)
        table["gap_ci_high"] = table["gap"] + 1.0  # 3 runs leave most upper ends open
        at = (table["algorithm"] == "pga_repair") & (table["targets.n"] == 7)
        table.loc[at, ["gap", "gap_ci_low", "gap_ci_high", "at_opt"]] = [0.2, 0.0, np.inf, 2 / 3]
        return table

    monkeypatch.setattr(report, "checkpoint_metrics", one_open)
    fig = drawn(report.figures(scene_run, ["scale"])["scale"])
    gap = fig.axes[1]
    arrows = [t for t in gap.texts if t.get_gid() == report.OPEN_ARROW]
    assert len(arrows) == 1
    assert arrows[0].xy[1] == 1.0 and arrows[0].xycoords == ("data", "axes fraction")
    assert arrows[0].xyann[0] == pytest.approx(1 + report.SCENE_SPREAD)  # pga_repair at N = 7
    bar_colours = {to_hex(c.get_color()[0]) for c in gap.collections}
    assert {to_hex(look(n).colour) for n in ("pga_paper", "pga_repair")} <= bar_colours
    notes = fig.legends[-1].get_title().get_text()
    assert "arrow to the top: no upper end" in notes and "only 1 of 3 runs missed J*" in notes


def test_scale_time_is_the_median_of_the_trials_wall_times(tmp_path):
    """The solve-time curve is the median of timings.csv's per-trial times (a few slow
    runs on a shared machine pull the mean up)."""
    run = _scale_run(tmp_path)
    fig = report.figures(run, ["scale"])["scale"]
    times = pd.read_csv(run.path / "timings.csv")
    exact = times[times["algorithm"] == "exact"].groupby("targets.n")["solve_time_s"].median()
    line = next(x for x in fig.axes[0].get_lines() if x.get_label() == look("exact").label)
    np.testing.assert_allclose(line.get_ydata(), 1e3 * exact.to_numpy())
    assert "median" in fig.axes[0].get_ylabel()


LONG_CPU = "Intel(R) Xeon(R) Platinum 8480+ Processor @ 2.50GHz with a very long model name"


def test_scale_figure_carries_no_host_text_and_stays_inside_its_canvas(tmp_path, monkeypatch):
    """The host's CPU model and worker count are provenance, not drawing: a run recorded on
    a CPU with a long name draws the same texts, all inside the canvas."""
    monkeypatch.setattr("trackfuse.environment.platform.processor", lambda: LONG_CPU)
    run = _scale_run(tmp_path)
    run.manifest["cpu"] = [{**c, "model": LONG_CPU} for c in run.manifest["cpu"]]
    run.manifest["workers"] = 1
    fig = drawn(report.figures(run, ["scale"])["scale"])
    texts = " ".join(t.get_text() for t in fig.findobj(Text))
    assert "Xeon" not in texts and "workers" not in texts and "EPYC" not in texts
    assert inside_canvas(fig) and text_overlaps(fig) == []


@pytest.mark.slow
def test_every_figure_prints_legibly_one_page_wide(shipped_run):
    """Printed 7.16 in wide (a two-column page), no text of any figure is under 6.5 pt and
    none overlaps another."""
    with context():
        figs = report.figures(shipped_run, list(EXPERIMENT.figures))
        for name, fig in figs.items():
            if isinstance(fig, str):
                continue
            assert smallest_printed_text(fig)[0] >= 6.5, (name, smallest_printed_text(fig))
            assert text_overlaps(fig) == [], name


def test_headline_table_schema_verdicts_and_docs_links(shipped_run):
    table = report.tables(shipped_run)["paper_vs_reproduced"]
    assert tuple(table.columns) == HEADLINE_COLUMNS
    assert set(table["verdict"]) <= set(VERDICTS)
    assert not table["reason"].str.contains("\n").any()
    # a row names its point: four p_m blocks of passive_mutation read as one point
    assert not table.duplicated(["paper_item", "quantity", "algorithm"]).any()
    fig2 = table[table["paper_item"] == "Fig. 2"]
    assert ((fig2["ci_low"] <= fig2["reproduced"] + 1e-9)
            & (fig2["reproduced"] <= fig2["ci_high"] + 1e-9)).all()
    if shipped_run.params["scene.mode"] == "paper" and "exact" in shipped_run.params["algorithms"]:
        assert len(fig2) > 0
    headings = re.findall(r"^#+ (.+)$", (ROOT / report.DOCS).read_text(), flags=re.M)
    anchors = {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in headings}
    for link in set(table["docs"]):
        page, _, anchor = link.partition("#")
        assert page == report.DOCS and anchor in anchors, link


def test_every_table_has_rows_or_says_why_not(shipped_run):
    tables = report.tables(shipped_run)
    for name, table in tables.items():
        if isinstance(table, str):
            assert table and "\n" not in table, name  # a one-line reason
        else:
            assert len(table) > 0, name
    at_paper = shipped_run.params["scene.mode"] == "paper" \
        and "exact" in shipped_run.params["algorithms"]
    assert isinstance(tables["versus_exact"], str) != at_paper  # the scale study: a reason


def test_checkpoint_gap_bounds_are_each_groups_own_bootstrap_to_the_last_bit():
    """The table's gap interval of a (point, algorithm, checkpoint) group is exactly the one
    that group alone gives (a batched bootstrap would differ in the last digits)."""
    rng = np.random.default_rng(3)
    trials = pd.DataFrame({"point": 0, "algorithm": np.repeat(["a", "b", "c", "d"], 50),
                           "ops": 100, "gap": rng.exponential(5.0, 200)})
    for metric in (*report.MEAN_METRICS, *report.RATE_METRICS, "pairs"):
        trials[metric] = rng.integers(0, 2, 200).astype(float)
    table = report.checkpoint_metrics(trials, {"params": {}, "sweep": {}})
    for row, (_, group) in zip(table.itertuples(), trials.groupby("algorithm"), strict=True):
        low, high = bootstrap_t_mean_intervals([group["gap"].to_numpy()], 0.95,
                                               report.BOOTSTRAP_RESAMPLES,
                                               report.BOOTSTRAP_SEED)[0]
        assert (row.gap_ci_low, row.gap_ci_high) == (max(low, 0.0), high)


def _scale_run(tmp_path, trials: int = 4):
    return harness.run_data(tmp_path, "passive_assoc",
                            {"pga.ops": 100, "pga.checkpoints": [100], "scene.mode": "random",
                             "algorithms": ["exact", "pga_paper", "pga_evict"]},
                            {"targets.n": [5, 10, 20, 50]}, trials=trials, seed=5)


def test_scale_time_axis_reads_in_plain_decimals_with_every_curve_banded(tmp_path):
    """The solve-time axis is labelled 0.1, 1, 10 (no 4x10^-1 mathtext) and the exact
    optimum's time has its interval band like the others."""
    fig = drawn(report.figures(_scale_run(tmp_path, trials=8), ["scale"])["scale"])
    time_ax = fig.axes[0]
    labels = [t.get_text() for t in (*time_ax.get_yticklabels(),
                                     *time_ax.get_yticklabels(minor=True)) if t.get_text()]
    assert len(labels) >= 2 and all(re.fullmatch(r"[0-9.]+", t) for t in labels), labels
    exact = [c for c in time_ax.collections if np.allclose(c.get_facecolor()[0][:3], 0.0)]
    assert len(exact) == 1  # the exact optimum's band (black at low alpha)
    assert len(time_ax.collections) == 3  # and one band per PGA variant
    for band in time_ax.collections:  # each a real interval (6+ trials: median_interval)
        extent = band.get_paths()[0].get_extents()
        assert np.isfinite([extent.y0, extent.y1]).all() and extent.y1 > extent.y0


def test_exact_optimum_band_lies_light_and_behind_the_algorithms_bands(tmp_path):
    """In the accuracy panel the exact optimum's grey band must not cover the others: it
    is drawn under them and fainter than they are."""
    fig = report.figures(_scale_run(tmp_path), ["scale"])["scale"]
    bands = fig.axes[2].collections
    exact = [c for c in bands if np.allclose(c.get_facecolor()[0][:3], 0.0)]
    others = [c for c in bands if c not in exact]
    assert len(exact) == 1 and others
    assert all(exact[0].get_zorder() < c.get_zorder() for c in others)
    assert all(exact[0].get_facecolor()[0][3] < c.get_facecolor()[0][3] for c in others)


def test_scale_time_labels_stay_apart_on_a_range_under_one_decade(tmp_path):
    """Solve times between 0.03 and 0.2 ms (less than a decade): 0.08, 0.09 and 0.1 ms
    labelled at once would overlap; the labels stay apart and at least 2 remain."""
    run = _scale_run(tmp_path)
    times = pd.read_csv(run.path / "timings.csv")
    times["solve_time_s"] = np.geomspace(0.03e-3, 0.19e-3, len(times))
    times.to_csv(run.path / "timings.csv", index=False)
    fig = drawn(report.figures(run, ["scale"])["scale"])
    assert text_overlaps(fig) == []
    low, high = fig.axes[0].get_ylim()
    assert sum(low <= t <= high for t in fig.axes[0].get_yticks()) >= 2


def test_the_high_rate_verdict_follows_the_margin_below_the_optimum(shipped_run):
    """"A high correct rate" agrees when the paired interval of exact - PGA lies below the
    margin declared on the paper's item, differs when above it, else is inconclusive (it
    agreed whenever the interval held 0, so a small run always agreed)."""
    table = report.tables(shipped_run)["paper_vs_reproduced"]
    rows = table[table["quantity"].str.startswith("accuracy after")]
    margin = 100 * PASSIVE_ASSOC.result("high correct rate").margin
    for _, row in rows.iterrows():
        low, high = (float(x.replace("\u2212", "-")) for x in re.search(
            r"exact minus PGA \S+ points \((\S+) to (\S+)\)", row["reason"]).groups())
        expected = ("agrees" if high <= margin else "differs" if low > margin
                    else "inconclusive")
        assert row["verdict"] == expected, row["reason"]


def test_a_variant_is_one_headline_row_per_setting_when_algorithms_are_swept(tmp_path):
    """Two points of a swept algorithms list run pga_paper on the same draws: its headline
    rows came twice, alike."""
    run = harness.run_data(tmp_path, "passive_assoc", {"targets.n": 5, **SMALL},
                           {"algorithms": [["exact", "pga_paper"],
                                           ["exact", "pga_paper", "pga_repair"]]},
                           trials=3, seed=1)
    table = report.tables(run)["paper_vs_reproduced"]
    fig2 = table[table["paper_item"] == "Fig. 2"]
    assert len(fig2) == 2 and set(fig2["algorithm"]) == {"pga_paper"}
    assert not table.duplicated(["paper_item", "quantity", "algorithm"]).any()

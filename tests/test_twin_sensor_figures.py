"""Axes of the twin_sensor figures: every drawn interval fits its axis or is marked, every
legend entry can be seen."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from figure_checks import inside_canvas, internal_names, journal_problems, text_overlaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex
from matplotlib.container import ErrorbarContainer
from matplotlib.lines import Line2D
from matplotlib.offsetbox import OffsetBox, TextArea

from trackfuse import harness
from trackfuse.config import load
from trackfuse.experiments.twin_sensor import EXPERIMENT, LOOKS, report
from trackfuse.plots.algorithms import GREYS, line_kwargs, look
from trackfuse.reportkit.style import context
from trackfuse.rundata import RunData

ROOT = Path(__file__).resolve().parents[1]
LOSS_FIGURES = ("loss_vs_clutter", "loss_vs_clutter_ablation", "loss_gate_and_nees_vs_clutter")
ALGORITHMS = ["nn/mgekf", "mspda_parallel/mgekf", "paper_approx/mgekf", "paper_approx/ekf"]


@pytest.fixture(scope="module")
def run_50(tmp_path_factory) -> RunData:
    """50 runs at the paper's scenario, three clutter levels (the real runner)."""
    base = {**EXPERIMENT.defaults(), "algorithms": ALGORITHMS}
    return harness.run_data(tmp_path_factory.mktemp("axes"), EXPERIMENT, base,
                            {"clutter.mean": [0.0, 8.0, 15.0]}, trials=50, seed=3)


def _flagged(run: RunData, flags: dict[tuple[str, float, str], int],
             runs: int | None = None) -> RunData:
    """``run`` (its first ``runs`` trials) whose last scan flags nothing except the first
    ``k`` trials of each ``(algorithm, clutter level, rule): k`` of ``flags``."""
    trials = run.trials if runs is None else run.trials[run.trials["trial"] < runs]
    trials = trials.copy()
    last = trials["scan"] == trials["scan"].max()
    for rule in report.RULES:
        trials[rule] = 0
    for (name, level, rule), k in flags.items():
        trials.loc[last & (trials["algorithm"] == name) & (trials["clutter.mean"] == level)
                   & (trials["trial"] < k), rule] = 1
    flagged = replace(run)
    flagged.trials = trials
    return flagged


def _bar_tops(ax) -> list[tuple[float, float, str]]:
    """``(x, upper end, colour)`` of every error bar drawn in ``ax``."""
    tops = []
    for container in ax.containers:
        if isinstance(container, ErrorbarContainer):
            for collection in container.lines[2]:
                colour = to_hex(collection.get_color()[0])
                tops += [(seg[:, 0].max(), seg[:, 1].max(), colour)
                         for seg in collection.get_segments()]
    return tops


def _past_top_marks(ax) -> set[tuple[float, float, str]]:
    """``(x, y, colour)`` of every triangle drawn outside the clipping (at the axis top)."""
    return {(round(float(x), 9), round(float(y), 9), to_hex(line.get_color()))
            for line in ax.get_lines() if line.get_marker() == "^" and not line.get_clip_on()
            for x, y in zip(line.get_xdata(), line.get_ydata(), strict=True)}


def _legend(fig) -> list[str]:
    return [t.get_text() for legend in fig.legends for t in legend.get_texts()]


def test_an_interval_past_15_percent_stretches_the_axis_to_a_round_tick(run_50):
    """Nearest neighbour, 3 of 50 lost at 8 (gate rule, as in twin_sensor_orbit): the 95 %
    Wilson upper bound 16.2 % used to run off the 0-15 % axis; now the axis ends at 20 %."""
    run = _flagged(run_50, {("nn/mgekf", 8.0, "lost_gate"): 3,
                            ("paper_approx/mgekf", 8.0, "lost_angle"): 3})
    figs = report.figures(run, LOSS_FIGURES)
    for name in LOSS_FIGURES:
        axes = [ax for ax in figs[name].axes if ax.get_visible()]
        assert any(_bar_tops(ax) for ax in axes), name
        for ax in axes:
            top = ax.get_ylim()[1]
            assert all(t <= top for _, t, _ in _bar_tops(ax)), (name, ax.get_title())
            assert top in ax.get_yticks(), (name, top)  # the top is labelled
            assert not _past_top_marks(ax)
        assert report.PAST_TOP_LABEL not in _legend(figs[name])
        assert text_overlaps(figs[name]) == [], name
    gate = figs["loss_gate_and_nees_vs_clutter"].axes[0]
    assert max(t for _, t, _ in _bar_tops(gate)) == pytest.approx(16.2, abs=0.05)
    assert gate.get_ylim()[1] == 20.0


@pytest.mark.parametrize(("highest", "upper", "top"), [
    (0.0, 7.1, 15.0),    # 0 of 50: the claim's scale
    (6.0, 16.2, 20.0),   # 3 of 50
    (10.0, 21.4, 25.0),  # 5 of 50
    (48.0, 61.4, 70.0),  # the NEES panel of twin_sensor_orbit
    (2.0, 62.0, 15.0),   # 1 of 5 beside 2 %: would squash, marked instead
    (95.0, 99.0, 100.0),
])
def test_loss_top_is_a_round_tick_above_the_intervals_unless_they_squash(highest, upper, top):
    points = pd.DataFrame({"pct": [0.0, highest], "hi": [1.0, upper], "bar": [True, True]})
    assert report._loss_top(points) == top
    assert report._tick_ceiling(upper) >= upper


def test_every_loss_axis_top_is_a_labelled_tick():
    """The top comes from the same ticks the axis is labelled with, whatever the panel's
    size (matplotlib's automatic ticks skipped a stretched 12 % or a 90 % top)."""
    for highest, upper in ((h, u) for h in np.linspace(0.0, 80.0, 161)
                           for u in (h + 1.0, 1.3 * h + 4.0, 2.2 * h + 9.0)):
        points = pd.DataFrame({"pct": [0.0, highest], "hi": [0.0, upper], "bar": [True, True]})
        top = report._loss_top(points)
        ticks = report._round_ticks(top)
        assert ticks[0] == 0.0 and ticks[-1] == top and len(ticks) <= 8
        assert set(np.diff(ticks) / 10 ** np.floor(np.log10(np.diff(ticks)))) <= {1, 2, 5}


# --------------------------------------------------------------------------------------------
# Fig. 2 redrawn: range RMSE and ANEES against time


def _curve(ax, name: str):
    label = look(name).label
    return next(line for line in ax.get_lines() if line.get_label() == label)


def _legend_handle(fig, label: str):
    legend = fig.legends[0]
    return next(h for h, t in zip(legend.legend_handles, legend.get_texts(), strict=True)
                if t.get_text() == label)


def _single_runs(ax) -> list:
    return [line for line in ax.get_lines() if line.get_color() == GREYS[1]]


def test_single_runs_fit_the_range_axis(run_50):
    """The grey single runs used to be cut at 1.8 times the highest RMSE or bound; the axis
    now reaches a round tick above them (at most 3 times that height)."""
    fig = report.figures(run_50, ["range_error_vs_time"])["range_error_vs_time"]
    for ax in fig.axes:
        runs = _single_runs(ax)
        assert len(runs) == report.SINGLE_RUNS
        top = ax.get_ylim()[1]
        assert max(float(np.max(line.get_ydata())) for line in runs) <= top
        assert top in ax.get_yticks()
        assert not any("cut" in t.get_text() for t in ax.texts)


def test_coinciding_bounds_are_drawn_once_and_said_so(run_50):
    """With the filter's q equal to the truth's the two bounds are the same curve: one
    dash-dot curve labelled for both, no dotted curve hidden under it."""
    equal = replace(run_50)
    equal.config = {**run_50.config, "params": {**run_50.config["params"],
                                                "filter.q": run_50.params["target.q"]}}
    fig = report.figures(equal, ["range_error_vs_time"])["range_error_vs_time"]
    texts = _legend(fig)
    assert report.PCRLB_BOTH in texts
    assert report.PCRLB_FILTER not in texts and report.PCRLB_TRUTH not in texts
    assert not any(line.get_linestyle() == ":" for ax in fig.axes for line in ax.get_lines())
    apart = report.figures(run_50, ["range_error_vs_time"])["range_error_vs_time"]
    assert {report.PCRLB_TRUTH, report.PCRLB_FILTER} <= set(_legend(apart))


def test_coinciding_final_bounds_are_drawn_once_and_said_so(run_50):
    """The final-RMSE figure too: one dash-dot bound for both when the filter's q is the
    truth's, the dashed and dotted pair otherwise."""
    equal = replace(run_50)
    equal.config = {**run_50.config, "params": {**run_50.config["params"],
                                                "filter.q": run_50.params["target.q"]}}
    name = "final_range_rmse_vs_sweep"
    fig = report.figures(equal, [name])[name]
    assert report.PCRLB_BOTH in _legend(fig)
    assert report.PCRLB_FILTER not in _legend(fig) and report.PCRLB_TRUTH not in _legend(fig)
    assert not any(line.get_linestyle() == ":" for ax in fig.axes for line in ax.get_lines())
    apart = report.figures(run_50, [name])[name]
    assert {report.PCRLB_TRUTH, report.PCRLB_FILTER} <= set(_legend(apart))
    assert report.PCRLB_BOTH not in _legend(apart)
    assert text_overlaps(fig) == [] and text_overlaps(apart) == []


def test_final_rmse_axis_top_is_a_labelled_tick_above_every_curve(run_50):
    """The final-RMSE axis ends on a labelled tick at or above 1.8 times the highest RMSE or
    bound drawn (it ended at exactly 1.8 times, between two ticks)."""
    name = "final_range_rmse_vs_sweep"
    ax = report.figures(run_50, [name])[name].axes[0]
    top = ax.get_ylim()[1]
    bounds = [line for line in ax.get_lines() if not line.get_label().startswith("_")]
    rmse = [c.lines[0] for c in ax.containers if isinstance(c, ErrorbarContainer)]
    assert bounds and rmse
    curves = bounds + rmse  # not the interval caps: those may run off the top
    highest = max(float(np.nanmax(line.get_ydata())) for line in curves)
    assert top in ax.get_yticks()
    assert report.RMSE_HEADROOM * highest <= top


def test_fig2_draws_our_method_beside_the_papers_pair(run_50):
    """Paper Fig. 2 redrawn shows the paper's fused-gate PDA (MGEKF band, EKF edges) and our
    parallel PDA (MGEKF) as a thin curve on top of them (it was left out)."""
    name = "range_error_vs_time"
    fig = report.figures(run_50, [name])[name]
    ours = look("mspda_parallel/mgekf").label
    assert any(ours in text for text in _legend(fig))
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        by_colour = {to_hex(line.get_color()): line for line in ax.get_lines()
                     if len(line.get_xdata()) == 20 and line.get_linestyle() == "-"}
        curve = by_colour[to_hex(line_kwargs("mspda_parallel/mgekf")["color"])]
        paper = by_colour[to_hex(line_kwargs("paper_approx/mgekf")["color"])]
        assert curve.get_zorder() > paper.get_zorder()
        assert curve.get_marker() in ("", "None")  # bare: it must not hide what it lies on
        assert curve.get_linewidth() < paper.get_linewidth()


def test_anees_axis_top_is_a_labelled_tick_above_every_curve(run_50):
    """Each ANEES panel ends on a labelled tick at or above its band and curves (the top
    was matplotlib's, between ticks)."""
    fig = report.figures(run_50, ["anees_vs_time"])["anees_vs_time"]
    for ax in (a for a in fig.axes if a.get_visible()):
        top = ax.get_ylim()[1]
        assert top in ax.get_yticks()
        assert all(1.03 * np.nanmax(line.get_ydata()) <= top for line in ax.get_lines()
                   if len(line.get_ydata()))  # a marker at the top would be cut in half


def test_a_panel_title_too_long_breaks_after_a_comma():
    """"1 sensor, mean 150 false returns per scan" breaks after "1 sensor," instead of
    leaving "scan" alone on the second line; titles that fit stay whole."""
    assert report._wrapped(["1 sensor, mean 150 false returns per scan"], 3.1) == \
        ["1 sensor,\nmean 150 false returns per scan"]
    assert report._wrapped(["lost, gate rule: 3 scans outside every gate, 2 sensors"],
                           3.9) == ["lost, gate rule: 3 scans outside every gate,\n2 sensors"]
    assert report._wrapped(["mean 9 false returns per scan"], 3.1) == \
        ["mean 9 false returns per scan"]


def _failed_at_point_0(run: RunData) -> RunData:
    """``run`` as if every trial of sweep point 0 had failed: one ``failed`` row per trial
    (as the runner writes it) instead of its rows, and no summary row of point 0."""
    trials, summary = run.trials, run.summary
    first = trials[trials["point"] == 0].drop_duplicates("trial")
    failed = first[["point", "trial", "clutter.mean"]].assign(
        algorithm="", status="failed", error="ValueError: math domain error")
    broken = replace(run)
    broken.trials = pd.concat([failed, trials[trials["point"] != 0]], ignore_index=True)
    broken.summary = summary[summary["point"] != 0]
    return broken


@pytest.mark.parametrize("name", ["range_error_vs_time", "anees_vs_time"])
def test_a_point_whose_every_trial_failed_gets_a_panel_that_says_so(run_50, name):
    """`trackfuse plot` of a run whose clutter-0 trials had all failed lost the range figure
    to `IndexError: single positional indexer is out-of-bounds`; the legend came from the
    first panel, which had nothing drawn."""
    fig = report.figures(_failed_at_point_0(run_50), [name])[name]
    first = fig.axes[0]
    assert [t.get_text() for t in first.texts] == ["all 50 trials failed\n(status=failed in "
                                                   "trials.csv)"]
    assert not first.lines and all(ax.lines for ax in fig.axes[1:3])
    assert any(look(a).label in t.get_text() for t in fig.legends[0].get_texts()
               for a in ALGORITHMS)


@pytest.mark.parametrize("name", ["range_error_vs_time", "anees_vs_time"])
def test_a_time_figure_chooses_its_points_once(run_50, monkeypatch, name):
    """The ANEES figure chose its sweep points three times (title, y range, panels), the
    range figure three times too: once now, passed on."""
    calls = []
    chosen = report._time_points
    monkeypatch.setattr(report, "_time_points", lambda run: calls.append(1) or chosen(run))
    assert not isinstance(report.figures(run_50, [name])[name], str)
    assert len(calls) == 1


def test_time_panels_share_one_y_range_when_their_tops_are_alike(run_50):
    """Panels of a time figure whose needed tops differ by at most 2.5x share one range,
    so that they compare at a glance (twin_sensor_baseline's nine panels ended at 30, 40 or
    50 km); the shared top is a labelled tick."""
    for name in ("range_error_vs_time", "anees_vs_time"):
        axes = [ax for ax in report.figures(run_50, [name])[name].axes if ax.get_visible()]
        tops = {ax.get_ylim()[1] for ax in axes}
        assert len(axes) == 3 and len(tops) == 1, (name, tops)
        assert tops.pop() in axes[0].get_yticks()


def test_shared_tops_go_by_figure_then_by_row():
    """One top for all when the figure allows, else per row, else each its own (a 5 km
    panel is not squeezed under a 140 km one)."""
    assert report._shared_tops({0: 30.0, 1: 50.0, 2: 40.0, 3: 30.0}, 3) == dict.fromkeys(
        range(4), 50.0)
    rows = report._shared_tops({0: 5.0, 1: 5.0, 2: 6.0, 3: 120.0, 4: 140.0, 5: 120.0}, 3)
    assert rows == {0: 6.0, 1: 6.0, 2: 6.0, 3: 140.0, 4: 140.0, 5: 140.0}
    alone = {0: 5.0, 1: 50.0, 2: 140.0}
    assert report._shared_tops(alone, 3) == alone
    gap = report._shared_tops({0: 5.0, 2: 6.0, 3: 120.0, 5: 140.0}, 3)  # panels 1, 4 failed
    assert gap == {0: 6.0, 2: 6.0, 3: 140.0, 5: 140.0}


def test_no_empty_legend_row_when_nothing_passes_the_top(run_50):
    """The range figure reserves a legend row for the past-the-top triangle; when no band
    passes the top that row is cut, so the legend sits right under the x labels (an empty
    0.2 in row used to separate them)."""
    fig = report.figures(run_50, ["range_error_vs_time"])["range_error_vs_time"]
    assert report.PAST_TOP_LABEL not in _legend(fig)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    labels_bottom = min(ax.xaxis.label.get_window_extent(renderer).y0
                        for ax in fig.axes if ax.get_visible())
    legend_top = fig.legends[0].get_window_extent(renderer).y1
    assert 0 < (labels_bottom - legend_top) / fig.dpi < 0.3
    assert text_overlaps(fig) == []


def test_the_single_runs_legend_counts_the_runs_drawn(tmp_path):
    """A 3-trial run drew 3 grey runs under a legend that said "5 single runs"."""
    base = {**EXPERIMENT.defaults(), "algorithms": ALGORITHMS[:1], "scan.count": 5}
    run = harness.run_data(tmp_path, EXPERIMENT, base, {"clutter.mean": [0.0]}, trials=3,
                           seed=3)
    fig = report.figures(run, ["range_error_vs_time"])["range_error_vs_time"]
    assert len(_single_runs(fig.axes[0])) == 3
    assert "3 single runs, |range error|" in _legend(fig)


# --------------------------------------------------------------------------------------------
# Review of the figures (IEEE TAES reviewer)


def _range_scaled(run: RunData, ratio: float) -> RunData:
    """``run`` whose paper_approx/mgekf range RMSE is ``ratio`` times the truth-model bound
    at every scan of every point (squared errors scaled per point and scan; their spread
    across runs, and so the band's width, kept)."""
    trials = run.trials.copy()
    mine = trials["algorithm"] == "paper_approx/mgekf"
    for (point, scan), rows in trials[mine].groupby(["point", "scan"]):
        bound = report.bounds(run.point_params(int(point)))[0][int(scan) - 1]
        trials.loc[rows.index, "range_sq_err_m2"] *= (ratio * bound) ** 2 / rows[
            "range_sq_err_m2"].mean()
    scaled = replace(run)
    scaled.trials = trials
    return scaled


def _notes(ax) -> list[str]:
    return [t.get_text() for t in ax.texts]


def _run_off(run: RunData, runs: int, flag: bool) -> RunData:
    """``run`` whose first ``runs`` trials of mspda_parallel/mgekf at clutter 8 end 300 km
    off in range, flagged inconsistent when ``flag`` (as twin_sensor_baseline's two runs at
    40 km: angles on target, no loss, NEES flag)."""
    trials = run.trials.copy()
    off = ((trials["scan"] == trials["scan"].max()) & (trials["trial"] < runs)
           & (trials["algorithm"] == "mspda_parallel/mgekf") & (trials["clutter.mean"] == 8.0))
    trials.loc[off, "range_sq_err_m2"] = 3e5**2
    trials.loc[off, "inconsistent_nees"] = int(flag)
    changed = replace(run)
    changed.trials = trials
    return changed


def _joined_x(ax, name: str) -> list[np.ndarray]:
    """x of every drawn line of ``name``'s look that joins points (solid or dashed)."""
    colour = to_hex(line_kwargs(name)["color"])
    return [np.asarray(line.get_xdata(), float) for line in ax.get_lines()
            if to_hex(line.get_color()) == colour and line.get_linestyle() not in ("None", "")
            and line.get_marker() == line_kwargs(name)["marker"]]


def _legend_markers(fig, label: str) -> list[tuple]:
    """``(marker, face colour, edge colour)`` of every line the figure legend draws in the
    handle of the entry ``label``."""
    def boxes(box):
        yield box
        for child in box.get_children():
            if isinstance(child, OffsetBox):
                yield from boxes(child)

    for box in boxes(fig.legends[0].get_children()[0]):
        handle, text = (box.get_children() + [None, None])[:2]
        if isinstance(text, TextArea) and text.get_text() == label:
            return [_marker_look(a) for a in handle.get_children() if isinstance(a, Line2D)]
    raise AssertionError(f"no legend entry {label!r}")


def _marker_look(line) -> tuple:
    return (line.get_marker(), to_hex(line.get_markerfacecolor(), keep_alpha=True)
            if line.get_markerfacecolor() != "none" else "none",
            to_hex(line.get_markeredgecolor()))


def test_many_flagged_runs_are_not_a_few():
    """Flagged runs above 10 % of a point's runs are the point's behaviour, not a few runs
    run off: the point stays joined (twin_sensor_close, 30-90 % of runs flagged)."""
    rows = pd.DataFrame({"x": 1.0, "algorithm": "a", "range_sq_err_m2": [100.0] * 6 + [1.0] * 44,
                         **{rule: [1] * 6 + [0] * 44 for rule in report.RULES}})
    assert report._few_runs_carry(rows, "x", ["a"]) == {}
    rows.loc[5, list(report.RULES)] = 0
    ((k, n, share),) = report._few_runs_carry(rows, "x", ["a"])["a"].values()
    assert (k, n) == (5, 50) and share > 0.5


@pytest.mark.parametrize(("values", "threshold"), [
    ([0, 10, 15, 20, 40, 50, 150], 10.0),  # twin_sensor_close: 50 to 150 a wide gap
    ([0.0, 0.015, 0.05, 0.1, 0.2], 0.015),  # twin_sensor_hard's manoeuvring indices
    (list(range(16)), None),  # twin_sensor_orbit: an even grid
    ([0, 1000, 2000, 5000, 10000, 20000, 30000, 40000, 50000], None),  # baseline: no wide gap
    ([0, 5, 10, 15], None),
    ([2000, 20000, 50000], None),
])
def test_a_wide_gap_beside_crowded_values_gets_a_symlog_axis(values, threshold):
    assert report._symlog_threshold(values) == threshold


@pytest.fixture(scope="module")
def run_wide(tmp_path_factory) -> RunData:
    """20 short runs at clutter 0, 10, 15, 20, 150 (twin_sensor_close's gap)."""
    base = {**EXPERIMENT.defaults(), "algorithms": ALGORITHMS[1:3], "scan.count": 5}
    return harness.run_data(tmp_path_factory.mktemp("wide"), EXPERIMENT, base,
                            {"clutter.mean": [0.0, 10.0, 15.0, 20.0, 150.0]}, trials=20, seed=3)


@pytest.mark.parametrize("name", ["loss_vs_clutter", "final_range_rmse_vs_sweep"])
def test_clutter_with_a_wide_gap_is_drawn_on_a_symlog_axis(run_wide, name):
    """twin_sensor_close joined 50 to 150 false returns by one long segment with the points
    at 0-20 piled up: the axis is symmetric-log, labelled at the swept values, and the
    points at 10, 15 and 20 lie apart on the page."""
    fig = report.figures(run_wide, [name])[name]
    ax = fig.axes[0]
    assert ax.get_xscale() == "symlog"
    # the axis says it is not linear (audit: the labels did not, unlike passive and esm's)
    assert "x axis: symmetric log, linear up to 10" in [
        t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert list(ax.get_xticks()) == [0.0, 10.0, 15.0, 20.0, 150.0]
    drawn = ax.transData.transform([(v, 0.0) for v in (10.0, 15.0, 20.0, 150.0)])[:, 0]
    assert np.min(np.diff(drawn)) / ax.figure.dpi > 0.2  # inches apart
    assert text_overlaps(ax.figure) == []


def _legend_look(line, at_legend_scale: bool = False) -> tuple:
    """A line's width, marker size and marker fill, as its legend entry draws them when
    ``at_legend_scale`` (:data:`report.LEGEND_LINE_PT`)."""
    width, marker = report.LEGEND_LINE_PT if at_legend_scale else (np.inf, np.inf)
    return (min(line.get_linewidth(), width), min(line.get_markersize(), marker),
            line.get_markerfacecolor())


def test_anees_panels_share_one_log_axis_with_the_band_inside(run_50):
    """twin_sensor_close and _hard's ANEES panels each had their own linear y range (0-7 to
    0-60): they now share one log axis that holds every curve and chi-square band, even
    when one panel's ANEES is ten times the others'."""
    trials = run_50.trials.copy()
    trials.loc[trials["clutter.mean"] == 15.0, "nees"] *= 10
    wild = replace(run_50)
    wild.trials = trials
    fig = report.figures(wild, ["anees_vs_time"])["anees_vs_time"]
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert {ax.get_yscale() for ax in axes} == {"log"}
    assert len({ax.get_ylim() for ax in axes}) == 1
    low, high = axes[0].get_ylim()
    for ax in axes:
        drawn = np.concatenate([line.get_ydata() for line in ax.get_lines()])
        assert low <= np.nanmin(drawn) and np.nanmax(drawn) <= high
        (band,) = ax.patches  # the chi-square band, inside the axis
        corners = band.get_transform().transform(band.get_path().vertices)
        inside = ax.transAxes.inverted().transform(corners)[:, 1]
        assert np.all((inside >= 0) & (inside <= 1))
    assert low in axes[0].get_yticks() and high in axes[0].get_yticks()
    assert text_overlaps(fig) == []


def test_an_anees_in_the_thousands_keeps_its_axis_label_on_the_figure(run_50):
    """A diverging filter (ANEES 2000-3000) got ticks "3e+03", wider than the margin: the
    y label ran off the figure and onto the panel to its left. Ticks now read "3000"."""
    trials = run_50.trials.copy()
    trials["nees"] *= 400
    wild = replace(run_50)
    wild.trials = trials
    with context():
        fig = report.figures(wild, ["anees_vs_time"])["anees_vs_time"]
        assert text_overlaps(fig) == [] and inside_canvas(fig)
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert "3000" in labels or "2000" in labels, labels
    assert [report._log_tick_text(v) for v in (0.5, 3.0, 3000.0, 1e4, 1e5)] == \
        ["0.5", "3", "3000", "$10^{4}$", "$10^{5}$"]


@pytest.mark.parametrize("scale", [1000, 4000])
def test_an_anees_in_the_tens_of_thousands_is_labelled_by_decades(run_50, scale):
    """ANEES 5000-30000 drew 1-2-3-5 ticks over four decades: "1e+04" and "2e+04" pushed the
    y label off the figure again and "20"/"30", "200"/"300" overlapped (review). Over more
    than three decades the axis is labelled at the powers of ten alone."""
    trials = run_50.trials.copy()
    trials["nees"] *= scale
    wild = replace(run_50)
    wild.trials = trials
    with context():
        fig = report.figures(wild, ["anees_vs_time"])["anees_vs_time"]
        assert text_overlaps(fig) == [] and inside_canvas(fig)
    ticks = fig.axes[0].get_yticks()
    assert np.allclose(np.log10(ticks), np.round(np.log10(ticks))) and ticks[-1] >= 1e4
    assert report._log_ticks(3.0, 3000.0).tolist() == [3, 5, 10, 20, 30, 50, 100, 200, 300,
                                                       500, 1000, 2000, 3000]
    assert report._log_ticks(47.6, 21000.0).tolist() == [10, 100, 1000, 1e4, 1e5]  # review


def test_a_swept_q_is_titled_by_its_manoeuvring_index():
    """twin_sensor_hard's panels were titled "truth and filter q 160000 m^2/s^4": the study
    is about the manoeuvring index, so the panel says that (q stays in the caption)."""
    params = {**EXPERIMENT.defaults(), "target.q": 160000.0, "filter.q": 160000.0,
              "clutter.mean": 40.0}
    swept = ["target.q", "filter.q", "clutter.mean"]
    assert report._point_title(params, swept, matched=True) == \
        "manoeuvring index 0.2, mean 40 false returns per scan"
    assert report._point_title({**params, "target.q": 900.0, "filter.q": 900.0}, swept,
                               matched=True).startswith("manoeuvring index 0.015,")
    assert report._point_title({**params, "filter.q": 900.0}, swept, matched=False) == \
        "manoeuvring index 0.2, filter q 900 m²/s⁴, mean 40 false returns per scan"
    # the truth's q swept alone: the index said nothing of the filter's q, nor the title
    assert report._point_title({**params, "filter.q": 900.0}, ["target.q"], matched=False) \
        == "manoeuvring index 0.2, filter q 900 m²/s⁴"


def test_a_panel_whose_filter_q_equals_the_truths_says_it_unless_the_title_does(tmp_path):
    """A target.q x filter.q grid: the panels where the two were equal left the filter's q
    out while the figure's title said nothing of it (a reader could not tell which filter q
    they used). Every panel now gives it; only when every panel's filter q is the truth's
    does the title say "truth q = filter q" once (twin_sensor_hard, test below). The
    manoeuvring-index figure, whose title says truth q = filter q, is not drawn from
    such a grid (it would pool two filter qs at one index)."""
    base = {**EXPERIMENT.defaults(), "algorithms": ALGORITHMS[1:3], "scan.count": 5,
            "clutter.model": "window", "clutter.window": 0.1, "clutter.mean": 40.0}
    run = harness.run_data(tmp_path, EXPERIMENT, base,
                           {"target.q": [0.0, 900.0, 10000.0], "filter.q": [0.0, 900.0]},
                           trials=4, seed=3)
    figs = report.figures(run, EXPERIMENT.figures)
    for name in ("range_error_vs_time", "anees_vs_time"):
        titles = [ax.get_title().replace("\n", " ") for ax in figs[name].axes
                  if ax.get_visible()]
        assert len(titles) == 6 and all("filter q " in t for t in titles), titles
        assert "truth q = filter q" not in figs[name].get_suptitle()
    assert figs["loss_vs_manoeuvring_index"].startswith("needs filter.q equal to target.q")


@pytest.fixture(scope="module")
def run_hard(tmp_path_factory) -> RunData:
    """twin_sensor_hard's zipped sweep (truth and filter q with clutter), 10 short runs."""
    base = {**EXPERIMENT.defaults(), "algorithms": ALGORITHMS, "scan.count": 5,
            "clutter.model": "window", "clutter.window": 0.1}
    q = [0.0, 160000.0, 0.0, 900.0, 10000.0, 40000.0, 160000.0]
    return harness.run_data(tmp_path_factory.mktemp("hard"), EXPERIMENT, base,
                            {"target.q": q, "filter.q": q,
                             "clutter.mean": [0.0, 0.0, 40.0, 40.0, 40.0, 40.0, 40.0]},
                            trials=10, seed=3, sweep_mode="zip")


def test_a_matched_q_is_said_once_in_the_title(run_hard):
    """twin_sensor_hard: the filter's q is the truth's at every point, said once in the
    figure's title; the panels give the manoeuvring index alone."""
    for name, fig in report.figures(run_hard, ["range_error_vs_time", "anees_vs_time"]).items():
        assert "truth q = filter q" in fig.get_suptitle().replace("\n", " "), name
        titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
        assert all(t.startswith("manoeuvring index") and "filter q" not in t for t in titles)


@pytest.mark.slow
@pytest.mark.parametrize("fixture", ["run_50", "run_wide", "run_hard"])
def test_every_figure_meets_the_journal_rules(fixture, request):
    """Every figure is 7.16 in wide (a double-column slot: it was up to 11.25 in, its text
    4.5 pt once printed), at most 8.5 in tall, its text inside the canvas and at least 7 pt,
    its legends at most six entries, TrueType fonts in its PDF, no host text and no
    internal name (config key, algorithm id, ASCII unit)."""
    run = request.getfixturevalue(fixture)
    with context():  # drawn as trackfuse.reports draws them
        drawn = {name: fig for name, fig in report.figures(run, EXPERIMENT.figures).items()
                 if not isinstance(fig, str)}
        assert len(drawn) >= 3
        for name, fig in drawn.items():
            assert journal_problems(fig) == [], name
            assert internal_names(fig, EXPERIMENT) == [], name


def test_fig1_headline_draws_the_papers_scenario_beside_the_close_analogue(tmp_path):
    """Paper 000's Fig. 1 is flat at 0 % at the paper's scenario (the true result there):
    the headline puts the close geometry, where loss rises with clutter, beside it on one
    y axis, each panel titled, the figure a journal slot."""
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
    assert left.get_title() == "paper's scenario" and "close" in right.get_title()
    assert left.get_shared_y_axes().joined(left, right)
    assert fig.get_suptitle().startswith("Paper 000 Fig. 1 redrawn (left)")
    # the close run's one-sensor points are left out: each curve has one point per level
    labels = {LOOKS[n].label for n in pairs}
    for ax in (left, right):
        curves = [ln for ln in ax.get_lines() if ln.get_label() in labels]
        assert len(curves) == 2 and all(len(ln.get_xdata()) == 2 for ln in curves)


def test_curves_shifted_beside_equal_ones_stay_in_view(tmp_path):
    """configs/ci/twin_sensor_ci.yaml: every curve of the ablation lies at 0 %, so each is
    shifted beside the next; a line drawn in a moved frame sets no data limits, and the
    x axis showed -0.05 to 0.05 with the curves off to its right."""
    cfg = load(ROOT / "configs" / "ci" / "twin_sensor_ci.yaml")
    run = harness.run_data(tmp_path, EXPERIMENT, cfg.params, cfg.sweep, trials=cfg.trials,
                           seed=cfg.seed)
    with context():
        fig = report.figures(run, ["loss_vs_clutter_ablation"])["loss_vs_clutter_ablation"]
        fig.canvas.draw()
    for ax in (a for a in fig.axes if a.get_visible() and a.has_data()):
        low, high = sorted(ax.get_xlim())
        assert low <= 0.0 and high >= 10.0, ax.get_xlim()

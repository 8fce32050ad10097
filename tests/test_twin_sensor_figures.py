"""Axes of the twin_sensor figures: every drawn interval fits its axis or is marked, every
legend entry can be seen."""

from dataclasses import replace

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
from matplotlib.container import ErrorbarContainer
from matplotlib.lines import Line2D
from matplotlib.offsetbox import OffsetBox, TextArea

from trackfuse import harness
from trackfuse.experiments.twin_sensor import EXPERIMENT, report
from trackfuse.plots.algorithms import GREYS, line_kwargs, look
from trackfuse.plots.style import context
from trackfuse.rundata import RunData

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


def test_an_interval_that_would_squash_the_curves_is_marked_at_the_top(run_50):
    """With 5 runs, "1 of 5" reaches 62 %: stretching the 0-30 % axis to 70 % would
    squeeze the curves, so each bar past the top gets a triangle there in its colour and
    the legend says what it means."""
    run = _flagged(run_50, {("nn/mgekf", 8.0, "lost_gate"): 1,
                            ("paper_approx/mgekf", 8.0, "lost_angle"): 1}, runs=5)
    figs = report.figures(run, LOSS_FIGURES)
    marked = 0
    for name in LOSS_FIGURES:
        for ax in figs[name].axes:
            if not ax.get_visible():
                continue
            top = ax.get_ylim()[1]
            marks = _past_top_marks(ax)
            for x, bar_top, colour in _bar_tops(ax):
                if bar_top > top:
                    assert (round(float(x), 9), round(top, 9), colour) in marks, (name, x)
                    marked += 1
            assert {m[2] for m in marks} <= {to_hex(line_kwargs(n)["color"]) for n in ALGORITHMS}
        if any(_past_top_marks(ax) for ax in figs[name].axes):
            assert report.PAST_TOP_LABEL in _legend(figs[name]), name
        assert text_overlaps(figs[name]) == [], name
    assert marked > 0
    # "0 of 5 flagged" is bounded by 43 %, above the 0-30 % axis: said in the legend, with
    # its value, where the dotted line cannot be drawn (four curves: bars only where flagged).
    gate = figs["loss_gate_and_nees_vs_clutter"]
    assert "upper 95 % bound when 0 of 5 are flagged: 43 %, above the axis" in _legend(gate)
    assert not any(line.get_linestyle() == ":" for line in gate.axes[0].get_lines())


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


@pytest.mark.parametrize("figure", ["range_error_vs_time", "anees_vs_time"])
def test_the_ekf_curve_shows_where_it_lies_on_the_mgekf(run_50, figure):
    """The EKF curve (within 0.41 km of the MGEKF's in twin_sensor_orbit) lies above the
    MGEKF's, thinner and dashed with white gaps, with larger open markers; its legend entry
    is dashed like its band edges."""
    fig = report.figures(run_50, [figure])[figure]
    for ax in fig.axes:
        mgekf, ekf = _curve(ax, "paper_approx/mgekf"), _curve(ax, "paper_approx/ekf")
        assert ekf.get_zorder() > mgekf.get_zorder()
        assert ekf.get_linestyle() == "--" and ekf.get_gapcolor() == "white"
        assert ekf.get_linewidth() < mgekf.get_linewidth()
        assert ekf.get_markersize() > mgekf.get_markersize()
        assert ekf.get_markerfacecolor() == "none"
    handle = _legend_handle(fig, look("paper_approx/ekf").label)
    assert handle.get_linestyle() == "--"
    if figure == "range_error_vs_time":
        edges = _legend_handle(fig, "95 % band, EKF (dashed edges)")
        assert edges.get_linestyle() == "--" and to_hex(edges.get_color()) == to_hex(
            handle.get_color())
        assert "95 % band, MGEKF (shaded)" in _legend(fig)
    assert text_overlaps(fig) == []


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


def test_a_single_run_far_above_the_curves_is_cut_and_the_panel_says_so(run_50):
    trials = run_50.trials.copy()
    first = (trials["algorithm"] == "paper_approx/mgekf") & (trials["trial"] == 0)
    trials.loc[first, "range_err_m"] *= 20  # only the single run; the RMSE keeps its data
    run = replace(run_50)
    run.trials = trials
    fig = report.figures(run, ["range_error_vs_time"])["range_error_vs_time"]
    for ax in fig.axes:
        top = ax.get_ylim()[1]
        highest = max(float(np.max(line.get_ydata())) for line in _single_runs(ax))
        assert highest > report.SINGLE_RUNS_REACH * top / 1.8  # far above: cut
        notes = [t.get_text() for t in ax.texts if "cut" in t.get_text()]
        assert notes == [f"single runs cut at {top:g} km (highest {highest:.0f} km)"]
    assert text_overlaps(fig) == []


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


def test_a_final_rmse_interval_past_the_top_is_marked_there(run_50):
    """One diverged run (range error 1000 km at the last scan) sends its interval far past
    the axis top: a triangle in its colour marks it at the top, with its legend entry (it
    used to end at the frame without a sign)."""
    name = "final_range_rmse_vs_sweep"
    trials = run_50.trials.copy()
    diverged = ((trials["scan"] == trials["scan"].max()) & (trials["trial"] == 0)
                & (trials["algorithm"] == "mspda_parallel/mgekf")
                & (trials["clutter.mean"] == 8.0))
    trials.loc[diverged, "range_sq_err_m2"] = 1e6**2
    bad = replace(run_50)
    bad.trials = trials
    fig = report.figures(bad, [name])[name]
    ax = fig.axes[0]
    top = ax.get_ylim()[1]
    (x, y, colour), = _past_top_marks(ax)  # one mark: the interval is unbounded or past top
    assert x == pytest.approx(8.0, abs=0.2) and y == top
    assert colour == to_hex(line_kwargs("mspda_parallel/mgekf")["color"])
    assert report.PAST_TOP_LABEL in _legend(fig)
    clean = report.figures(run_50, [name])[name]
    assert not _past_top_marks(clean.axes[0]) and report.PAST_TOP_LABEL not in _legend(clean)


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


def test_every_loss_figure_says_its_error_bars_are_wilson_intervals(run_50):
    """The error bars of the loss figures are named in the legend (nothing said what they
    were)."""
    for name, fig in report.figures(run_50, LOSS_FIGURES).items():
        assert report.WILSON_LABEL in _legend(fig), name
        assert text_overlaps(fig) == [], name


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


def test_a_range_band_past_the_top_is_marked_there(run_50):
    """A band that leaves the axis top (twin_sensor_baseline's 40 and 50 km panels, with no
    sign) gets a triangle at the top at each such time, with its legend entry."""
    name = "range_error_vs_time"
    trials = run_50.trials.copy()
    wild = ((trials["scan"] == 10) & (trials["trial"] == 0) & (trials["clutter.mean"] == 8.0)
            & (trials["algorithm"] == "paper_approx/mgekf"))
    trials.loc[wild, "range_sq_err_m2"] = 2e5**2
    bad = replace(run_50)
    bad.trials = trials
    fig = report.figures(bad, [name])[name]
    marks = [_past_top_marks(ax) for ax in fig.axes if ax.get_visible()]
    assert not marks[0] and not marks[2]
    (x, y, colour), = marks[1]
    assert x == pytest.approx(10 * bad.params["scan.period"]) and y == fig.axes[1].get_ylim()[1]
    assert colour == to_hex(line_kwargs("paper_approx/mgekf")["color"])
    assert report.PAST_TOP_LABEL in _legend(fig)
    assert report.PAST_TOP_LABEL not in _legend(report.figures(run_50, [name])[name])


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


def test_a_range_panel_below_the_bound_at_every_scan_says_why(run_50):
    """twin_sensor_orbit's 50-run RMSE lay below the sqrt PCRLB at all 20 scans of every
    panel with nothing said: such a panel, with the bound inside its band, now says it is
    one sample of correlated runs; a panel at or above the bound keeps the plain note."""
    name = "range_error_vs_time"
    below = report.figures(_range_scaled(run_50, 0.9), [name])[name]
    for ax in below.axes:
        (note,) = _notes(ax)
        assert note.startswith("below the bound at all 20 scans:\none sample of 50 runs")
        assert note.endswith("the bound lies inside the 95 % band")
    assert text_overlaps(below) == []
    above = report.figures(_range_scaled(run_50, 1.1), [name])[name]
    for ax in above.axes:
        (note,) = _notes(ax)
        assert note.startswith("corr. of errors, scan 1 vs 20: ")


@pytest.mark.parametrize(("corr", "words"), [
    (0.95, "errors\ncorrelated across scans (0.95);"),
    (-0.7, "errors\ncorrelated across scans (-0.70);"),
    (0.12, "errors weakly\ncorrelated across scans (0.12);"),
    (-0.3, "errors weakly\ncorrelated across scans (-0.30);")])
def test_the_below_the_bound_note_calls_weak_correlation_weak(corr, words):
    """The note said "errors correlated across scans (0.12)" whatever the correlation (0.95
    in twin_sensor_orbit): a weak one is now called weak."""
    band = pd.DataFrame({"rmse": [9.0] * 20, "lo": [7.0] * 20, "hi": [12.0] * 20})
    note = report._range_note(band, np.full(20, 10.0), 50, 20, corr)
    assert note == ("below the bound at all 20 scans:\none sample of 50 runs, "
                    f"{words}\nthe bound lies inside the 95 % band")
    assert report._range_note(band, np.full(20, 8.0), 50, 20, corr) == \
        f"corr. of errors, scan 1 vs 20: {corr:.2f}"


def test_a_bound_outside_the_band_gets_no_below_the_bound_note():
    """Below the bound but with the bound above the band (a filter shown better than the
    bound, a bug) is not explained away as sampling."""
    band = pd.DataFrame({"rmse": [10.0, 9.0], "lo": [8.0, 7.0], "hi": [12.0, 11.0]})
    assert report._below_bound_everywhere(band, np.array([11.0, 10.0]))
    assert not report._below_bound_everywhere(band, np.array([13.0, 10.0]))  # outside
    assert not report._below_bound_everywhere(band, np.array([11.0, 8.5]))  # above once


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


def test_a_point_a_few_flagged_runs_carry_is_not_joined_and_says_so(run_50):
    """twin_sensor_baseline's 40 km point (2 of 50 runs off in range, 95 % of the squared
    error) read as a resonance between 30 and 50 km: such a point is now marker and
    interval only, annotated with the count; unflagged runs (no rule of the report calls
    them off) stay joined."""
    name = "final_range_rmse_vs_sweep"
    fig = report.figures(_run_off(run_50, 2, flag=True), [name])[name]
    ax = fig.axes[0]
    joined = _joined_x(ax, "mspda_parallel/mgekf")
    assert joined and all(not np.any(np.abs(x - 8.0) < 0.5) for x in joined)
    (note,) = [t.get_text() for t in ax.texts]
    assert note.startswith("2/50 flagged runs:\n") and note.endswith("% of the MSE")
    assert report.FEW_LABEL in _legend(fig)
    assert text_overlaps(fig) == []
    plain = report.figures(_run_off(run_50, 2, flag=False), [name])[name]
    assert any(np.any(np.abs(x - 8.0) < 0.5) for x in _joined_x(plain.axes[0],
                                                                  "mspda_parallel/mgekf"))
    assert not plain.axes[0].texts and report.FEW_LABEL not in _legend(plain)


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


@pytest.mark.parametrize("algorithms", [["mspda_parallel/mgekf"],
                                        ["mspda_parallel/mgekf", "paper_approx/ekf"]])
def test_the_not_joined_legend_entry_shows_the_markers_drawn(run_50, algorithms):
    """twin_sensor_baseline's 40 km points were drawn with the algorithms' markers (MGEKF
    filled, EKF open) while the legend's "point not joined" showed an open grey circle:
    the entry now shows each not-joined marker as it is drawn, side by side."""
    run = _run_off(run_50, 2, flag=True)
    for name in algorithms[1:]:
        trials = run.trials.copy()
        off = ((trials["scan"] == trials["scan"].max()) & (trials["trial"] < 2)
               & (trials["algorithm"] == name) & (trials["clutter.mean"] == 8.0))
        trials.loc[off, ["range_sq_err_m2", "inconsistent_nees"]] = [3e5**2, 1]
        run.trials = trials
    fig = report.figures(run, ["final_range_rmse_vs_sweep"])["final_range_rmse_vs_sweep"]
    FigureCanvasAgg(fig).draw()
    drawn = [_marker_look(c.lines[0]) for c in fig.axes[0].containers
             if isinstance(c, ErrorbarContainer) and c.get_label() == "_few"]
    assert len(drawn) == len(algorithms)
    assert _legend_markers(fig, report.FEW_LABEL) == drawn
    assert text_overlaps(fig) == []


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


def test_a_wide_covered_curve_has_a_legend_entry_of_legend_size(run_50):
    """Curves nested around two or three others (up to 6.4 pt wide with 11 pt markers)
    drew legend entries as blocks over their neighbours' (review of the orbit's loss
    figures): an entry is at most 3 pt wide with 7 pt markers, still wider than a plain
    curve's, with the same colour, dashes and open marker."""
    name = "loss_vs_clutter_ablation"
    with context():
        fig = report.figures(run_50, [name])[name]
        assert text_overlaps(fig) == [] and alike_legend_entries(fig) == []
    wide = [line for line in fig.axes[0].get_lines()
            if line.get_linewidth() > report.LEGEND_LINE_PT[0]]
    assert wide  # run_50's PDA variants coincide at 0 %
    for line in wide:
        handle = _legend_handle(fig, line.get_label())
        assert _legend_look(handle) == _legend_look(line, at_legend_scale=True)
        assert (handle.get_color(), handle.get_linestyle(), handle.get_marker()) == \
            (line.get_color(), line.get_linestyle(), line.get_marker())


def test_a_curve_under_an_equal_one_shows_around_it(run_50):
    """fig1_claim's parallel PDA lay at 0 % under the paper's curve, its legend entry
    matching nothing visible: a covered curve is now wider with larger open markers (in
    the legend too); curves that differ keep their looks."""
    name = "loss_vs_clutter"
    fig = report.figures(_flagged(run_50, {}), [name])[name]
    ours, paper = _curve(fig.axes[0], "mspda_parallel/mgekf"), _curve(fig.axes[0],
                                                                      "paper_approx/mgekf")
    lines = fig.axes[0].get_lines()
    assert lines.index(ours) < lines.index(paper)  # drawn first, underneath
    assert ours.get_linewidth() >= paper.get_linewidth() + 2
    assert ours.get_markersize() > paper.get_markersize() and \
        ours.get_markerfacecolor() == "none"
    handle = _legend_handle(fig, look("mspda_parallel/mgekf").label)
    assert _legend_look(handle) == _legend_look(ours, at_legend_scale=True)
    assert handle.get_linewidth() > paper.get_linewidth()  # the legend shows it wide too
    apart = report.figures(_flagged(run_50, {("paper_approx/mgekf", 8.0, "lost_angle"): 3}),
                           [name])[name]
    assert _curve(apart.axes[0], "mspda_parallel/mgekf").get_linewidth() == \
        line_kwargs("mspda_parallel/mgekf")["linewidth"]


def test_the_legend_look_of_a_covered_curve_holds_in_every_panel(run_50):
    """The look of a curve lying on another (wider, larger open markers) was decided per
    panel while the legend came from the first: with every gate-rule curve at 0 % but the
    paper's MGEKF flagged inconsistent at 8, the legend showed that curve wide while the
    NEES panel drew it plain. A curve now has one look in every panel of the figure."""
    name = "loss_gate_and_nees_vs_clutter"
    fig = report.figures(_flagged(run_50, {("paper_approx/mgekf", 8.0,
                                            "inconsistent_nees"): 3}), [name])[name]
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 2
    for algorithm in ALGORITHMS:
        label = look(algorithm).label
        handle = _legend_handle(fig, label)
        for ax in panels:
            line = _curve(ax, algorithm)
            assert _legend_look(line, at_legend_scale=True) == _legend_look(handle), \
                (algorithm, ax.get_title())
    assert _curve(panels[0], "paper_approx/mgekf").get_linewidth() > \
        line_kwargs("paper_approx/mgekf")["linewidth"]  # it lies on the EKF in the gate panel


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


def test_a_range_note_hides_no_curve(run_50):
    """The note's white box hid the sqrt PCRLB under it (twin_sensor_baseline, 50 km): the
    note is outlined in white, letter by letter, with no box."""
    fig = report.figures(run_50, ["range_error_vs_time"])["range_error_vs_time"]
    notes = [t for ax in fig.axes for t in ax.texts if "corr." in t.get_text()
             or "below the bound" in t.get_text()]
    assert len(notes) == 3
    for note in notes:
        assert note.get_bbox_patch() is None and note.get_path_effects() == report.NOTE_HALO


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
        "manoeuvring index 0.2, filter q 900 m^2/s^4, mean 40 false returns per scan"
    # the truth's q swept alone: the index said nothing of the filter's q, nor the title
    assert report._point_title({**params, "filter.q": 900.0}, ["target.q"], matched=False) \
        == "manoeuvring index 0.2, filter q 900 m^2/s^4"


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
        assert "truth q = filter q" in fig.get_suptitle(), name
        titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
        assert all(t.startswith("manoeuvring index") and "filter q" not in t for t in titles)


@pytest.mark.slow
@pytest.mark.parametrize("fixture", ["run_50", "run_wide", "run_hard"])
def test_every_figure_prints_its_smallest_text_at_6_5_pt_without_overlaps(fixture, request):
    """The three-panel figures were 11.25 in wide, their 7-9 pt text 4.5-5.7 pt once printed
    7.16 in wide: every figure is now at most 8.7 in wide, its notes at 8 pt, so its
    smallest text prints at 6.5 pt or more, and no text overlaps another. Everything drawn
    lies inside the canvas (the range and final-RMSE figures drew an empty unclipped
    triangle line per algorithm without a past-the-top mark, whose marker box lay at the
    figure's corner, 0.035 in outside it)."""
    run = request.getfixturevalue(fixture)
    with context():  # drawn as trackfuse.reports draws them
        drawn = {name: fig for name, fig in report.figures(run, EXPERIMENT.figures).items()
                 if not isinstance(fig, str)}
        assert len(drawn) >= 3
        for name, fig in drawn.items():
            size, text = smallest_printed_text(fig)
            assert size >= 6.5, (name, fig.get_figwidth(), text)
            assert text_overlaps(fig) == [], name
            assert inside_canvas(fig), name

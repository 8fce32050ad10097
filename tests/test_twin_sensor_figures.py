"""Axes of the twin_sensor figures: every drawn interval fits its axis or is marked, every
legend entry can be seen."""

from dataclasses import replace

import pandas as pd
import pytest
from matplotlib.colors import to_hex
from matplotlib.container import ErrorbarContainer

from trackfuse import harness
from trackfuse.experiments.twin_sensor import EXPERIMENT, report
from trackfuse.plots.algorithms import line_kwargs
from trackfuse.plots.style import text_overlaps
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
            assert top == 15.0 or top in ax.get_yticks(), (name, top)  # stretched: to a tick
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

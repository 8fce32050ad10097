"""The report kit's additions for the esm_radar, passive_assoc and passive_sd figures:
rates derived from trials, ticks a reader can read, a mark for a markerless method."""

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from trackfuse.reportkit import axes as kit_axes
from trackfuse.reportkit import render
from trackfuse.reportkit.derived import Rate, rate_rows
from trackfuse.reportkit.looks import Look
from trackfuse.reportkit.typography import plain
from trackfuse.stats import wilson_interval


def test_a_short_symlog_grid_is_ticked_at_every_value_a_long_one_at_powers():
    """0, 25, ..., 500 spans one power of 10: ticked 0 and 100 alone a reader cannot place
    the points; 1 to 10^4 over 9 values is ticked at its powers."""
    short = np.array([0.0, 25.0, 50.0, 100.0, 200.0, 500.0])
    assert kit_axes._ticks(short, "symlog") == list(short)
    long = np.geomspace(1.0, 1e4, 9)
    assert kit_axes._ticks(long, "log") == [1.0, 10.0, 100.0, 1000.0, 10000.0]


@pytest.mark.parametrize(("low", "high", "only_powers"), [(1e-5, 1.0, True), (0.1, 5.0, False)])
def test_a_log_y_axis_over_many_decades_is_ticked_at_powers_only(low, high, only_powers):
    ax = Figure().subplots()
    ax.plot([0, 1], [low, high])
    kit_axes.y_log(ax, "log")
    ticks = [t for t in ax.get_yticks() if low <= t <= high]
    assert all(np.isclose(np.log10(t), round(np.log10(t))) for t in ticks) == only_powers


def test_a_markerless_method_drawn_on_categories_keeps_a_visible_mark():
    """An exact optimum (no marker, dashed) on unjoined categories is a bar at its mean, so
    its legend entry shows something."""
    ax = Figure().subplots()
    look = Look("exact optimum", "#000000", "", "reference")
    render._series(ax, np.array([0.0, 1.0]), np.array([0.5, 0.6]), np.array([0.4, 0.5]),
                   np.array([0.6, 0.7]), look, categories=True)
    (line,) = ax.get_lines()
    assert line.get_marker() == "_" and line.get_linestyle() == "None"


def test_derived_rates_are_the_share_of_rows_with_wilson_intervals():
    trials = pd.DataFrame({"point": [0] * 6, "algorithm": ["a"] * 3 + ["b"] * 3,
                           "decided": [1, 1, 0, 1, 1, 1], "correct": [1, 0, 0, 1, 1, 0]})
    wrong = Rate("wrong", "false", lambda t: (t["decided"] == 1) & (t["correct"] == 0))
    missed = Rate("missed", "missed", lambda t: t["decided"] == 0, ("a",))
    rows = rate_rows(trials, ["point", "algorithm"], [wrong, missed]).set_index(
        ["metric", "algorithm"])
    assert rows.loc[("wrong", "a"), "mean"] == pytest.approx(1 / 3)
    low, high = wilson_interval(1, 3)
    assert (rows.loc[("wrong", "b"), ["ci_low", "ci_high"]].tolist()
            == pytest.approx([float(low), float(high)]))
    assert ("missed", "b") not in rows.index  # b always decides: no curve for it
    assert rows.loc[("missed", "a"), "n"] == 3


def test_plain_unwraps_mathtext_for_a_table_cell():
    assert plain("$P_D$ = 0.95") == "P_D = 0.95"
    assert plain(r"$\sigma_R/R$") == "σ_R/R"

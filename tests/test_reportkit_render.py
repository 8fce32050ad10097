"""The report kit's renderer (trackfuse/reportkit/render.py) on a toy run: what a declared
Plot selects, transforms and adds, judged on the drawn artists."""

import numpy as np
import pytest
from figure_checks import journal_problems
from toy_experiments import GAUSSIAN

from trackfuse import harness
from trackfuse.reportkit import render
from trackfuse.reportkit.spec import Plot, Reference
from trackfuse.rundata import RunData

BASE = {**GAUSSIAN.defaults(), "n": 4}


@pytest.fixture(scope="module")
def grid(tmp_path_factory) -> RunData:
    """mu 1, 2, 3 by sigma 1, 2, 4: three panels against sigma."""
    return harness.run_data(tmp_path_factory.mktemp("grid"), GAUSSIAN, BASE,
                            {"mu": [1.0, 2.0, 3.0], "sigma": [1.0, 2.0, 4.0]}, trials=6, seed=1)


def _curve(ax, label: str):
    return next(line for line in ax.get_lines() if line.get_label() == label)


def test_a_tuple_held_keeps_only_those_panels(grid):
    fig = render.draw(grid, Plot(("estimate",), "sigma", at={"mu": (1.0, 3.0)}))
    titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
    assert titles == ["mu = 1 m", "mu = 3 m"]
    assert journal_problems(fig) == []


def test_a_root_plot_draws_the_square_root_of_the_mean_and_names_it(grid):
    plot = Plot(("estimate",), "sigma", ("mean",), at={"mu": 3.0}, root="root of estimate")
    fig = render.draw(grid, plot)
    ax = fig.axes[0]
    rows = grid.summary[(grid.summary["metric"] == "estimate") & (grid.summary["mu"] == 3.0)
                        & (grid.summary["algorithm"] == "mean")].sort_values("sigma")
    drawn = _curve(ax, render.looks_of(GAUSSIAN, "mean").label).get_ydata()
    np.testing.assert_allclose(drawn, np.sqrt(rows["mean"].clip(lower=0)))
    assert ax.get_ylabel().startswith("root of estimate")


def test_a_band_until_an_x_stops_there_and_decorate_draws_in_every_panel(grid):
    seen = []

    def decorate(ax, metric, cell, factor):
        seen.append((metric, cell["mu"], factor))
        ax.plot([1, 4], [0, 0], label="added")

    plot = Plot(("covered",), "sigma", references=(Reference(band=(0.9, 1.0), until=2.0,
                                                             label="claim"),))
    fig = render.draw(grid, plot, decorate=decorate)
    assert seen == [("covered", mu, 100.0) for mu in (1.0, 2.0, 3.0)]
    for ax in (a for a in fig.axes if a.get_visible()):
        claim = next(c for c in ax.collections if c.get_label() == "claim")
        x, y = claim.get_paths()[0].vertices.T
        assert (x.min(), x.max(), y.min(), y.max()) == (1.0, 2.0, 90.0, 100.0)


def test_keys_zipped_with_x_are_not_panels(tmp_path):
    run = harness.run_data(tmp_path, GAUSSIAN, BASE, {"mu": [1.0, 2.0, 3.0],
                                                      "sigma": [1.0, 2.0, 4.0]},
                           trials=4, seed=1, sweep_mode="zip")
    fig = render.draw(run, Plot(("estimate",), "sigma", together=("mu",)))
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 1
    line = _curve(fig.axes[0], render.looks_of(GAUSSIAN, "mean").label)
    assert list(line.get_xdata()) == [1.0, 2.0, 4.0]


def test_a_long_panel_title_breaks_after_a_comma():
    assert render.wrapped("q = 40000 m²/s⁴, filter q = 40000 m²/s⁴, clutter = 40", 2.0) == \
        "q = 40000 m²/s⁴,\nfilter q = 40000 m²/s⁴,\nclutter = 40"

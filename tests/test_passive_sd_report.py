"""Figures and tables of passive_sd runs (trackfuse/experiments/passive_sd/report.py,
docs/papers/sd_assignment.md)."""

import matplotlib
import pytest
from figure_checks import inside_canvas, smallest_printed_text, text_overlaps
from matplotlib.backends.backend_agg import FigureCanvasAgg

from trackfuse import harness
from trackfuse.experiments import get
from trackfuse.experiments.passive_sd import report
from trackfuse.plots.style import context

EXPERIMENT = get("passive_sd")


@pytest.fixture(scope="module")
def geometry_run(tmp_path_factory):
    """Two target counts by two baselines, 4 trials each."""
    return harness.run_data(tmp_path_factory.mktemp("sd"), "passive_sd",
                            {"noise.sigma": 0.01},
                            {"targets.n": [4, 6], "sensor3.baseline": [0.05, 20.0]},
                            trials=4, seed=3)


def drawn(run, names):
    with context():
        figs = report.figures(run, names)
    for fig in figs.values():
        if isinstance(fig, matplotlib.figure.Figure):
            FigureCanvasAgg(fig)
            fig.canvas.draw()
    return figs


def test_every_figure_is_drawn_cleanly(geometry_run):
    figs = drawn(geometry_run, list(EXPERIMENT.figures))
    assert set(figs) == set(EXPERIMENT.figures)
    for name, fig in figs.items():
        assert isinstance(fig, matplotlib.figure.Figure), (name, fig)
        assert text_overlaps(fig) == [], name
        assert inside_canvas(fig), name
        assert smallest_printed_text(fig)[0] >= 6.5, (name, smallest_printed_text(fig))
    ghosts = figs["ghosts"]
    assert [ax.get_title() for ax in ghosts.axes if ax.get_visible()] == [
        "n = 4", "n = 6"]
    assert all(ax.get_xscale() == "linear" for ax in ghosts.axes)  # two values: no log axis


def test_without_a_swept_key_the_curves_say_why(tmp_path):
    run = harness.run_data(tmp_path, "passive_sd", {"targets.n": 3}, trials=2, seed=1)
    figs = drawn(run, ["ghosts", "found", "duality_gap"])
    assert isinstance(figs["ghosts"], str) and "\n" not in figs["ghosts"]
    assert isinstance(figs["duality_gap"], matplotlib.figure.Figure)


def test_versus_exact_summarises_the_relaxation_per_point(geometry_run):
    table = report.tables(geometry_run)["versus_exact"]
    assert list(table["point"]) == [0, 1, 2, 3]
    assert (table["trials"] == 4).all()
    assert table["at_opt"].between(0, 1).all() and (table["max_gap"] >= table["mean_gap"]).all()

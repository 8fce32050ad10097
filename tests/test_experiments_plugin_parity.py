"""A plugin has what the built-ins have: an RMS metric with the built-ins' bootstrap-t
interval, found by plot/compare/the harness wherever they run; list's wording; a --set of
several values hints --sweep."""

from __future__ import annotations

import json
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest
from conftest import trackfuse

from trackfuse import harness
from trackfuse.config import SET, ConfigError, load
from trackfuse.experiments.base import Metric
from trackfuse.runfiles import read_run
from trackfuse.stats import rmse_intervals
from trackfuse.summary import summarize

PLUGIN = textwrap.dedent('''
    """An error of spread ``sigma`` summed up as a root mean square."""
    from trackfuse.experiments.base import Experiment, Metric, Param


    def run_trial(params, streams):
        error = params["sigma"] * float(streams.common.normal()) + 0.5
        return [{"algorithm": "a", "err": error, "err_mean": error}]


    EXPERIMENT = Experiment(
        name="rmsplug", title="An RMS metric",
        params=(Param("sigma", 2.0, "spread of the error", "m", low=0.0),),
        run_trial=run_trial,
        metrics=(Metric("err", "m", "an error, summed up as RMS", better="lower",
                        aggregate="rms"),
                 Metric("err_mean", "m", "the same error, averaged")))
''')


@pytest.fixture
def plugin_folder(tmp_path):
    folder = tmp_path / "plugin"
    folder.mkdir()
    (folder / "rmsplug.py").write_text(PLUGIN)
    (folder / "rms.yaml").write_text("experiment: rmsplug:EXPERIMENT\ntrials: 40\nseed: 3\n")
    yield folder
    sys.modules.pop("rmsplug", None)
    while str(folder) in sys.path:
        sys.path.remove(str(folder))


def test_an_rms_metric_is_summarized_as_the_builtins_rmse(plugin_folder, tmp_path):
    other = tmp_path / "elsewhere"
    other.mkdir()
    trials, summary = harness.run(f"{plugin_folder / 'rmsplug.py'}:EXPERIMENT", trials=40,
                                  seed=3)  # by its file, from any folder
    err = trials["err"].to_numpy()
    row = summary.set_index("metric").loc["err"]
    low, high = rmse_intervals([err**2])[0]
    assert row["mean"] == pytest.approx(np.sqrt(np.mean(err**2)), rel=1e-12)
    assert (row["ci_low"], row["ci_high"]) == pytest.approx((low, high), rel=1e-12)
    assert row["interval"] == "bootstrap-t rms" and np.isnan(row["std"])
    plain = summary.set_index("metric").loc["err_mean"]
    assert plain["mean"] == pytest.approx(err.mean()) and plain["interval"] == "t"


def test_an_rms_summary_is_the_same_in_chunks():
    rng = np.random.default_rng(1)
    frame = pd.DataFrame({"point": np.repeat([0, 1], 50), "algorithm": "a",
                          "trial": np.tile(np.arange(50), 2), "e": rng.normal(size=100)})
    whole, _ = summarize(frame, ["point", "algorithm"], rms=["e"])
    chunked, _ = summarize(frame, ["point", "algorithm"], rms=["e"], chunk_rows=7)
    pd.testing.assert_frame_equal(whole, chunked, rtol=1e-12)
    assert whole["mean"].tolist() == pytest.approx(
        [np.sqrt(np.mean(frame["e"][frame.point == p] ** 2)) for p in (0, 1)])


def test_an_rms_metric_must_be_an_error_in_a_unit():
    with pytest.raises(ValueError, match="aggregate"):
        Metric("hit", "1", "a hit", binary=True, aggregate="rms")
    with pytest.raises(ValueError, match="allowed: mean, rms"):
        Metric("e", "m", "an error", aggregate="median")


@pytest.mark.slow
def test_plot_and_compare_find_the_plugin_from_the_run_wherever_they_run(plugin_folder,
                                                                        tmp_path):
    out = tmp_path / "out"
    for sigma in ("2.0", "3.0"):
        ran = trackfuse("run", "rms.yaml", f"sigma={sigma}", "--out", out, "--no-plots",
                        "--no-progress", "--workers", "1", cwd=plugin_folder)
        assert ran.returncode == 0, ran.stderr
    # by sigma: two runs can start within the manifest's one-second resolution
    base, new = sorted((out / "rms").iterdir(),
                       key=lambda p: float(read_run(p).config["params"]["sigma"]))
    assert json.loads((base / "manifest.json").read_text())["plugin_folder"] == \
        str(plugin_folder.resolve())
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    compared = trackfuse("compare", base, new, "--json", cwd=elsewhere)
    assert compared.returncode == 0, compared.stderr
    cells = {c["metric"]: c for c in json.loads(compared.stdout)["cells"]}
    assert cells["err"]["test"] == "paired t on e^2"  # the RMS's mean square is compared
    assert cells["err"]["diff"] > 0 and cells["err_mean"]["test"] == "paired t"
    plotted = trackfuse("plot", base, cwd=elsewhere)
    assert plotted.returncode == 0, plotted.stderr


def test_list_wording_is_generic_and_a_set_of_several_values_hints_sweep(write_config):
    listed = trackfuse("list", "twin_sensor")
    assert "share their clutter" not in listed.stdout  # a plugin may have no clutter
    assert "share their simulated data" in listed.stdout
    cfg = write_config("experiment: toy_gaussian\ntrials: 2\n")
    for value in ("0,5,10", [0.0, 5.0, 10.0]):
        with pytest.raises(ConfigError) as err:
            load(cfg, {"mu": value})
        assert (err.value.source, err.value.key) == (SET, "mu")
        assert err.value.message.endswith("to run each value, sweep it: --sweep mu=0,5,10") \
            or err.value.message.endswith("--sweep mu=0.0,5.0,10.0")
    with pytest.raises(ConfigError) as err:
        load(cfg, {"mu": "x"})
    assert "--sweep" not in err.value.message

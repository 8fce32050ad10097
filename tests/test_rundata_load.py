"""``trackfuse.load``: the public reader of a run folder; importing trackfuse stays light."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import pytest
from toy_experiments import cluttered_trial

import trackfuse
from trackfuse.harness import run_data
from trackfuse.results import RunFolderError
from trackfuse.seeding import trial_streams


def test_load_returns_the_frames_and_config_of_a_run(tmp_path):
    folder = run_data(tmp_path, "toy_gaussian", sweep={"mu": [0.0, 1.0]}, trials=6).path
    run = trackfuse.load(folder)
    assert run.config["experiment"] == "toy_gaussian" and run.manifest.status == "complete"
    assert len(run.trials) == 2 * 6 * 2  # points x trials x algorithms
    assert {"metric", "mean", "ci_low", "ci_high", "interval"} <= set(run.summary.columns)
    assert (run.summary["ci_low"] <= run.summary["mean"]).all()
    assert run.summary.query("metric == 'covered' and algorithm == 'mean'")["interval"].eq(
        "wilson").all()
    (folder / "summary.csv").write_text("point,metric\n")
    with pytest.raises(RunFolderError, match="summary.csv"):
        trackfuse.load(folder)


def test_a_runs_draw_points_re_simulate_its_trials(tmp_path):
    run = trackfuse.load(run_data(tmp_path, "toy_cluttered", trials=4, seed=6,
                                  sweep={"gain": [1.0, 2.0], "density": [1.0, 3.0]}).path)
    assert run.draw_points == [0, 1, 0, 1]  # gain draws nothing, density does
    for (point, trial), row in run.trials.set_index(["point", "trial"]).iterrows():
        streams = trial_streams(6, run.draw_points[point], trial)
        again = cluttered_trial(run.point_params(point), streams)[0]
        assert (again["uniform"], again["estimate"]) == (row["uniform"], row["estimate"])
    assert run.manifest.draw_points == [0, 1, 0, 1]


def test_draw_points_come_from_the_manifest_before_the_current_flags(tmp_path):
    run = run_data(tmp_path, "toy_cluttered", trials=2, seed=6,
                   sweep={"gain": [1.0, 2.0], "density": [1.0, 3.0]})
    recorded = dataclasses.replace(run, manifest=dataclasses.replace(run.manifest,
                                                                     draw_points=[0, 1, 2, 3]))
    assert recorded.draw_points == [0, 1, 2, 3]  # as if gain had drawn when it ran
    older = dataclasses.replace(run, manifest=dataclasses.replace(run.manifest,
                                                                  draw_points=None))
    assert older.draw_points == [0, 1, 0, 1]


def test_importing_the_config_layer_loads_no_pandas_scipy_or_matplotlib():
    code = ("import sys, trackfuse, trackfuse.config, trackfuse.experiments\n"
            "trackfuse.experiments.listing()\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'pandas', 'scipy', 'matplotlib', 'numpy'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]", out
    with pytest.raises(AttributeError):
        trackfuse.no_such_thing  # noqa: B018

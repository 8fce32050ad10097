"""The in-memory harness runs exactly the Experiment object it is given."""

from __future__ import annotations

import dataclasses

import pytest

from trackfuse import experiments, harness
from trackfuse.experiments.base import Experiment, Metric, Param
from trackfuse.experiments.esm_radar import EXPERIMENT as ESM_RADAR


def _constant(value: float) -> Experiment:
    """An experiment named ``harness_probe`` whose every trial reports ``value``."""
    def trial(params, streams) -> list[dict]:
        return [{"algorithm": "a", "value": value}]
    return Experiment(name="harness_probe", title="probe", params=(Param("x", 0.0, "x", "1"),),
                      run_trial=trial, metrics=(Metric("value", "1", "the constant"),))


def test_two_experiments_of_one_name_each_run_their_own_trials():
    """The harness registered the first object under its name and looked the name up
    afterwards: the second object of the same name silently ran the first one's trials."""
    first, _ = harness.run(_constant(1.0), trials=2)
    second, summary = harness.run(_constant(2.0), trials=2)
    assert first["value"].tolist() == [1.0, 1.0]
    assert second["value"].tolist() == [2.0, 2.0]
    assert summary.loc[summary["metric"] == "value", "mean"].tolist() == [2.0]
    assert "harness_probe" not in experiments.names()  # the global registry is left alone


def test_a_changed_copy_of_a_built_in_runs_the_copy(tmp_path):
    """A `dataclasses.replace` of a built-in ran the built-in (found by its name)."""
    def abstaining(params, streams) -> list[list[dict]]:
        return [[{**row, "chosen": 0, "correct": 0, "decided": 0} for row in rows]
                for rows in ESM_RADAR.run_batch(params, streams)]
    copy = dataclasses.replace(ESM_RADAR, run_batch=abstaining)
    params = {"scan.count": 5}
    run = harness.run_data(tmp_path / "copy", copy, params, trials=3)
    assert run.experiment is copy
    assert len(run.trials) == 9 and (run.trials["decided"] == 0).all()
    builtin, _ = harness.run(ESM_RADAR, params, trials=3)
    assert len(builtin) == 9 and (builtin["decided"] == 1).all()
    assert experiments.get("esm_radar") is ESM_RADAR


def test_a_name_still_runs_the_registered_experiment():
    trials, _ = harness.run("esm_radar", {"scan.count": 5, "algorithms": ["chi2"]}, trials=2)
    assert trials["algorithm"].tolist() == ["chi2", "chi2"]
    with pytest.raises(ValueError, match="harness: experiment: unknown experiment"):
        harness.run("harness_probe")

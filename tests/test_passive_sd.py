"""Experiment passive_sd (docs/papers/sd_assignment.md): S-D assignment of S passive sensors
beside the exact two-sensor assignment, on the same scans."""

import numpy as np
import pytest

from trackfuse.experiments import get
from trackfuse.experiments.passive_assoc.model import run_trial as run_passive_assoc
from trackfuse.experiments.passive_sd.model import run_trial, score, sensor_positions
from trackfuse.seeding import trial_streams

EXPERIMENT = get("passive_sd")


def params(**changes):
    p = EXPERIMENT.defaults()
    p.update(changes)
    return p


def rows_of(p, trial=0, seed=5):
    return {r["algorithm"]: r for r in run_trial(p, trial_streams(seed, 0, trial))}


def test_every_algorithm_reports_every_metric():
    rows = rows_of(params(**{"targets.n": 6}))
    assert set(rows) == {"sd_lagrangian", "sd_exact", "exact_2d"}
    for row in rows.values():
        assert not EXPERIMENT.missing_metrics(row)
    lagrangian, exact = rows["sd_lagrangian"], rows["sd_exact"]
    assert lagrangian["objective"] <= exact["objective"] + 1e-9 * abs(exact["objective"])
    assert lagrangian["at_opt"] == int(np.isclose(lagrangian["objective"], exact["objective"],
                                                  rtol=1e-9))
    assert lagrangian["duality_gap"] >= 0.0 and exact["duality_gap"] == 0.0
    assert np.isnan(rows["exact_2d"]["at_opt"])


def test_exact_2d_is_paper_002s_exact_solution_of_the_same_scan():
    """Sensors 1 and 2 see the scan that passive_assoc simulates from the same streams."""
    for trial in range(3):
        mine = rows_of(params(**{"targets.n": 8}), trial)["exact_2d"]
        theirs = run_passive_assoc(
            {**get("passive_assoc").defaults(), "scene.mode": "random", "targets.n": 8,
             "algorithms": ["exact"]}, trial_streams(5, 0, trial))[0]
        assert mine["accuracy"] == pytest.approx(theirs["accuracy"])
        assert mine["objective"] == pytest.approx(theirs["objective"], rel=1e-9)
        assert mine["tuples"] == theirs["pairs"]


def test_two_sensors_make_the_relaxation_the_exact_2d_assignment():
    rows = rows_of(params(**{"sensors.n": 2, "targets.n": 8}))
    for metric in ("accuracy", "ghost_rate", "found", "tuples", "objective"):
        assert rows["sd_lagrangian"][metric] == pytest.approx(rows["exact_2d"][metric])
    assert rows["sd_lagrangian"]["iterations"] == 1


def test_the_baseline_moves_only_sensor_3():
    near, far = sensor_positions(params(**{"sensor3.baseline": 0.05})), \
        sensor_positions(params(**{"sensor3.baseline": 20.0}))
    assert np.array_equal(near[:2], far[:2]) and near.shape == (3, 3)
    assert far[2].tolist() == [20000.0, 0.0, 0.0]
    near_2d = rows_of(params(**{"sensor3.baseline": 0.05}))["exact_2d"]
    far_2d = rows_of(params(**{"sensor3.baseline": 20.0}))["exact_2d"]
    results = [k for k in near_2d if not k.endswith("_time_s") and k != "at_opt"]
    assert [near_2d[k] for k in results] == [far_2d[k] for k in results]


def test_a_distant_third_sensor_removes_ghosts_that_two_sensors_make():
    p = params(**{"targets.n": 20, "noise.sigma": 0.01, "algorithms": ["sd_exact", "exact_2d"],
                  "sensor3.baseline": 20.0})
    ghosts = {"sd_exact": 0, "exact_2d": 0}
    for trial in range(8):
        for name, row in rows_of(p, trial).items():
            ghosts[name] += row["ghosts"]
    assert ghosts["sd_exact"] < ghosts["exact_2d"]


def test_score_counts_ghosts_accuracy_and_found_targets():
    labels = (np.array([0, 1, -1]), np.array([1, 0]), np.array([0]))
    tuples = np.array([[1, 2, 1],   # target 0 on all three sensors: right
                       [2, 0, 0],   # target 1 on sensor 1 alone: its true tuple has sensor 2
                       [0, 1, 0],
                       [3, 0, 0]])  # the false alarm alone: right
    got = score(tuples, labels, n_targets=2)
    assert got["accuracy"] == pytest.approx(4 / 6)
    assert got["ghosts"] == 0 and got["tuples"] == 1 and got["found"] == 0.5
    ghost = np.array([[1, 1, 0], [2, 2, 1], [3, 0, 0]])  # targets 0+1, then 1+0+0
    got = score(ghost, labels, n_targets=2)
    assert got["ghosts"] == 2 and got["ghost_rate"] == 1.0 and got["found"] == 0.0
    assert got["correct"] == 0


def test_the_preload_compiles_the_versions_a_trial_calls(monkeypatch):
    """The fork server's preload must compile exactly the kernels' versions a trial uses,
    else every worker compiles its own."""
    from numba import typeof

    from trackfuse import precompile
    from trackfuse.association import sd_assignment, sd_costs

    def types_of(call) -> dict:
        seen = {"reduce_tail": set(), "_combination_fit": set()}
        with monkeypatch.context() as m:
            for module, name in ((sd_assignment, "reduce_tail"), (sd_costs, "_combination_fit")):
                def record(*args, _compiled=getattr(module, name), _name=name):
                    seen[_name].add(tuple(typeof(a) for a in args))
                    return _compiled(*args)
                m.setattr(module, name, record)
            call()
        return seen

    trial = types_of(lambda: rows_of(params(**{"targets.n": 4})))
    ahead = types_of(precompile.load_sd_kernels)
    assert all(trial.values()) and trial == ahead


def test_the_marginal_likelihood_declares_fewer_ghosts_with_three_sensors():
    """The fitted ratio charges nothing for a tuple's free position, so a target's
    measurement and a false alarm make a cheap pair; integrating the position out charges
    every declared tuple (docs/papers/sd_assignment.md)."""
    ghosts = {}
    for position in ("fitted", "marginal"):
        p = params(**{"targets.n": 10, "noise.sigma": 0.01, "algorithms": ["sd_exact"],
                      "assoc.position": position})
        ghosts[position] = sum(rows_of(p, trial)["sd_exact"]["ghosts"] for trial in range(8))
    assert ghosts["marginal"] < ghosts["fitted"]

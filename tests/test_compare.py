"""Comparing two runs: intervals, pairing, and the regression gate's error rates."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import trackfuse
from trackfuse import harness
from trackfuse.compare import _with_fixed_keys, compare_runs, compare_trials

KEYS = ["sigma", "algorithm"]


def frame(values, correct=None, sigma=1.0, algorithm="a"):
    """A trials.csv-like frame: one row per trial of one cell (plus a 0/1 metric)."""
    n = len(values)
    data = {"point": 0, "trial": np.arange(n), "sigma": sigma, "algorithm": algorithm,
            "error_m": values}
    if correct is not None:
        data["correct"] = correct
    return pd.DataFrame(data)


def gate(base, new, paired=True, **kw):
    return compare_trials(base, new, KEYS, binary=["correct"],
                          better={"error_m": "lower", "correct": "higher"}, paired=paired, **kw)


def test_identical_runs_show_no_difference_and_no_regression():
    rng = np.random.default_rng(0)
    base = frame(rng.normal(10, 2, 50), (rng.random(50) < 0.7).astype(int))
    result = gate(base, base.copy())
    assert result.regressions.empty and result.paired and result.gated == 2
    assert (result.cells["diff"] == 0).all()
    assert (result.cells["verdict"] == "no significant change").all()


def test_a_planted_regression_is_found_in_both_directions_and_not_reversed():
    rng = np.random.default_rng(1)
    x = rng.normal(10, 2, 200)
    ok = (rng.random(200) < 0.8).astype(int)
    worse_ok = np.where(rng.random(200) < 0.25, 0, ok)  # about 20 points less correct
    result = gate(frame(x, ok), frame(x + 1.0 + rng.normal(0, 0.5, 200), worse_ok))
    verdict = result.cells.set_index("metric")["verdict"]
    assert verdict["error_m"] == "regression" and verdict["correct"] == "regression"
    mirror = gate(frame(x + 1.0, worse_ok), frame(x, ok)).cells.set_index("metric")
    assert (mirror["verdict"] == "improvement").all()


def test_tolerance_accepts_a_small_worsening():
    rng = np.random.default_rng(2)
    x = rng.normal(10, 2, 300)
    base, new = frame(x), frame(x + 0.2 + rng.normal(0, 0.1, 300))
    assert gate(base, new).cells["verdict"].iloc[0] == "regression"
    assert gate(base, new, tolerance={"error_m": 0.5}).cells["verdict"].iloc[0] == \
        "no significant change"


def null_and_shifted(shift: float, cells: int = 300, n: int = 40, seed: int = 7):
    """``cells`` independent algorithms, paired noise; ``new`` is worse by ``shift`` sd."""
    rng = np.random.default_rng(seed)
    x = rng.normal(0, 1, (cells, n))
    y = x + shift + rng.normal(0, 1, (cells, n))
    names = [f"a{i}" for i in range(cells)]
    return (pd.concat([frame(x[i], algorithm=a) for i, a in enumerate(names)]),
            pd.concat([frame(y[i], algorithm=a) for i, a in enumerate(names)]))


def test_per_cell_false_alarm_rate_is_near_the_nominal_level_and_power_is_high():
    base, new = null_and_shifted(0.0)
    rate = len(gate(base, new, family_wise=False).regressions) / 300
    assert 0.02 <= rate <= 0.09
    base, new = null_and_shifted(0.6)
    assert len(gate(base, new, family_wise=False).regressions) / 300 >= 0.9


@pytest.mark.slow
def test_family_wise_gate_stays_quiet_over_many_null_cells():
    """300 null cells: Bonferroni keeps the chance of any alarm below alpha; over ten
    independent families at most one alarm is expected, and a real shift is still found."""
    alarms = sum(not gate(*null_and_shifted(0.0, seed=s)).regressions.empty for s in range(10))
    assert alarms <= 2
    assert len(gate(*null_and_shifted(1.5)).regressions) >= 250


def test_unpaired_comparison_matches_points_by_swept_value_not_index():
    rng = np.random.default_rng(4)
    base = pd.concat([frame(rng.normal(0, 1, 30), sigma=s).assign(point=i)
                      for i, s in enumerate((1.0, 2.0))])
    new = pd.concat([frame(rng.normal(0, 1, 25) + (3 if s == 2.0 else 0), sigma=s)
                     .assign(point=i) for i, s in enumerate((2.0, 1.0))])
    cells = gate(base, new, paired=False).cells.set_index("sigma")
    assert cells.loc[2.0, "verdict"] == "regression"
    assert cells.loc[1.0, "verdict"] == "no significant change"
    assert (cells["test"] == "Welch t").all() and (cells["n_new"] == 25).all()


def test_failed_trials_are_left_out():
    base = frame(np.arange(10.0))
    new = frame(np.arange(10.0)).assign(status=["ok"] * 9 + ["failed"])
    assert gate(base, new).cells["n_new"].iloc[0] == 9
    lost = gate(base, new.assign(status="failed"))  # every trial of the cell failed
    assert lost.cells.empty and lost.only_base == 1 and lost.gate_failure() is not None


def test_compare_runs_takes_binary_metrics_and_directions_from_the_experiment(tmp_path):
    sweep = {"mu": [0.0, 1.0]}
    base = harness.run_data(tmp_path / "a", "toy_gaussian", {"n": 5}, sweep, trials=30, seed=3)
    same = harness.run_data(tmp_path / "b", "toy_gaussian", {"n": 5, "label": "b"}, sweep,
                            trials=30, seed=3)
    result = compare_runs(base, same)
    assert result.paired
    cells = result.cells.set_index(["mu", "algorithm", "metric"])
    assert (cells.xs("covered", level="metric")["better"] == "higher").all()
    assert (cells.xs("estimate", level="metric")["better"] == "").all()
    assert cells.xs("covered", level="metric")["test"].str.contains("McNemar").all()
    assert (cells["diff"] == 0).all() and "regression" not in set(cells["verdict"])
    other = harness.run_data(tmp_path / "c", "toy_gaussian", {"n": 5}, sweep, trials=30,
                             seed=4)
    assert not compare_runs(base, other).paired


def test_a_key_one_run_sweeps_and_the_other_fixes_is_compared_at_the_fixed_value(tmp_path):
    """NEW fixing BASE's swept key (`--set gain=2`) was refused ('BASE sweeps gain, NEW
    sweeps no key'). gain draws nothing, so NEW's trials are BASE's at gain=2, not gain=1:
    every compared difference is 0 only if the cells line up at the fixed value."""
    base = harness.run_data(tmp_path / "a", "toy_cluttered", {}, {"gain": [1.0, 2.0]},
                            trials=12, seed=3)
    fixed = harness.run_data(tmp_path / "b", "toy_cluttered", {"gain": 2.0}, trials=12,
                             seed=3)
    result = compare_runs(base, fixed)
    assert len(result.cells) == 3 and set(result.cells["gain"]) == {2.0}
    assert (result.cells["diff"] == 0).all() and result.paired
    assert set(result.only_base_cells["gain"]) == {1.0} and result.only_new == 0
    reverse = compare_runs(fixed, base)
    assert reverse.only_base == 0 and set(reverse.only_new_cells["gain"]) == {1.0}
    # the fixed gain against "(swept)", not the config value BASE never ran at (1.0), and
    # the axis; not an empty sweep
    assert reverse.config_differences == (("params.gain", 2.0, "(swept)"),
                                          ("sweep.gain", None, [1.0, 2.0]))
    listed = SimpleNamespace(trials=base.trials, sweep={}, params={"gain": [1.0, 2.0]})
    with pytest.raises(ValueError, match=r"the other run sweeps gain, which NEW fixes to "
                                         r"\[1.0, 2.0\]; allowed: a key fixed to one"):
        _with_fixed_keys(listed, ["gain"], "NEW")
    with pytest.raises(ValueError, match="the other run sweeps gain, a parameter BASE's "
                                         "experiment does not have"):
        _with_fixed_keys(SimpleNamespace(trials=base.trials, sweep={}, params={}), ["gain"],
                         "BASE")


@pytest.mark.parametrize("paired", [True, False])
def test_a_single_trial_or_an_infinite_value_has_no_p_value(paired):
    """No spread to test against: the p-value is NaN like the interval, not 0."""
    one = gate(frame([1.0]), frame([2.0]), paired=paired).cells
    assert np.isnan(one.loc[one.metric == "error_m", "p_value"]).all()
    inf = gate(frame([1.0, 2.0, 3.0]), frame([1.0, np.inf, 3.0]), paired=paired).cells
    assert np.isnan(inf.loc[inf.metric == "error_m", "p_value"]).all()


def test_a_metric_new_no_longer_produces_is_missing_not_ignored():
    """A metric column NEW lacks was dropped from both runs without a word (only_base 0)."""
    rng = np.random.default_rng(5)
    base = frame(rng.normal(10, 2, 30), (rng.random(30) < 0.7).astype(int))
    result = gate(base, base.drop(columns="correct"))
    assert (result.only_base, result.only_new, len(result.cells)) == (1, 0, 1)
    assert result.gate_failure() == ("1 cells of BASE missing from NEW, e.g. sigma=1.0, "
                                     "algorithm=a, metric=correct")
    assert gate(base.drop(columns="correct"), base).gate_failure() is None


def test_the_gate_fails_when_nothing_is_compared_or_gated():
    rng = np.random.default_rng(6)
    base = frame(rng.normal(10, 2, 30))
    disjoint = gate(base, frame(rng.normal(10, 2, 30), algorithm="b"))
    assert disjoint.cells.empty and (disjoint.only_base, disjoint.only_new) == (1, 1)
    assert disjoint.gate_failure().startswith("nothing compared (the runs share no cell); 1 "
                                              "cells of BASE missing from NEW, e.g. sigma=1.0, "
                                              "algorithm=a, metric=error_m")
    ungated = compare_trials(base, base.copy(), KEYS)
    assert ungated.gated == 0 and ungated.gate_failure().startswith("nothing gated")
    assert gate(base, base.copy()).gate_failure() is None


def test_runs_of_one_seed_and_different_trial_counts_pair_on_the_shared_trials(tmp_path):
    """Trials 0-29 of a 30- and a 60-trial run are the same draws (the seeding depends on the
    root seed and the trial index only), yet were compared unpaired (Welch)."""
    sweep = {"mu": [0.0, 1.0]}
    short = harness.run_data(tmp_path / "a", "toy_gaussian", {"n": 5}, sweep, trials=30,
                             seed=3)
    long = harness.run_data(tmp_path / "b", "toy_gaussian", {"n": 5}, sweep, trials=60,
                            seed=3)
    result = compare_runs(short, long)
    assert result.paired and "both runs have" in result.pairing
    assert (result.cells["n_base"] == 30).all() and (result.cells["n_new"] == 30).all()
    assert (result.cells["diff"] == 0).all()
    estimate = result.cells[result.cells["metric"] == "estimate"]  # paired t: no spread at all
    assert (estimate["ci_low"] == 0).all() and (estimate["ci_high"] == 0).all()
    assert result.config_differences == (("trials", 30, 60),)
    assert compare_runs(long, short).paired  # either way round
    other = harness.run_data(tmp_path / "c", "toy_gaussian", {"n": 6}, sweep, trials=60,
                             seed=4)
    unpaired = compare_runs(short, other)
    assert not unpaired.paired and "seeds differ, 3 and 4" in unpaired.pairing
    assert unpaired.config_differences == (("trials", 30, 60), ("seed", 3, 4),
                                           ("params.n", 5, 6))


def test_compare_refuses_a_run_whose_every_trial_failed_and_a_run_against_itself(tmp_path):
    """A run of failed trials has no row-key columns: compare crashed with a KeyError
    traceback (exit 1, which `--fail-on-regression` reads as a regression); a run compared
    with itself passed the gate, so a typo in a CI script always passed."""
    base = harness.run_data(tmp_path / "a", "toy_gaussian", {"n": 5}, trials=4, seed=3)
    failed = harness.run_data(tmp_path / "b", "toy_gaussian", {"n": 5, "fail_every": 1},
                              trials=4, seed=3)
    for pair in ((base, failed), (failed, base)):
        with pytest.raises(ValueError, match="every trial of the run failed"):
            compare_runs(*pair)
    with pytest.raises(ValueError, match="the same run"):
        compare_runs(base, trackfuse.load(base.path))


def test_a_difference_without_spread_is_judged_by_an_exact_test_not_a_zero_width_t():
    """Two runs of two trials, each run's values equal (seeds 7 and 8 of passive_assoc_ci):
    the Welch interval had zero width and p 0, and the gate called 3 cells regressions."""
    unpaired = gate(frame([1.0, 1.0]), frame([2.0, 2.0]), paired=False).cells.iloc[0]
    assert unpaired["verdict"] == "no significant change"
    assert unpaired["p_value"] == pytest.approx(1 / 3)  # 2 of the 6 splits of 4 values
    assert (unpaired["ci_low"], unpaired["ci_high"]) == (-np.inf, np.inf)
    assert unpaired["test"] == "permutation test (no spread)"
    few = gate(frame(np.arange(4.0)), frame(np.arange(4.0) + 1)).cells.iloc[0]
    assert few["verdict"] == "no significant change" and few["p_value"] == 2 / 16
    # six pairs all worse by 1: the sign test's 2/64 is below the gate's 0.10 (one cell)
    six = gate(frame(np.arange(6.0)), frame(np.arange(6.0) + 1)).cells.iloc[0]
    assert six["verdict"] == "regression" and six["p_value"] == 2 / 64
    assert (six["ci_low"], six["ci_high"]) == (1.0, 1.0)
    many = gate(frame(np.full(30, 5.0)), frame(np.full(30, 4.0)), paired=False).cells.iloc[0]
    assert many["verdict"] == "improvement" and many["test"] == "permutation test (no spread)"


@pytest.mark.parametrize("name", ["value", "metric"])
def test_a_metric_may_be_called_value_or_metric(name):
    """pandas' melt refused a metric column called like its own output column ``value``:
    compare exited 2 for any experiment with such a metric."""
    rng = np.random.default_rng(1)
    base = frame(rng.normal(10, 2, 30)).rename(columns={"error_m": name})
    new = base.assign(**{name: base[name] + 5.0})
    result = compare_trials(base, new, KEYS, better={name: "lower"})
    assert list(result.cells["metric"]) == [name]
    assert result.cells["diff"].iloc[0] == pytest.approx(5.0)
    assert list(result.regressions["metric"]) == [name]

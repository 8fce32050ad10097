"""Paper 001 fixes: static-spread baseline, manoeuvre detector, d/lambda config, paper table."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import trackfuse

from trackfuse.association import ahp
from trackfuse.config import load
from trackfuse.experiments.esm_radar import EXPERIMENT
from trackfuse.experiments.esm_radar.model import alpha_max, differences, manoeuvre_alpha, simulate
from trackfuse.experiments.esm_radar.paper import paper_vs_reproduced
from trackfuse.rundata import RunData
from trackfuse.seeding import trial_streams

ROOT = Path(__file__).resolve().parents[1]


def streams(n, seed=12):
    return [trial_streams(seed, 0, t) for t in range(n)]


def chosen(params, n, seed=12):
    rows = EXPERIMENT.run_trials(params, streams(n, seed))
    return {r["algorithm"]: np.array([t[i]["chosen"] for t in rows])
            for i, r in enumerate(rows[0])}


def test_static_spread_baseline_is_unbiased_and_per_sample_reproduces_old_rate():
    """W001-8. Tracks 1 and 2 fly the same manoeuvre 200 m apart; only the bearing separates
    them, weakly. A baseline with a static spread is not pulled toward either, so it picks
    the true track 2 at least as often as track 1, and its correct rate lies in [0.50, 0.62]
    (the paper reports 0.552). The per-sample spread is sharp when the TDOA-DF range falls
    short, so it prefers the nearer track 1: at this seed the code before the fix chose
    track 2 in exactly 185 of 400 trials."""
    base = dict(EXPERIMENT.defaults(), algorithms=["traditional"])
    out = {rule: chosen(dict(base, **{"baseline.spread": rule}), 400)["traditional"]
           for rule in ("nominal", "trial_mean", "per_sample")}
    for rule in ("nominal", "trial_mean"):
        c = out[rule]
        assert 0.50 <= (c == 2).mean() <= 0.62, rule
        assert (c == 2).sum() > (c == 1).sum(), rule
        assert (c == 2).mean() - (out["per_sample"] == 2).mean() >= 0.04, rule
    assert (out["per_sample"] == 2).sum() == 185
    assert (out["per_sample"] == 1).sum() > (out["per_sample"] == 2).sum()


def test_per_sample_spread_correlates_with_the_range_error_and_static_does_not():
    """The mechanism behind W001-8: the measured TDOA-DF sd tracks the range error."""
    sim = simulate(EXPERIMENT.defaults(), streams(200))
    sd = np.sqrt(sim.P_esm[..., 0, 0])
    err = sim.x_esm[..., 0] - np.hypot(*sim.truth_p[:, 1].T)
    assert np.corrcoef(sd.ravel(), err.ravel())[0, 1] > 0.6
    diff = differences(sim)
    # nominal: one constant per factor; trial_mean: constant over scans and tracks.
    assert diff.var_nominal.shape == (5,) and np.isfinite(diff.var_nominal).all()
    assert diff.var_trial_mean.shape == (200, 1, 1, 5)
    mean_sd = np.sqrt(sim.P_esm[..., 0, 0]).mean()
    assert np.sqrt(diff.var_nominal[0]) == pytest.approx(mean_sd, rel=0.1)


def test_static_spread_without_any_esm_range_stays_finite():
    p = dict(EXPERIMENT.defaults(), algorithms=["traditional", "traditional_5f"],
             **{"esm.min_denominator": 1e5, "baseline.spread": "trial_mean"})
    for trial in EXPERIMENT.run_trials(p, streams(5)):
        for r in trial:
            assert r["chosen"] in (1, 2, 3) and np.isfinite(r["margin"])


def _alpha(amplitude, index, n=300):
    p = dict(EXPERIMENT.defaults(), **{"snake.amplitude": amplitude})
    sim = simulate(p, streams(n, seed=21))
    return manoeuvre_alpha(p, sim.x_esm, sim.P_esm, index)


def test_detector_sees_the_snake_and_matches_its_null_without_it():
    """W001-4. After start-up the windowed NIS averages about 1 (its chi-square null) without
    the weave, and is larger by far more than its spread with the 1 km weave."""
    snake, straight = _alpha(1000.0, "nis_tdoa"), _alpha(0.0, "nis_tdoa")
    defined = np.isfinite(straight).all(axis=0)
    assert not defined[:7].any() and defined[7:].all()  # start-up scans excluded
    assert straight[:, defined].mean() == pytest.approx(1.0, abs=0.1)
    a_max = alpha_max(EXPERIMENT.defaults())[0]
    assert 0.002 < (straight[:, defined] > a_max).mean() < 0.03  # about the 1 % stated
    assert snake[:, defined].mean() > 20 * straight[:, defined].mean()
    assert np.median(snake[:, defined]) > a_max


def test_literal_index_does_not_see_the_snake():
    """The paper's reading is dominated by start-up and blind to the weave."""
    snake, straight = _alpha(1000.0, "literal"), _alpha(0.0, "literal")
    assert abs(np.nanmean(snake) - np.nanmean(straight)) < 0.3
    assert np.nanmean(snake[:, 2]) > 3 * np.nanmean(snake[:, 20:])


def test_dynamic_weights_follow_the_detector():
    p = dict(EXPERIMENT.defaults(), algorithms=["improved", "improved_static"])
    rows = {a: EXPERIMENT.run_trials(dict(p, **{"snake.amplitude": a}), streams(60))
            for a in (1000.0, 0.0)}
    weight = {a: np.mean([t[0]["range_weight_mean"] for t in r]) for a, r in rows.items()}
    assert weight[1000.0] < 0.3 < 0.45 < weight[0.0] <= 0.51
    static = np.mean([t[1]["range_weight_mean"] for t in rows[1000.0]])
    assert static == pytest.approx(0.51, abs=1e-3)


def test_chi2_alpha_max_needs_the_nis_index():
    p = dict(EXPERIMENT.defaults(), **{"alpha.index": "literal"})
    with pytest.raises(ValueError, match="nis_tdoa"):
        alpha_max(p)
    assert alpha_max(dict(p, **{"alpha.max_mode": "fixed"})) == (10.0, "fixed")


@pytest.mark.slow
def test_phase_config_runs_and_the_spacing_sharpens_the_phase_factor(tmp_path):
    """d/lambda reaches the data, in the direction the physics says. With the radar's own
    phase noise (`table`), a tenfold spacing multiplies the T1/T2 phase difference by ten
    (0.017 -> 0.17 rad per scan, docs/papers/esm_radar.md) against the same noise, so the
    ML reference, which weighs phase, leads its runner-up by more: about 50 scans x
    0.17^2 rad^2 / (2 x 1.25 rad^2) = 0.6 nat. Trials are paired (common random numbers),
    so a model ignoring d/lambda would give every trial the same margin at both values."""
    cfg = load(ROOT / "configs" / "esm_radar_phase.yaml")
    assert cfg.trials == 500
    assert cfg.sweep["phase.d_over_lambda"] == [0.5, 5.0]
    assert cfg.sweep["radar.factor_model"] == ["table", "derived"]
    n = 200
    proc = trackfuse("run", ROOT / "configs" / "esm_radar_phase.yaml", "--out", tmp_path,
                     "--workers", "1", "--no-progress", "--trials", str(n))
    assert proc.returncode == 0, proc.stderr
    run = next(tmp_path.glob("*/*/"))
    trials = pd.read_csv(run / "trials.csv")
    assert sorted(trials["phase.d_over_lambda"].unique()) == [0.5, 5.0]
    assert len(trials) == 4 * n * len(cfg.params["algorithms"])
    assert (run / "tables" / "paper_vs_reproduced.csv").exists()
    assert (run / "figures" / "manoeuvre.png").exists()
    margin = trials[trials["algorithm"] == "chi2"].pivot_table(
        index=["radar.factor_model", "trial"], columns="phase.d_over_lambda", values="margin")
    gain = margin[5.0] - margin[0.5]  # nat, per trial
    for model in ("table", "derived"):
        assert (gain.loc[model] != 0).mean() > 0.95, model
    table = gain.loc["table"]
    assert table.mean() > 3 * table.std() / np.sqrt(n)  # larger, beyond Monte Carlo noise
    assert 0.1 < table.mean() < 1.5


def _trials(counts, algorithm, n=500, point=0):
    chosen_ = np.repeat([1, 2, 3], counts)
    assert len(chosen_) == n
    return pd.DataFrame({"point": point, "trial": np.arange(n), "algorithm": algorithm,
                         "target.separation": [200.0, 1000.0][point], "chosen": chosen_,
                         "correct": (chosen_ == 2).astype(int)})


def test_paper_vs_reproduced_table(tmp_path):
    trials = pd.concat([_trials([130, 370, 0], "improved"),
                        _trials([0, 500, 0], "traditional"),
                        _trials([0, 500, 0], "improved", point=1),
                        _trials([0, 500, 0], "traditional", point=1)])
    config = {"experiment": "esm_radar", "params": dict(EXPERIMENT.defaults()),
              "sweep": {"target.separation": [200.0, 1000.0]}}
    run = RunData(tmp_path, config, {})
    run.__dict__["trials"] = trials
    table = paper_vs_reproduced(run)
    t3 = table[table["paper_item"] == "Table 3"].set_index("algorithm")
    assert len(t3) == 2  # only the paper's setting (200 m) is compared
    assert t3.loc["improved", "reproduced"] == 0.740 == t3.loc["improved", "paper_value"]
    assert t3.loc["improved", "verdict"] == "agrees"
    assert t3.loc["traditional", "verdict"] == "differs"  # 1.0 against 0.552
    assert t3.loc["traditional", "trials"] == 500
    ahp_rows = table[table["paper_item"] == "Table 1"].set_index("quantity")
    assert ahp_rows.loc["lambda_max", "verdict"] == "agrees"
    assert ahp_rows.loc["lambda_max", "reproduced"] == pytest.approx(
        ahp.lambda_max(ahp.PAPER_001_JUDGEMENT))
    assert ahp_rows.loc["CR", "verdict"] == "agrees"
    assert ahp_rows.loc["CI", "verdict"] == "agrees"  # from lambda_max as printed: 0.059375
    assert ahp_rows[["ci_low", "ci_high"]].isna().all().all()  # exact values: no interval
    assert ahp_rows.loc["weight: tdoa", "verdict"] == "differs"  # 0.0636 printed as 0.07
    assert (ahp_rows.loc[["weight: range", "weight: speed", "weight: angle",
                          "weight: phase"], "verdict"] == "agrees").all()
    # Fig. 3: improved 0.74 vs traditional 1.0 at 200 m, both 1.0 at 1000 m
    close = table[table["quantity"].str.startswith("improved - traditional at the closest")]
    assert close["verdict"].tolist() == ["differs"] and close["reproduced"].iloc[0] == -0.26
    trend = table[table["quantity"].str.startswith("rate at 200 m minus at 1000 m")]
    # the traditional method is right in every trial at both separations: on 500 runs that
    # excludes a decline of 5 points, the smallest the paper's item counts
    assert trend.set_index("algorithm")["verdict"].to_dict() == {"improved": "agrees",
                                                                  "traditional": "differs"}

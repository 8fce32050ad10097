"""The esm_radar experiment: science properties, batching, tables and figures."""

import numpy as np
import pandas as pd
import pytest
from conftest import another_value

from trackfuse import harness
from trackfuse.association.track_likelihood import abstaining_decision, ml_track_decision
from trackfuse.compare import compare_runs
from trackfuse.experiments import get
from trackfuse.experiments.esm_radar import EXPERIMENT, LOOKS, report
from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    SCAN_SERIES,
    decode_series,
    differences,
    encode_series,
    run_trial,
    simulate,
    static_weights,
    variant_weights,
)
from trackfuse.reported import ESM_RADAR_WEIGHTS
from trackfuse.results import rows_to_csv
from trackfuse.rowtable import columns_csv
from trackfuse.seeding import trial_streams
from trackfuse.stats import holm_adjusted, wilson_interval

ALL = list(ALGORITHMS)


def params(**over):
    p = EXPERIMENT.defaults()
    p["algorithms"] = ALL
    p.update({k.replace("__", "."): v for k, v in over.items()})
    return p


def rngs(n, point=0, seed=11):
    return [trial_streams(seed, point, t) for t in range(n)]


def test_a_parameter_marked_draws_false_changes_no_simulated_data():
    """Sweep points that differ only in such a parameter share their point stream (the
    runner's draw points; this experiment draws nothing from it yet), so it must leave the
    simulated ESM and radar data alone (the manoeuvre index is computed from them)."""
    base = params()
    kept = ("t", "truth_p", "x_esm", "P_esm", "esm_valid", "x_radar", "P_radar", "sd_nominal")
    ref = simulate(base, rngs(3))
    quiet = [p for p in EXPERIMENT.params if not p.draws]
    assert {"baseline.spread", "alpha.index", "algorithms"} <= {p.key for p in quiet}
    for param in quiet:
        got = simulate({**base, param.key: another_value(param, base[param.key])}, rngs(3))
        for name in kept:
            np.testing.assert_array_equal(getattr(got, name), getattr(ref, name),
                                          err_msg=f"{param.key} changes {name}")
    got = simulate({**base, "radar.sigma_range_coef": 0.02}, rngs(3))  # the check sees it
    assert not np.array_equal(got.x_radar, ref.x_radar)


def frame(rows, point=0, extra=None):
    out = []
    for trial, trial_rows in enumerate(rows):
        for r in trial_rows:
            out.append({"point": point, "trial": trial, **(extra or {}), **r})
    return pd.DataFrame(out)


def mini_run(out, base, sweep, trials, seed=5):
    """A complete run folder made by the harness (the real runner)."""
    return harness.run_data(out, EXPERIMENT, base, sweep, trials=trials, seed=seed)


def test_registered_and_schema_valid():
    assert get("esm_radar") is EXPERIMENT
    for p in EXPERIMENT.params:
        assert p.doc
        if p.kind is list:
            assert set(p.default) <= set(p.choices)
        elif p.choices is not None:
            assert p.default in p.choices
        elif p.kind in (int, float):
            assert p.low <= p.default <= p.high


@pytest.mark.parametrize("model", ["table", "derived"])
def test_noise_free_every_algorithm_picks_the_true_track(model):
    rows = EXPERIMENT.run_trials(params(noise__scale=0.0, radar__factor_model=model), rngs(3))
    for trial in rows:
        for r in trial:
            assert (r["chosen"], r["correct"]) == (2, 1), r


def test_noise_free_with_time_alignment_at_different_rates():
    # ESM at 1 s starting 0.5 s after the radar, radar at 2 s: the interpolated radar track 2
    # is close to the truth only with alignment; every algorithm still picks track 2.
    p = params(noise__scale=0.0, esm__offset=0.5, radar__period=2.0, time_align=True)
    for r in EXPERIMENT.run_trials(p, rngs(1))[0]:
        assert r["chosen"] == 2
    sims = {align: simulate(dict(p, time_align=align), rngs(1)) for align in (True, False)}
    truth = simulate(dict(p, **{"radar.period": 0.5}), rngs(1))  # samples at ESM times
    err = {a: np.abs(s.x_radar[0, :, 1, 0] - truth.x_radar[0, :, 1, 0]).mean()
           for a, s in sims.items()}
    assert err[True] < 0.05 * err[False]


def test_chi2_reference_never_worse_than_chance_and_beats_fuzzy_on_hard_setting():
    p = params(target__separation=50.0, radar__factor_model="derived")
    df = frame(EXPERIMENT.run_trials(p, rngs(150)))
    rate = df.groupby("algorithm")["correct"].mean()
    lo, _ = wilson_interval(rate["chi2"] * 150, 150)
    assert lo > 1 / 3
    # Track 3 (crossing, different speed) is never chosen by the reference.
    assert not (df[(df.algorithm == "chi2")].chosen == 3).any()
    assert rate["chi2"] >= rate["improved"]


def test_trial_without_any_valid_tdoa_df_sample_ignores_range():
    p = params(**{"esm.min_denominator": 1e5})
    rows = EXPERIMENT.run_trials(p, rngs(20))
    df = frame(rows)
    assert (df["esm_invalid"] == p["scan.count"]).all()
    assert df["chosen"].isin([1, 2, 3]).all() and np.isfinite(df["margin"]).all()
    # The reference never uses the ESM range, so it is unaffected by the missing range.
    ref = frame(EXPERIMENT.run_trials(params(), rngs(20)))
    np.testing.assert_array_equal(df[df.algorithm == "chi2"]["chosen"],
                                  ref[ref.algorithm == "chi2"]["chosen"])


@pytest.mark.parametrize("model", ["table", "derived"])
def test_true_track_chi2_distance_is_chi2_distributed(model):
    """The reference's covariance model is right: D of the true track ~ chi2(K F)."""
    p = params(radar__factor_model=model)
    diff = differences(simulate(p, rngs(200)))
    idx = [1, 2, 3, 4]  # speed, angle, tdoa, phase (the chi2 reference's factors)
    _, _, D = ml_track_decision(diff.d[..., idx], diff.S[..., idx, :][..., idx])
    dof = p["scan.count"] * len(idx)
    D_true = D[:, 1]
    assert D_true.mean() / dof == pytest.approx(1.0, abs=0.03)
    assert D_true.var() / (2 * dof) == pytest.approx(1.0, abs=0.3)


def test_abstaining_decision():
    j = np.array([0, 1, 2, 1])
    log_lr = np.array([5.0, 1.0, 5.0, 5.0])
    D_best = np.array([100.0, 100.0, 400.0, 100.0])
    out = abstaining_decision(j, log_lr, D_best, 100, np.log(19), 0.001)
    np.testing.assert_array_equal(out, [0, -1, -1, 1])  # ambiguous, then gated out
    np.testing.assert_array_equal(abstaining_decision(j, log_lr, D_best, 100, 0.0, 0.0), j)


def test_lrt_reference_abstains_on_identical_tracks():
    p = params(target__separation=0.0, algorithms=["chi2", "chi2_lrt"])
    df = frame(EXPERIMENT.run_trials(p, rngs(150)))
    lrt = df[df.algorithm == "chi2_lrt"]
    forced = df[df.algorithm == "chi2"]
    assert forced["decided"].all() and 0.1 < 1 - lrt["decided"].mean() < 0.6
    # Abstaining only removes decisions: never changes a decided track.
    both = lrt["chosen"].to_numpy() != 0
    np.testing.assert_array_equal(lrt["chosen"].to_numpy()[both], forced["chosen"].to_numpy()[both])
    assert ((lrt["chosen"] != 0) & (lrt["correct"] == 0)).mean() < (forced["correct"] == 0).mean()


@pytest.mark.parametrize("over", [{}, {"radar.period": 2.0, "esm.offset": 0.5,
                                      "time_align": True, "radar.factor_model": "derived"}])
def test_batch_equals_single_trials_and_algorithms_do_not_change_data(over):
    p = dict(params(), **over)
    g1, g2 = rngs(6), rngs(6)
    batch = EXPERIMENT.run_trials(p, g1)
    single = [EXPERIMENT.run_trial(p, g) for g in g2]
    for b, s in zip(batch, single, strict=True):
        for rb, rs in zip(b, s, strict=True):
            assert rb.keys() == rs.keys()
            for k in rb:
                if isinstance(rs[k], str):
                    assert rb[k] == rs[k], k
                else:
                    assert rb[k] == pytest.approx(rs[k], rel=1e-9, abs=1e-12), k
    only = EXPERIMENT.run_trials(dict(p, algorithms=["improved"]), rngs(6))
    esm_series = ("alpha_per_scan", "esm_range_error_per_scan_m",
                  "esm_bearing_error_per_scan_mrad")
    for full, one in zip(batch, only, strict=True):
        (row,) = [r for r in full if r["algorithm"] == "improved"]
        # the ESM track's series sit on each trial's first row, whichever algorithm it is
        assert {k: v for k, v in row.items() if k not in esm_series} \
            == {k: v for k, v in one[0].items() if k not in esm_series}
        assert all(full[0][k] == one[0][k] != "" for k in esm_series)
        assert all(r[k] == "" for r in full[1:] for k in esm_series)


def test_rows_are_tidy_and_deterministic():
    a = EXPERIMENT.run_trials(params(), rngs(4))
    b = EXPERIMENT.run_trials(params(), rngs(4))
    assert list(a) == list(b)
    for trial in a:
        assert [r["algorithm"] for r in trial] == ALL
        for r in trial:
            assert r["correct"] == int(r["chosen"] == 2) and r["chosen"] in (0, 1, 2, 3)
            assert r["decided"] == int(r["chosen"] != 0)
            assert r["margin"] >= 0
            assert not any(k.endswith("_time_s") for k in r)
            assert 0 <= r["range_weight_min"] <= r["range_weight_mean"] + 1e-12
            assert r["range_weight_mean"] <= 0.637 + 1e-12  # largest static range weight


def test_table_model_tdoa_decides_and_derived_is_harder():
    """W001-2: the radar-factor model changes the headline result."""
    out = {}
    for model in ("table", "derived"):
        df = frame(EXPERIMENT.run_trials(params(radar__factor_model=model), rngs(120)))
        out[model] = df.groupby("algorithm")["correct"].mean()
    assert out["table"]["improved"] > 0.9 and out["table"]["chi2"] > 0.95
    assert out["derived"]["improved"] < out["table"]["improved"] - 0.1
    # The 3-factor methods do not use TDOA/phase, so the model does not affect them.
    assert out["table"]["traditional"] == out["derived"]["traditional"]


def test_tables_from_saved_frames(tmp_path):
    base = params(algorithms=["traditional", "improved", "improved_static", "chi2", "chi2_lrt"])
    run = mini_run(tmp_path, base, {"target.separation": [100.0, 1000.0]}, 12)
    tabs = report.tables(run)
    t3 = tabs["table3"]
    assert set(t3.columns) >= {"radar_track_1", "radar_track_2", "radar_track_3",
                               "correct_rate", "correct_rate_ci_low", "correct_rate_ci_high",
                               "n"}
    np.testing.assert_array_equal(t3[["radar_track_1", "radar_track_2", "radar_track_3",
                                      "no_decision"]].sum(axis=1), t3["n"])
    np.testing.assert_allclose(t3["correct_rate"], t3["radar_track_2"] / t3["n"])
    assert (t3["correct_rate_ci_low"] <= t3["correct_rate"]).all()
    assert (t3["correct_rate"] <= t3["correct_rate_ci_high"]).all()
    assert (t3["wrong_rate_ci_low"] <= t3["wrong_rate"]).all()
    assert (t3["wrong_rate"] <= t3["wrong_rate_ci_high"]).all()
    abl = tabs["ablation"]
    imp = abl[abl.algorithm == "improved"]
    assert (imp["gain_vs_improved"] == 0).all()
    # improved against itself is no comparison: no interval, no p-value
    assert imp[["gain_vs_improved_ci_low", "gain_vs_improved_ci_high", "mcnemar_p",
                "mcnemar_p_holm"]].isna().all().all()
    variants = abl[abl.algorithm != "improved"]
    assert (variants["gain_vs_improved_ci_low"] <= variants["gain_vs_improved"]).all()
    assert (variants["gain_vs_improved"] <= variants["gain_vs_improved_ci_high"]).all()
    for _, rows in variants.groupby("point"):
        np.testing.assert_array_equal(rows["mcnemar_p_holm"],
                                      holm_adjusted(rows["mcnemar_p"]))
        assert (rows["mcnemar_p_holm"] >= rows["mcnemar_p"]).all()
    for _, rows in variants.groupby("algorithm"):  # the same comparison along the sweep
        assert len(rows) == 2
        np.testing.assert_array_equal(rows["mcnemar_p_holm_sweep"],
                                      holm_adjusted(rows["mcnemar_p"]))
    assert imp["mcnemar_p_holm_sweep"].isna().all()
    assert set(abl["weights"]) == {"static", "dynamic", "-"}


def test_the_chosen_track_is_a_label_counted_by_table3_never_averaged(tmp_path):
    """A mean (and t interval) of track indices 0-3 means nothing: summary.csv has no row for
    ``chosen`` and comparing two runs skips it; table3 counts its values."""
    run = mini_run(tmp_path / "a", params(algorithms=["traditional", "improved"]), {}, 12)
    assert "chosen" in set(run.trials.columns)
    assert "chosen" not in set(run.summary["metric"])
    assert {"correct", "margin"} <= set(run.summary["metric"])
    other = mini_run(tmp_path / "b", params(algorithms=["traditional", "improved"]), {}, 12,
                     seed=6)
    cells = compare_runs(run, other).cells
    assert "chosen" not in set(cells["metric"]) and "correct" in set(cells["metric"])
    with pytest.raises(ValueError, match="unknown metric 'chosen'"):
        compare_runs(run, other, tolerance={"chosen": 1.0})


def test_categorical_sweep_draws_one_category_per_setting(tmp_path):
    base = params(algorithms=["traditional", "improved", "chi2"])
    run = mini_run(tmp_path, base, {"radar.factor_model": ["table", "derived"]}, 8)
    fig = report.figures(run, ["correct_rate"])["correct_rate"]
    (panel,) = [a for a in fig.axes if a.has_data()]
    assert [t.get_text() for t in panel.get_xticklabels()] == ["'table' (own noise)",
                                                               "'derived' (from position)"]
    drawn = {ln.get_label() for ln in panel.get_lines()}
    assert LOOKS["improved"].label in drawn and LOOKS["chi2"].label not in drawn  # elsewhere
    t3 = report.tables(run)["table3"]
    assert set(t3["radar.factor_model"]) == {"table", "derived"}


def test_static_weight_methods():
    np.testing.assert_allclose(static_weights(ALGORITHMS["improved"].factors, "root_exact"),
                               [0.5100, 0.2638, 0.1296, 0.0636, 0.0329], atol=1e-4)
    np.testing.assert_allclose(static_weights(ALGORITHMS["improved"].factors, "eigen")[0],
                               0.5128, atol=1e-4)
    np.testing.assert_array_equal(static_weights(ALGORITHMS["improved"].factors,
                                                 "paper_rounded"), ESM_RADAR_WEIGHTS)
    # Subsets use the AHP sub-matrix (traditional: 0.637/0.258/0.105), in the given order.
    np.testing.assert_allclose(static_weights(("range", "speed", "angle"), "paper_rounded"),
                               [0.637, 0.258, 0.105], atol=1e-3)
    np.testing.assert_allclose(static_weights(("angle", "range"), "root_exact"),
                               [1 / 6, 5 / 6])


@pytest.mark.parametrize("fmt", sorted(set(SCAN_SERIES.values())))
def test_series_cells_are_each_value_formatted_and_nan_where_not_finite(fmt):
    rng = np.random.default_rng(3)
    values = rng.normal(size=(40, 13)) * 10.0 ** rng.integers(-9, 9, size=(40, 13))
    values[0, :6] = [np.nan, np.inf, -np.inf, -0.0, 0.5, 2.5]
    cells = encode_series(values, fmt)
    assert cells == [";".join(format(v, fmt) if np.isfinite(v) else "nan" for v in row)
                     for row in values]
    back = decode_series(cells)
    assert np.array_equal(np.isnan(back), ~np.isfinite(values))


def test_the_batch_table_writes_the_cells_of_its_row_dicts():
    """The batch's columns written as CSV equal its per-trial row dicts written one by one
    (the runner writes the former; the latter is the plain form of the same rows)."""
    table = EXPERIMENT.run_trials(params(), rngs(7))
    rows = [row for trial in table for row in trial]
    assert columns_csv(table.columns, table.rows) == rows_to_csv(rows)
    assert sum(1 for r in rows if r["alpha_per_scan"]) == 7
    assert all(type(r[k]) is int for r in rows
               for k in ("chosen", "correct", "decided", "esm_invalid"))


def test_no_range_variant_uses_the_five_factor_weights_rescaled():
    """improved_no_range: static weights where the dynamic ones go when the range weight is
    cut to 0 (the other four five-factor AHP weights, rescaled), never the 4x4 sub-block."""
    variant = ALGORITHMS["improved_no_range"]
    five = static_weights(ALGORITHMS["improved"].factors, "root_exact")
    w = variant_weights(variant, variant.factors, "root_exact")
    np.testing.assert_allclose(w, five[1:] / five[1:].sum())
    assert not variant.dynamic and "range" not in variant.factors
    rows = run_trial(params(algorithms=["improved", "improved_no_range"]), rngs(1)[0])
    assert rows[1]["range_weight_mean"] == 0.0 and rows[0]["range_weight_mean"] > 0

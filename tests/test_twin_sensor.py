"""The twin_sensor experiment: contract, paired data, consistency against the PCRLB, figures."""

import itertools

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from trackfuse.experiments import get
from trackfuse.experiments.twin_sensor import EXPERIMENT, bounds, build_scenario, simulate
from trackfuse.seeding import trial_streams
from trackfuse.stats import nees_band
from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import azel

ROW_METRICS = {"range_err_m", "range_sq_err_m2", "pos_sq_err_m2", "nees", "nees_pos",
               "n_valid", "lost_gate", "lost_angle", "inconsistent_nees", "cpu_time_s"}


def params(**kw):
    p = EXPERIMENT.defaults()
    p.update({k.replace("__", "."): v for k, v in kw.items()})
    return p


def frames(base: dict, sweep: dict[str, list], trials: int, seed: int = 1):
    """A tiny stand-in for the runner: grid sweep, trial seeds, trials and summary frames."""
    keys = list(sweep)
    rows = []
    for point, values in enumerate(itertools.product(*sweep.values())):  # keeps the types
        swept = dict(zip(keys, values, strict=True))
        rngs = [trial_streams(seed, point, t) for t in range(trials)]
        for t, trial_rows in enumerate(EXPERIMENT.run_batch(dict(base, **swept), rngs)):
            for r in trial_rows:
                rows.append({"point": point, "trial": t, **swept, **r})
    trials_df = pd.DataFrame(rows).drop(columns="cpu_time_s")
    long = trials_df.melt(id_vars=["point", *keys, "algorithm", "scan", "trial"],
                          var_name="metric")
    summary = long.groupby(["point", *keys, "algorithm", "scan", "metric"])["value"].agg(
        n="count", mean="mean", std="std").reset_index()
    config = {"experiment": "twin_sensor", "title": "test", "trials": trials, "seed": seed,
              "params": base, "sweep": sweep, "sweep_mode": "grid"}
    return trials_df, summary, config


def test_registered_schema_is_complete():
    assert get("twin_sensor") is EXPERIMENT
    assert EXPERIMENT.row_keys == ("algorithm", "scan")
    for p in EXPERIMENT.params:
        assert p.doc, p.key
        if p.kind in (int, float) and p.choices is None:
            assert p.low is not None and p.high is not None and p.low <= p.default <= p.high
    assert set(EXPERIMENT.binary_metrics) == {"lost_gate", "lost_angle", "inconsistent_nees"}
    with pytest.raises(ValueError, match="3 components"):
        build_scenario(params(target__position=[1.0, 2.0]))


def test_rows_are_tidy_and_reproducible():
    p = params(clutter__mean=4.0, algorithms=["mspda_parallel/mgekf", "nn/ekf"])
    a = EXPERIMENT.run_trial(p, trial_streams(3, 0, 0))
    b = EXPERIMENT.run_trial(p, trial_streams(3, 0, 0))
    assert len(a) == 2 * 20
    assert {r["algorithm"] for r in a} == {"mspda_parallel/mgekf", "nn/ekf"}
    for ra, rb in zip(a, b, strict=True):
        assert set(ra) == {"algorithm", "scan"} | ROW_METRICS
        assert type(ra["lost_gate"]) is int and type(ra["nees"]) is float
        ra, rb = dict(ra), dict(rb)
        ra.pop("cpu_time_s"), rb.pop("cpu_time_s")
        assert ra == rb


def test_truth_trajectory_follows_the_cv_recursion():
    from trackfuse.experiments.twin_sensor import truth_trajectory
    from trackfuse.tracking.models import cv_noise_gain, cv_transition

    sc = build_scenario(params(target__q=400.0, target__velocity=[10.0, -20.0, 3.0],
                               scan__period=0.5))
    x = truth_trajectory(sc, np.random.default_rng(3))
    accel = np.sqrt(400.0) * np.random.default_rng(3).standard_normal((sc.K, 3))
    F, G = cv_transition(0.5), cv_noise_gain(0.5)
    ref = [sc.x_start]
    for a in accel:
        ref.append(F @ ref[-1] + G @ a)
    np.testing.assert_allclose(x, np.array(ref), rtol=1e-12, atol=1e-8)


def test_batch_equals_per_trial():
    p = params(clutter__mean=6.0, sensors__pd=0.9,
               algorithms=["mspda_parallel/mgekf", "mspda_sequential/ekf", "paper_approx/mgekf"])
    rngs = lambda: [trial_streams(5, 2, t) for t in range(4)]  # noqa: E731
    batch = EXPERIMENT.run_batch(p, rngs())
    single = [EXPERIMENT.run_trial(p, g) for g in rngs()]
    for rows_b, rows_s in zip(batch, single, strict=True):
        fb = pd.DataFrame(rows_b).drop(columns="cpu_time_s")
        fs = pd.DataFrame(rows_s).drop(columns="cpu_time_s")
        pd.testing.assert_frame_equal(fb, fs, rtol=1e-9, atol=1e-9)


def test_adding_an_algorithm_does_not_change_the_data_or_other_results():
    one = params(clutter__mean=5.0, algorithms=["mspda_parallel/mgekf"])
    three = params(clutter__mean=5.0, algorithms=["nn/mgekf", "mspda_parallel/mgekf",
                                                  "paper_approx/ekf"])
    a = pd.DataFrame(EXPERIMENT.run_trial(one, trial_streams(11, 0, 0)))
    b = pd.DataFrame(EXPERIMENT.run_trial(three, trial_streams(11, 0, 0)))
    b = b[b["algorithm"] == "mspda_parallel/mgekf"].reset_index(drop=True)
    pd.testing.assert_frame_equal(a.drop(columns="cpu_time_s"), b.drop(columns="cpu_time_s"))


def test_window_clutter_is_centred_on_the_line_of_sight():
    sc = build_scenario(params(clutter__model="window", clutter__mean=30.0))
    d = simulate(sc, trial_streams(4, 0, 0))
    assert d.clutter.shape == (int(d.n_clutter.sum()), 2)
    assert abs(d.n_clutter.mean() - 30.0) < 3.0
    np.testing.assert_allclose(d.los, azel(d.x_true[1:, None, :3] - sc.sensor_pos[1:]))
    centre = np.repeat(d.los.reshape(-1, 2), d.n_clutter.ravel(), axis=0)
    off = np.abs(wrap(d.clutter - centre))  # uniform on [0, window] per axis
    assert off.max() <= 0.1 + 1e-12 and abs(off.mean() - 0.05) < 0.005
    # the noisy target returns are not the centre: they scatter by sigma about it
    assert 0 < np.abs(wrap(d.z_target - d.los)).max() < 6 * 0.01


def test_clutter_free_filter_is_consistent_and_not_below_the_pcrlb():
    """Matched model (q = 0, stationary truth), no clutter: ANEES inside its 95 % band and the
    range RMSE never below sqrt(PCRLB) by more than Monte Carlo noise."""
    n = 400
    p = params(filter__q=0.0, algorithms=["mspda_parallel/mgekf", "mspda_parallel/ekf"])
    rows = EXPERIMENT.run_batch(p, [trial_streams(2024, 0, t) for t in range(n)])
    df = pd.DataFrame([r for trial in rows for r in trial])
    lo, hi = nees_band(6, n)
    rb, pb = bounds(p)
    floor = stats.chi2.ppf(0.001, n) / n  # MSE / bound^2 can dip this low by chance
    for name, g in df.groupby("algorithm"):
        anees = g.groupby("scan")["nees"].mean()
        assert lo <= anees.loc[1] <= hi, name
        assert lo <= anees.mean() <= hi, name
        mse = g.groupby("scan")["range_sq_err_m2"].mean().to_numpy()
        assert np.all(mse >= floor * rb**2), name
        pos = g.groupby("scan")["pos_sq_err_m2"].mean().to_numpy()
        assert np.all(pos >= floor * pb**2), name
        assert g["lost_gate"].sum() == 0 and g["lost_angle"].sum() == 0
        assert g["inconsistent_nees"].mean() < 0.01


def test_loss_flags_are_permanent_and_clutter_can_lose_tracks():
    """Close-in (about 20 km), hard-manoeuvring target seen by one hovering sensor."""
    p = params(clutter__mean=15.0, sensors__count=1, sensors__pd=0.7,
               target__position=[140000.0, 15000.0, 4000.0], target__velocity=[0.0, 300.0, 0.0],
               target__q=2500.0, platform__motion="straight", platform__speed=0.0,
               platform__climb=0.0, algorithms=["nn/ekf", "mspda_parallel/mgekf"])
    rows = EXPERIMENT.run_batch(p, [trial_streams(8, 0, t) for t in range(60)])
    df = pd.DataFrame([r for trial in rows for r in trial])
    flags = df.pivot_table(index=["algorithm", df.index // 20], columns="scan",
                           values="lost_gate").to_numpy()
    assert np.all(np.diff(flags, axis=1) >= 0)
    assert df.loc[df["scan"] == 20, "lost_gate"].mean() > 0


def test_bound_grows_with_clutter_and_shrinks_with_baseline():
    r0 = bounds(params())[0][-1]
    assert bounds(params(clutter__mean=10.0))[0][-1] > r0
    assert bounds(params(sensors__baseline=50e3))[0][-1] < 0.5 * r0
    assert bounds(params(), q_model=900.0)[0][-1] > r0


@pytest.fixture(scope="module")
def small_run():
    base = params(algorithms=["mspda_parallel/mgekf", "mspda_parallel/ekf", "nn/mgekf"])
    return frames(base, {"clutter.mean": [0.0, 8.0]}, trials=6)


def test_figures_from_tables(small_run):
    trials, summary, config = small_run
    figs = EXPERIMENT.figures(trials, summary, config)
    assert {"loss_gate_vs_clutter", "loss_angle_vs_clutter", "inconsistent_nees_vs_clutter",
            "range_rmse_vs_time",
            "anees_vs_time", "final_range_rmse_vs_clutter_mean"} <= set(figs)
    for fig in figs.values():
        for ax in fig.axes:
            if ax.get_visible() and ax.has_data():
                assert "(" in ax.get_xlabel() and "(" in ax.get_ylabel()
    legend = figs["range_rmse_vs_time"].legends[0]
    assert any("PCRLB" in t.get_text() for t in legend.get_texts())


def test_tables_report_loss_and_bound(small_run):
    trials, summary, config = small_run
    table = EXPERIMENT.tables(trials, summary, config)["final_scan"]
    assert len(table) == 2 * 3
    assert {"lost_gate_pct", "lost_angle_pct", "inconsistent_nees_pct", "range_rmse_km",
            "range_rmse_ci95_km", "range_pcrlb_km", "range_bias_scan1_km",
            "range_bias_final_km"} <= set(table)
    assert (table["range_pcrlb_km"] > 0).all()


def test_figures_use_time_axes_and_accept_a_swept_string_key():
    """Regression: the RMSE curve was drawn against the scan index while its PCRLB was drawn
    against time, and a swept string key crashed the loss-figure titles."""
    base = params(algorithms=["mspda_parallel/mgekf", "nn/mgekf"], scan__count=4,
                  scan__period=2.0)
    trials, summary, config = frames(
        base, {"clutter.model": ["in_gate", "window"], "clutter.mean": [0.0, 5.0]}, trials=3)
    figs = EXPERIMENT.figures(trials, summary, config)
    titles = [ax.get_title() for ax in figs["loss_gate_vs_clutter"].axes if ax.get_visible()]
    assert titles == ["model=in_gate", "model=window"]
    for line in figs["range_rmse_vs_time"].axes[0].get_lines():
        np.testing.assert_allclose(line.get_xdata(), [2.0, 4.0, 6.0, 8.0])

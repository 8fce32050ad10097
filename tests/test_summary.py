"""Streaming summary equals a direct pandas computation, for any chunking."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from trackfuse.summary import _chunk_stats, summarize


@pytest.mark.parametrize("chunk_rows", [7, 64, 10_000])
def test_chunked_summary_equals_direct(tmp_path, chunk_rows):
    rng = np.random.default_rng(0)
    n = 300
    frame = pd.DataFrame({
        "point": np.repeat([0, 1, 2], n // 3), "trial": np.arange(n),
        "algorithm": np.tile(["a", "b"], n // 2), "x": rng.normal(5, 2, n),
        "hit": rng.integers(0, 2, n)})
    frame.loc[5, "x"] = np.nan
    path = tmp_path / "t.csv"
    frame.to_csv(path, index=False)
    summary, failed = summarize(path, ["point", "algorithm"], binary=["hit"],
                                chunk_rows=chunk_rows)
    assert failed == 0
    direct = frame.groupby(["point", "algorithm"])["x"].agg(["count", "mean", "std"])
    got = summary[summary.metric == "x"].set_index(["point", "algorithm"])
    for key, row in direct.iterrows():
        assert got.loc[key, "n"] == row["count"]
        assert np.isclose(got.loc[key, "mean"], row["mean"], rtol=1e-12)
        assert np.isclose(got.loc[key, "std"], row["std"], rtol=1e-10)
        assert got.loc[key, "ci_low"] < row["mean"] < got.loc[key, "ci_high"]
    hits = summary[summary.metric == "hit"]
    assert (hits["interval"] == "wilson").all() and (hits["ci_low"] >= 0).all()


@pytest.mark.parametrize("chunk_rows", [7, 10_000])
def test_a_file_read_whole_gives_the_summary_of_the_file(tmp_path, chunk_rows):
    """The runner summarizes a small trials.csv from the frame the report reads too: the
    same bytes as from the file, failed rows, NaN and integer metrics included."""
    rng = np.random.default_rng(1)
    n = 120
    frame = pd.DataFrame({
        "point": np.repeat([0, 1], n // 2), "trial": np.arange(n),
        "algorithm": np.tile(["a/b", "c"], n // 2), "x": rng.normal(5, 2, n) * 1e-3,
        "hit": rng.integers(0, 2, n), "status": "", "error": ""})
    frame.loc[[3, 40], "x"] = np.nan
    frame.loc[7, ["status", "error"]] = ["failed", "boom"]
    path = tmp_path / "t.csv"
    frame.to_csv(path, index=False)
    whole = pd.read_csv(path, low_memory=False)
    from_file = summarize(path, ["point", "algorithm"], ["hit"], chunk_rows=chunk_rows)
    from_frame = summarize(whole, ["point", "algorithm"], ["hit"], chunk_rows=chunk_rows)
    assert from_file[1] == from_frame[1] == 1
    assert from_frame[0].to_csv(index=False) == from_file[0].to_csv(index=False)


def test_failed_rows_are_counted_and_excluded(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("point,trial,algorithm,x,status,error\n0,0,a,1.0,,\n0,1,,,failed,boom\n"
                    "0,2,a,3.0,,\n")
    summary, failed = summarize(path, ["point", "algorithm"])
    assert failed == 1
    assert summary.loc[0, "n"] == 2 and summary.loc[0, "mean"] == 2.0


def _long_format_stats(frame: pd.DataFrame, group: list[str], metrics: list[str]):
    """The per-chunk statistics as the long format gives them (melt, drop missing values,
    group by keys and metric): the reference the wide computation must equal."""
    long = frame.melt(id_vars=group, value_vars=metrics, var_name="metric",
                      value_name="value").dropna(subset=["value"])
    stats = long.groupby([*group, "metric"], sort=False, dropna=False)["value"].agg(
        n="count", mean="mean", var="var")
    var = stats.pop("var").to_numpy(float)
    stats["m2"] = np.where(stats["n"].to_numpy() > 1, var * (stats["n"] - 1), 0.0)
    return stats.reset_index()


def test_wide_chunk_statistics_equal_the_long_format_bit_for_bit():
    rng = np.random.default_rng(4)
    n = 500
    frame = pd.DataFrame({
        "point": rng.integers(0, 3, n), "algorithm": rng.choice(["a", "b", "c"], n),
        "x": rng.normal(1e4, 3.0, n), "k": rng.integers(0, 5, n),
        "y": rng.exponential(2.0, n)})
    frame.loc[rng.random(n) < 0.3, "x"] = np.nan  # groups whose first rows lack a value
    frame.loc[frame.algorithm == "c", "y"] = np.nan  # a metric some groups never have
    got = _chunk_stats(frame, ["point", "algorithm"], ["x", "k", "y"])
    expected = _long_format_stats(frame, ["point", "algorithm"], ["x", "k", "y"])
    assert got.to_csv(index=False) == expected.to_csv(index=False)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # inf - inf
@pytest.mark.parametrize("values", [[1.0, np.inf, 2.0, 3.0], [1.0, 2.0, 3.0, np.inf],
                                    [np.inf, 1.0, -np.inf, 3.0]])
def test_an_infinite_value_gives_the_same_summary_for_any_chunking(values):
    """pandas' variance of a sample holding inf is NaN; the pooled chunks must say the same,
    not skip the chunk with the inf and report an infinite spread."""
    frame = pd.DataFrame({"point": 0, "trial": np.arange(4), "algorithm": "a", "x": values})
    whole, _ = summarize(frame, ["point", "algorithm"], chunk_rows=10)
    chunked, _ = summarize(frame, ["point", "algorithm"], chunk_rows=2)
    pd.testing.assert_frame_equal(whole, chunked)
    assert np.isnan(chunked["std"]).all() and np.isnan(chunked["ci_high"]).all()


def test_a_skipped_column_gets_no_summary_row(tmp_path):
    frame = pd.DataFrame({"point": 0, "algorithm": "a", "trial": range(4),
                          "label": [0, 3, 3, 1], "x": [1.0, 2.0, 3.0, 4.0]})
    summary, _ = summarize(frame, ["point", "algorithm"], skip=["label"])
    assert summary["metric"].tolist() == ["x"]
    everything, _ = summarize(frame, ["point", "algorithm"])
    assert sorted(everything["metric"]) == ["label", "x"]


def test_a_bounded_metric_has_its_interval_clipped_to_its_bounds():
    """A Student-t interval of a fraction near 1 passed 1 (passive_noise's accuracy of the
    exact solver: ci_high 1.001); a metric's bounds now clip it, and nothing else."""
    frame = pd.DataFrame({"point": 0, "algorithm": "a", "trial": range(4),
                          "fraction": [1.0, 1.0, 1.0, 0.9], "square": [0.0, 0.0, 0.1, 0.0],
                          "free": [1.0, 1.0, 1.0, 0.9]})
    bounds = {"fraction": (0.0, 1.0), "square": (0.0, np.inf)}
    clipped, _ = summarize(frame, ["point", "algorithm"], bounds=bounds)
    plain, _ = summarize(frame, ["point", "algorithm"])
    low, high = (clipped.set_index("metric")[c] for c in ("ci_low", "ci_high"))
    assert plain.set_index("metric").loc["fraction", "ci_high"] > 1.0
    assert plain.set_index("metric").loc["square", "ci_low"] < 0.0
    assert high["fraction"] == 1.0 and low["square"] == 0.0
    assert low["fraction"] == plain.set_index("metric").loc["fraction", "ci_low"]
    pd.testing.assert_series_equal(clipped.set_index("metric").loc["free"],
                                   plain.set_index("metric").loc["free"])


def test_one_pair_of_bounds_clips_every_metric():
    """The runner's timings summary: a time is never negative, whatever its column."""
    frame = pd.DataFrame({"point": 0, "algorithm": "a", "trial": range(4),
                          "cpu_time_s": [0.0, 0.0, 0.1, 0.0], "wall_time_s": [0, 0, 0, 2.0]})
    plain, _ = summarize(frame, ["point", "algorithm"])
    clipped, _ = summarize(frame, ["point", "algorithm"], bounds=(0.0, np.inf))
    assert (plain["ci_low"] < 0).all()
    assert (clipped["ci_low"] == 0).all()
    assert clipped["ci_high"].tolist() == plain["ci_high"].tolist()

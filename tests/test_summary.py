"""Streaming summary equals a direct pandas computation, for any chunking."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from trackfuse.summary import summarize


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


def test_failed_rows_are_counted_and_excluded(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("point,trial,algorithm,x,status,error\n0,0,a,1.0,,\n0,1,,,failed,boom\n"
                    "0,2,a,3.0,,\n")
    summary, failed = summarize(path, ["point", "algorithm"])
    assert failed == 1
    assert summary.loc[0, "n"] == 2 and summary.loc[0, "mean"] == 2.0

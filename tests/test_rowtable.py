"""trackfuse.rowtable: column-wise CSV text is the dict rows' CSV text (and a frame's is
pandas' text), byte for byte."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.batch import BatchTask, execute_batch
from trackfuse.experiments.base import Experiment, Metric
from trackfuse.results import BatchSpan, rows_to_csv
from trackfuse.rowtable import Constant, RowTable, columns_csv, frame_csv
from trackfuse.summary import summarize


def _table() -> RowTable:
    rng = np.random.default_rng(3)
    floats = rng.standard_normal(12) * 10.0 ** rng.integers(-20, 20, 12)
    floats[[1, 4, 7]] = [np.nan, np.inf, -0.0]
    return RowTable(np.repeat(np.arange(4), 3), {
        "algorithm": np.array(["a/b", 'say "hi"', "x,y"] * 4, dtype=object),
        "label": np.array(["b", "a\rc", "b", 'q"', "", "b"] * 2),  # str dtype: quoted once
        "scan": np.tile(np.arange(1, 4), 4),
        "err": floats,
        "lost": rng.random(12) < 0.5,
        "count": rng.integers(0, 9, 12),
    })


def test_columns_csv_equals_the_dict_rows_csv():
    table = _table()
    rows = [{"point": 2, "trial": 10 + n, "clutter.mean": 1.5, "targets": [1, 2], **row}
            for n in range(len(table)) for row in table[n]]
    text = columns_csv({"point": Constant(2), "trial": 10 + table.trial,
                        "clutter.mean": Constant(1.5), "targets": Constant([1, 2]),
                        **table.columns}, table.rows)
    assert text == rows_to_csv(rows)


def test_a_table_is_a_sequence_of_per_trial_rows():
    table = _table()
    assert len(table) == 4 and table.rows == 12
    first = table[0]
    assert [r["scan"] for r in first] == [1, 2, 3]
    assert type(first[0]["err"]) is float and type(first[0]["count"]) is int
    assert table[-1] == table[3] == list(table)[3]
    with pytest.raises(IndexError):
        table[4]


@pytest.mark.parametrize("trial", [[0, 0, 2], [1, 1, 2], [0, 1, 0]])
def test_check_refuses_a_table_that_skips_or_reorders_trials(trial):
    table = RowTable(np.array(trial), {"x": np.zeros(3)})
    with pytest.raises(TypeError):
        table.check(3)


def test_check_refuses_a_short_column():
    with pytest.raises(TypeError):
        RowTable(np.arange(3), {"x": np.zeros(2)}).check(3)
    RowTable(np.arange(3), {"x": np.zeros(3)}).check(3)


def test_check_names_a_column_of_more_than_one_value_per_row():
    """A (R, 2) column passed the length check and was written as '[1.0, 2.0]' cells, whose
    parts failed verification three times: the run blamed the disk ('is the disk
    failing?')."""
    table = RowTable(np.arange(3), {"algorithm": np.array(["a"] * 3), "x": np.zeros((3, 2))})
    with pytest.raises(TypeError, match=r"column 'x' has shape \(3, 2\); allowed: one value "
                                        r"per row, shape \(3,\)"):
        table.check(3)


def test_parts_that_keep_failing_verification_are_not_blamed_on_the_disk_alone(
        tmp_path, monkeypatch):
    from trackfuse.config import build
    from trackfuse.results import PartDamaged, RunFolder, RunFolderError
    from trackfuse.runner import Runner

    def damaged(self, spans, kind, target):
        raise PartDamaged(next(iter(spans())), kind, "a row has 4 cells for 3 columns")

    monkeypatch.setattr(RunFolder, "merge", damaged)
    config = build({"experiment": "toy_gaussian", "trials": 2}, "cfg.yaml")
    with pytest.raises(RunFolderError, match="a bug in its run_trial or run_batch") as caught:
        Runner(config, tmp_path, executor="serial", progress=False, plots=False,
               warn=lambda message: None).run()
    assert "disk is failing" in str(caught.value)  # it may also be the disk


def _column(data, kind: str, rows: int) -> pd.Series:
    """A column of ``rows`` values of one ``kind``: the column-wise path's (float, int,
    uint8, str) or pandas' (text needing quotes, bool, nullable integers)."""
    def values(strategy):
        return data.draw(st.lists(strategy, min_size=rows, max_size=rows))

    if kind == "float":  # NaN, infinities, -0, subnormals, 1e300...
        return pd.Series(values(st.floats(width=64) | st.just(float("nan"))), dtype="float64")
    if kind == "int":
        return pd.Series(values(st.integers(-2**63, 2**63 - 1)), dtype="int64")
    if kind == "uint8":
        return pd.Series(values(st.integers(0, 255)), dtype="uint8")
    if kind in ("str", "text"):
        alphabet = "ab/_.-" if kind == "str" else 'ab,"\r\n '
        size = {"min_size": 1} if kind == "str" else {}
        return pd.Series(values(st.text(alphabet, max_size=4, **size)), dtype=object)
    if kind == "bool":
        return pd.Series(values(st.booleans()), dtype=bool)
    return pd.Series(values(st.none() | st.integers(0, 9)), dtype="Int64")


FAST = ["float", "int", "uint8", "str"]


@settings(max_examples=150, deadline=None)
@given(data=st.data(), rows=st.integers(0, 6),
       kinds=st.lists(st.sampled_from(FAST), min_size=2, max_size=5))
def test_frame_csv_writes_what_pandas_writes(data, rows, kinds):
    frame = pd.DataFrame({f"c{i}" if i % 2 else f"col {i}.x": _column(data, kind, rows)
                          for i, kind in enumerate(kinds)})
    expected = frame.to_csv(index=False)
    original, pd.DataFrame.to_csv = pd.DataFrame.to_csv, None  # the column-wise path
    try:
        assert frame_csv(frame) == expected
    finally:
        pd.DataFrame.to_csv = original


@settings(max_examples=60, deadline=None)
@given(data=st.data(), rows=st.integers(0, 6),
       kinds=st.lists(st.sampled_from([*FAST, "text", "bool", "nullable"]), min_size=1,
                      max_size=4))
def test_frame_csv_of_any_frame_is_what_pandas_writes(data, rows, kinds):
    """Other column types (and one-column frames) are left to pandas."""
    frame = pd.DataFrame({f"c{i}": _column(data, kind, rows) for i, kind in enumerate(kinds)})
    assert frame_csv(frame) == frame.to_csv(index=False)


def test_frame_csv_of_a_run_summary_is_what_pandas_writes(tmp_path, monkeypatch):
    """A summary (string row keys and metric names, integer counts, float statistics with
    NaN standard deviations) takes the column-wise path and writes pandas' bytes."""
    rng = np.random.default_rng(5)
    trials = pd.DataFrame({"point": np.repeat([0, 1], 30), "trial": np.tile(range(30), 2),
                           "algorithm": np.tile(["a/mgekf", "b/ekf", "c"], 20),
                           "err": rng.standard_normal(60) * 1e3,
                           "lost": rng.random(60) < 0.3, "once": np.r_[1.5, [np.nan] * 59]})
    trials.to_csv(tmp_path / "trials.csv", index=False)
    summary, _ = summarize(tmp_path / "trials.csv", ["point", "algorithm"], ["lost"])
    assert summary["std"].isna().any() and summary["algorithm"].dtype.kind == "O"
    expected = summary.to_csv(index=False)
    monkeypatch.setattr(pd.DataFrame, "to_csv", None)  # the column-wise path, not pandas
    assert frame_csv(summary) == expected


@pytest.mark.parametrize("columns", [
    ["a", "a"],  # duplicate names: frame[name] is a frame (AttributeError: no dtype)
    [np.nan, "b"],  # a missing label: pandas writes an empty name, str() gives "nan"
    pd.to_datetime(["2020-01-01", "2020-01-02"]),  # pandas writes midnight as the date
])
def test_frame_csv_of_any_column_labels_is_what_pandas_writes(columns):
    frame = pd.DataFrame([[1.0, 2.0]], columns=columns)
    assert frame_csv(frame) == frame.to_csv(index=False)


def _batch(run_trial, run_batch) -> pd.DataFrame:
    """``trials.csv`` of a batch of 3 trials of an experiment declaring the metrics
    ``value`` and ``solve_time_s``."""
    experiment = Experiment("tabled", "a table", (), run_trial, run_batch=run_batch,
                            metrics=(Metric("value", "1", "a value"),
                                     Metric("solve_time_s", "s", "a timing")))
    result = execute_batch(BatchTask(experiment, {}, {}, 1, BatchSpan(0, 0, 0, 3), 0))
    return pd.read_csv(io.StringIO(result.trials_csv))


def _batch_form(column: str):
    def run_batch(params, streams):
        return RowTable(np.arange(len(streams)), {"algorithm": np.array(["a"] * len(streams)),
                                                  column: np.zeros(len(streams))})
    return run_batch


def test_a_batch_table_without_a_declared_metric_fails_its_trials():
    """A column table lacking a declared metric was written and summarised without it;
    retried trial by trial, it ran on the slow path unsaid whenever run_trial was right."""
    trials = _batch(lambda p, s: [{"algorithm": "a", "value": 1.0}], _batch_form("valeu"))
    assert list(trials["status"]) == ["failed"] * 3
    assert (trials["error"] == "TypeError: run_batch returned rows without the declared "
                               "metric value; the rows have algorithm, valeu").all()


def test_a_batch_that_raises_is_retried_by_trials_that_carry_no_batch_timing():
    """twin_sensor declares a per-batch CPU time that its run_trial rows cannot carry: when
    its batch form raised, every retried trial failed for lacking it (review)."""
    def raises(params, streams):
        raise np.linalg.LinAlgError("one trial's singular matrix")

    trials = _batch(lambda p, s: [{"algorithm": "a", "value": 1.0}], raises)
    assert "status" not in trials and list(trials["value"]) == [1.0] * 3
    assert _batch(lambda p, s: [{"algorithm": "a", "value": 1.0}], _batch_form("value"))[
        "value"].tolist() == [0.0] * 3

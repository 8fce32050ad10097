"""trackfuse.rowtable: column-wise CSV text is the dict rows' CSV text, byte for byte."""

from __future__ import annotations

import numpy as np
import pytest

from trackfuse.results import rows_to_csv
from trackfuse.rowtable import Constant, RowTable, columns_csv


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

"""trackfuse.sweep.split_values: list values in --sweep keep their commas."""

from __future__ import annotations

import pytest

from trackfuse.sweep import SweepError, parse_axis_values, parse_sweeps, split_values


def test_commas_inside_brackets_and_quotes_do_not_split():
    assert split_values("[a,b],[c]") == ["[a,b]", "[c]"]
    assert split_values("0,5,10") == ["0", "5", "10"]
    assert split_values("'a,b',c") == ["'a,b'", "c"]
    assert split_values("{x: 1, y: 2},[3]") == ["{x: 1, y: 2}", "[3]"]
    assert parse_sweeps(["algorithms=[nn/ekf,nn/mgekf],[nn/ekf]"]) == \
        {"algorithms": [["nn/ekf", "nn/mgekf"], ["nn/ekf"]]}
    assert parse_axis_values("[a,b],[c]") == [["a", "b"], ["c"]]


@pytest.mark.parametrize("text", ["[a,b", "a],b", "'a,b"])
def test_unbalanced_brackets_or_quotes_are_refused(text):
    with pytest.raises(SweepError, match="unbalanced"):
        split_values(text)

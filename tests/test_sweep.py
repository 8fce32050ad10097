"""Sweep axes, overrides and point expansion."""

from __future__ import annotations

import pytest

from trackfuse.sweep import SweepError, expand, parse_range, parse_sets, parse_sweeps


def test_integer_range_matches_python():
    assert parse_range("range(0, 21, 2)") == list(range(0, 21, 2))
    assert parse_range("range(3)") == [0, 1, 2]
    assert parse_range("range(5, 0, -2)") == [5, 3, 1]


def test_float_range_excludes_stop_without_drift():
    assert parse_range("range(0, 1, 0.1)") == [round(0.1 * i, 12) for i in range(10)]
    assert parse_range("range(0.005, 0.02, 0.005)") == [0.005, 0.01, 0.015]


@pytest.mark.parametrize("text", ["range()", "range(1, 2, 3, 4)", "range(a)", "range(0, 1, 0)",
                                  "range(4, 2)", "rang(1)"])
def test_bad_ranges(text):
    with pytest.raises(SweepError):
        parse_range(text)


def test_grid_order_last_axis_fastest_and_zip():
    points = expand({"a": [1, 2], "b": ["x", "y", "z"]})
    assert [p.index for p in points] == list(range(6))
    assert [tuple(p.values.values()) for p in points][:4] == [(1, "x"), (1, "y"), (1, "z"),
                                                              (2, "x")]
    zipped = expand({"a": [1, 2], "b": ["x", "y"]}, "zip")
    assert [p.values for p in zipped] == [{"a": 1, "b": "x"}, {"a": 2, "b": "y"}]
    assert expand({})[0].values == {}


def test_override_parsing():
    assert parse_sets(["a.b=1", "c=1e-3", "d=true", "e=nn", "f=[1, 2]"]) == {
        "a.b": 1, "c": 0.001, "d": True, "e": "nn", "f": [1, 2]}
    assert parse_sweeps(["a=0,5,10", "b=range(0,3)"]) == {"a": [0, 5, 10], "b": "range(0,3)"}
    with pytest.raises(SweepError):
        parse_sweeps(["a="])


@pytest.mark.parametrize(("text", "values"), [
    ("range(3e-13, 4e-13, 1e-13)", [3e-13]),  # rounded to 12 decimals: 0.0, unsaid
    ("range(1e-14, 4e-14, 1e-14)", [1e-14, 2e-14, 3e-14]),
    ("range(0, 3e-12, 1e-12)", [0.0, 1e-12, 2e-12]),
    ("range(1e20, 3e20, 1e20)", [1e20, 2e20]),
    ("range(0, 0.4, 0.1)", [0.0, 0.1, 0.2, 0.3]),
])
def test_a_float_range_keeps_the_values_written_at_any_magnitude(text, values):
    assert parse_range(text) == values

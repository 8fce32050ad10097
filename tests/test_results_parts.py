"""A part whose checksum holds can still hold the wrong rows (written by other code, or
rewritten with a new header): every row is checked, by array operations on the bytes where
they show it fits and line by line otherwise, which names what is wrong (issue 16)."""

from __future__ import annotations

import tracemalloc

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.results import (
    BatchSpan,
    PartDamaged,
    _check_rows,
    _lines,
    _rows_fit,
    part_bytes,
    read_part,
)

SPAN = BatchSpan(point=3, batch=1, first=10, stop=14)
HEADER = "point,trial,algorithm,err,lost"


def _rows(trials=range(10, 14), point: str = "3") -> list[str]:
    return [f"{point},{t},a/b,{t * 0.5},{t % 2}" for t in trials for _ in range(2)]


def _read(tmp_path, rows: list[str], kind: str = "trials", header: str = HEADER,
          count: int | None = None):
    path = tmp_path / "part.csv"
    text = header + "\n" + "".join(r + "\n" for r in rows)
    path.write_bytes(part_bytes(SPAN, text, len(rows) if count is None else count))
    return read_part(path, SPAN, kind)


def test_a_whole_part_reads_back_its_rows(tmp_path):
    part = _read(tmp_path, _rows())
    assert part.rows == 8 and part.columns == HEADER.split(",")
    assert part.data == "".join(r + "\n" for r in _rows())


@pytest.mark.parametrize(("rows", "kind", "message"), [
    (_rows()[:3] + ["3,11,a/b,1.0"] + _rows()[4:], "trials", "a row has 4 cells for 5"),
    (_rows()[:3] + ["3,11,a/b,1.0,0,9"] + _rows()[4:], "trials", "a row has 6 cells for 5"),
    (_rows()[:5] + [""] + _rows()[6:], "trials", "a row has 0 cells for 5"),
    (_rows()[:7] + ["4,13,a/b,1.0,0"], "trials", "a row of point '4'"),
    (_rows()[:7] + ["03,13,a/b,1.0,0"], "trials", "a row of point '03'"),
    (_rows()[:7] + ["3,14,a/b,1.0,0"], "trials", "trial '14' is not one of trials 10 to 13"),
    (_rows()[:7] + ["3,9,a/b,1.0,0"], "trials", "trial '9' is not one of trials 10 to 13"),
    (_rows()[:7] + ["3,,a/b,1.0,0"], "trials", "trial '' is not one of trials"),
    (_rows()[:7] + ["3,1x,a/b,1.0,0"], "trials", "trial '1x' is not one of trials"),
    (_rows()[:7] + ["3,0:,a/b,1.0,0"], "trials", "trial '0:' is not one of trials"),
    (_rows(range(10, 13)), "trials", "trials missing: 13"),
])
def test_wrong_rows_under_a_right_checksum_are_named(tmp_path, rows, kind, message):
    with pytest.raises(PartDamaged, match=message):
        _read(tmp_path, rows, kind)


def test_a_timings_part_need_not_hold_every_trial(tmp_path):
    assert _read(tmp_path, _rows(range(10, 11)), "timings").rows == 2


def test_a_row_count_other_than_the_header_says_is_damage(tmp_path):
    with pytest.raises(PartDamaged, match="7 rows where 8 were written"):
        _read(tmp_path, _rows()[:7], count=8)


def test_columns_in_another_order_are_checked_line_by_line(tmp_path):
    rows = [",".join(reversed(r.split(","))) for r in _rows()]
    assert _read(tmp_path, rows, header=",".join(reversed(HEADER.split(",")))).rows == 8
    with pytest.raises(PartDamaged, match="a row of point '2'"):
        _read(tmp_path, rows[:-1] + ["0,1.0,a/b,13,2"],
              header=",".join(reversed(HEADER.split(","))))


def _passes_line_by_line(data: str, columns: list[str], rows: int, kind: str) -> bool:
    lines = _lines(data)
    try:
        _check_rows(SPAN, kind, columns, [line.count(",") + 1 if line else 0 for line in lines],
                    lambda reach: [line.split(",", reach) for line in lines], rows)
    except PartDamaged:
        return False
    return True


@settings(max_examples=400, deadline=None)
@given(edits=st.lists(st.tuples(st.integers(0, 10**6), st.sampled_from(
    ["", ",", "\n", "0", "1", "3", "9", ":", "a", "-", " "])), max_size=3),
    kind=st.sampled_from(["trials", "timings"]), trials=st.sets(st.integers(8, 15),
                                                                  min_size=1, max_size=5))
def test_the_array_check_passes_only_rows_the_line_check_passes(edits, kind, trials):
    """Rows of any trials with up to three characters replaced, inserted or removed: the
    array check may leave a part to the line check, never pass one the line check refuses,
    and passes every whole part."""
    data = "".join(r + "\n" for r in _rows(sorted(trials)))
    for at, text in edits:
        at %= len(data) + 1
        data = data[:at] + text + data[at + 1:] if at % 2 else data[:at] + text + data[at:]
    columns = HEADER.split(",")
    rows = max(1, data.count("\n"))
    fits = _rows_fit(data.encode(), SPAN, kind, columns, rows)
    honest = _passes_line_by_line(data, columns, rows, kind)
    assert not fits or honest
    if not edits and (kind == "timings" or trials == set(range(10, 14))) \
            and trials <= set(range(10, 14)):
        assert fits


def test_an_empty_trial_cell_is_not_trial_zero(tmp_path):
    span = BatchSpan(point=0, batch=0, first=0, stop=2)
    rows = ["0,0,a/b,1.0,0", "0,,a/b,1.0,0", "0,1,a/b,1.0,0"]
    path = tmp_path / "part.csv"
    path.write_bytes(part_bytes(span, HEADER + "\n" + "".join(r + "\n" for r in rows), 3))
    with pytest.raises(PartDamaged, match="trial '' is not one of trials 0 to 1"):
        read_part(path, span, "trials")


@pytest.mark.parametrize("trial", ["1²", "١١", "1١"])
def test_a_trial_of_other_than_ascii_digits_is_damage(tmp_path, trial):
    """``str.isdigit`` holds for superscripts (which ``int`` refuses: a ValueError escaped the
    merge's repair loop, which recomputes only a PartDamaged batch) and for other scripts'
    digits (which ``int`` reads: a row whose trial cell is not the runner's was merged)."""
    rows = _rows()[:1] + [f"3,{trial},a/b,1.0,0"] + _rows()[1:]
    with pytest.raises(PartDamaged, match=f"trial '{trial}' is not one of trials 10 to 13"):
        _read(tmp_path, rows, count=len(rows))


def test_a_finished_batch_costs_at_most_200_bytes():
    """The runner keeps a set of the finished batches: 10^4 of them in a 10^6-trial study
    (issue 43, goal 3), measured with tracemalloc."""
    batches = 10_000
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        finished = {BatchSpan(b % 16, b // 16, 100 * (b // 16), 100 * (b // 16) + 100)
                    for b in range(batches)}
        used = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert len(finished) == batches
    assert used / batches <= 220  # about 200 with slots, about 240 without

"""Plain values from loose ones (trackfuse/coerce.py)."""

from trackfuse.coerce import MESSAGE_CHARS, int_or, one_line
from trackfuse.results import RunFolderError


def test_int_or_takes_only_a_true_int():
    assert int_or(7) == 7 and int_or(0, 5) == 0
    assert [int_or(v) for v in (True, "3", 3.0, None, [1])] == [0, 0, 0, 0, 0]
    assert int_or(None, -1) == -1


def test_one_line_reads_like_the_traceback_folded_and_cut():
    assert one_line(ValueError("bad\n  value\tthere")) == "ValueError: bad value there"
    assert one_line(KeyError("point")) == "KeyError: 'point'"
    assert one_line(RunFolderError("held")) == "trackfuse.results.RunFolderError: held"
    long = one_line(RuntimeError("x" * 1000))
    assert len(long) == MESSAGE_CHARS and long.endswith("...")
    assert len(one_line(RuntimeError("x" * 1000), 500)) == 500
    assert one_line(RuntimeError("x" * 10), 24) == "RuntimeError: xxxxxxxxxx"

"""An exception as one line (trackfuse/coerce.py)."""

from trackfuse.coerce import MESSAGE_CHARS, one_line
from trackfuse.results import RunFolderError


def test_one_line_reads_like_the_traceback_folded_and_cut():
    assert one_line(ValueError("bad\n  value\tthere")) == "ValueError: bad value there"
    assert one_line(KeyError("point")) == "KeyError: 'point'"
    assert one_line(RunFolderError("held")) == "trackfuse.results.RunFolderError: held"
    long = one_line(RuntimeError("x" * 1000))
    assert len(long) == MESSAGE_CHARS and long.endswith("...")
    assert len(one_line(RuntimeError("x" * 1000), 500)) == 500
    assert one_line(RuntimeError("x" * 10), 24) == "RuntimeError: xxxxxxxxxx"

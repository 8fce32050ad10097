"""The summary's memory grows slowly with the number of rows (issue 43, goal 3): what it
keeps from chunk to chunk is small and counted in bytes (chunks of whole trials here), and
a chunk of rows is let go, and the heap's free pages given back, before the next is read.
Measured with tracemalloc (Python's own count of its allocations), not with the resident
size, which depends on the host."""

from __future__ import annotations

import tracemalloc
import weakref
from pathlib import Path

import numpy as np
import pandas as pd

import trackfuse.store as store
import trackfuse.summary as summary

#: What a chunk of the summary may keep beyond its (n, mean, M2): a tuple, a list slot, three
#: array headers, and pandas' record of the views of each chunk's frames, which it clears
#: every few hundred chunks (about 2 KiB a chunk until then).
CHUNK_OVERHEAD = 2560


def _orbit_like_chunk(seed: int) -> pd.DataFrame:
    """1,000 rows of one sweep point: 2 algorithms x 20 scans (40 groups), 3 metrics."""
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"point": 0, "algorithm": np.repeat(["a", "b"], 500),
                         "scan": np.tile(np.arange(20), 50),
                         **{m: rng.normal(size=1000) for m in ("x", "y", "z")}})


def _read_as_orbit_chunks(monkeypatch, count: int) -> tuple[list[int], list[bool]]:
    """Make the summary's chunks ``count`` frames of :func:`_orbit_like_chunk`; return the
    traced bytes when each is asked for and whether the chunk before was still held then."""
    traced: list[int] = []
    held: list[bool] = []
    given: weakref.ref | None = None

    def chunks(source, chunk_rows):
        nonlocal given
        for _ in range(count):
            held.append(given is not None and given() is not None)
            traced.append(tracemalloc.get_traced_memory()[0])
            chunk = _orbit_like_chunk(1)  # anew: a copy would add to its source's refs
            given = weakref.ref(chunk)
            yield chunk
            del chunk

    monkeypatch.setattr(summary, "_chunks", chunks)
    return traced, held


def test_the_summary_keeps_24_bytes_a_group_and_metric_from_chunk_to_chunk(monkeypatch):
    groups, metrics, count = 40, 3, 150
    traced, _ = _read_as_orbit_chunks(monkeypatch, count)
    tracemalloc.start()
    try:
        result, failed = summary.summarize(Path("unused.csv"), ["point", "algorithm", "scan"])
    finally:
        tracemalloc.stop()
    assert failed == 0 and len(result) == groups * metrics
    assert (result["n"] == 25 * count).all()
    kept = (traced[-1] - traced[20]) / (count - 1 - 20)  # bytes a chunk, once warmed up
    assert kept <= 24 * groups * metrics + CHUNK_OVERHEAD


def test_the_summary_holds_one_chunk_while_reading_the_next(monkeypatch):
    _, held = _read_as_orbit_chunks(monkeypatch, 5)
    summary.summarize(Path("unused.csv"), ["point", "algorithm", "scan"])
    assert held == [False] * 5


def test_chunks_give_the_heap_back_before_each_next_chunk(tmp_path, monkeypatch):
    path = tmp_path / "trials.csv"
    pd.DataFrame({"point": 0, "x": np.arange(10.0)}).to_csv(path, index=False)
    released: list[int] = []
    monkeypatch.setattr(store, "release_free_memory", lambda: released.append(1))
    seen = [len(released) for _ in store.chunks(path, 3)]
    assert seen == [0, 1, 2, 3]
    assert len(released) == 4

"""Size and load time of a large twin_sensor run's rows: trials.csv against trials.parquet.

Runs ``configs/ci/twin_sensor_ci.yaml`` at one clutter level (5 per gate) with two
algorithms (nearest neighbour and parallel PDA, both MGEKF), 20 scans a trial, so each trial
writes 40 rows, for ``--trials`` trials (default 100,000: 4 million rows) into a CSV run
(or reuses that run when it is complete), then converts its ``trials.csv`` to Parquet with
:func:`trackfuse.store.write_parquet` (what ``outputs.store: parquet`` runs) and times,
best of ``--repeat``, the read ``trackfuse.load(run).trials`` does for each file
(:func:`trackfuse.store.read_trials`), and the summary's chunked pass over each
(:func:`trackfuse.summary.summarize`). Both reads give equal frames (checked).

Usage: ``python benchmarks/store_size.py [--trials 100000] [--workers 2] [--out DIR]``
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import pandas as pd

from trackfuse.config import load
from trackfuse.runner import Runner
from trackfuse.shipped import config_path
from trackfuse.store import read_trials, write_parquet
from trackfuse.summary import summarize

ALGORITHMS = ["nn/mgekf", "mspda_parallel/mgekf"]


def run_csv(trials: int, workers: int, out: Path) -> Path:
    """The complete CSV run of ``trials`` trials (computed, or found complete)."""
    config = load(config_path(Path("ci/twin_sensor_ci")), {"trials": trials,
                                                          "algorithms": ALGORITHMS,
                                                          "clutter.mean": 5.0})
    start = time.perf_counter()
    outcome = Runner(config, out, workers=workers, plots=False, progress=False).run()
    print(f"run: {outcome.total_trials} trials, {outcome.rows} rows, computed "
          f"{outcome.computed_trials} in {time.perf_counter() - start:.1f} s "
          f"({workers} workers)")
    return outcome.folder


def best_of(repeat: int, action) -> tuple[float, object]:
    """The fastest of ``repeat`` calls of ``action`` (seconds) and its last result."""
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = action()
        times.append(time.perf_counter() - start)
    return min(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("results/bench_store"))
    args = parser.parse_args()
    folder = run_csv(args.trials, args.workers, args.out)
    csv = folder / "trials.csv"
    with tempfile.TemporaryDirectory(prefix="store-size-") as tmp:
        copy = Path(tmp) / "trials.csv"
        shutil.copyfile(csv, copy)
        start = time.perf_counter()
        record = write_parquet(copy, Path(tmp) / "trials.parquet")
        convert = time.perf_counter() - start
        parquet = Path(tmp) / "trials.parquet"
        keys = ["point", "clutter.mean", "algorithm", "scan"]
        rows = {}
        for path in (csv, parquet):
            read_s, frame = best_of(args.repeat, lambda p=path: read_trials(p))
            summary_s, _ = best_of(1, lambda p=path: summarize(p, keys))
            rows[path.suffix] = frame
            print(f"{path.name:15s} {path.stat().st_size / 1e6:9.1f} MB  load {read_s:6.2f} s  "
                  f"summary pass {summary_s:6.2f} s  ({len(frame)} rows, "
                  f"{frame.shape[1]} columns)")
        pd.testing.assert_frame_equal(rows[".csv"], rows[".parquet"])
        print(f"conversion (outputs.store: parquet at the end of the run): {convert:.2f} s; "
              f"Parquet/CSV size {record['bytes'] / csv.stat().st_size:.3f}")


if __name__ == "__main__":
    main()

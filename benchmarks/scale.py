"""Throughput and peak memory of large runs of a cheap experiment (issue 6).

For 10^4, 10^5 and 10^6 trials of the test suite's trivial experiment, runs ``trackfuse run``
as a subprocess with 2 process workers and with a 2-worker dask LocalCluster, samples the
resident memory of the whole process tree (runner, pool or cluster workers) every 50 ms, and
prints trials/s and peak RSS. Flat memory means the 10^6 peak stays within 2x the 10^4 peak.

    python benchmarks/scale.py [--sizes 10000 100000 1000000] [--executors process dask]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]


def tree_rss(proc: psutil.Process) -> int:
    """Resident bytes of ``proc`` and all its descendants."""
    total = 0
    for p in [proc, *proc.children(recursive=True)]:
        with contextlib.suppress(psutil.Error):
            total += p.memory_info().rss
    return total


def measure(trials: int, executor: str) -> tuple[float, float]:
    """Return (trials/s, peak tree RSS in MiB) of one run."""
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "scale.yaml"
        cfg.write_text(f"experiment: toy_experiments:TRIVIAL\ntrials: {trials}\nseed: 1\n")
        env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "tests"), str(ROOT)])}
        command = [sys.executable, "-m", "cli.main", "run", str(cfg), "--out", tmp,
                   "--workers", "2", "--executor", executor, "--no-progress", "--no-plots"]
        t0 = time.perf_counter()
        proc = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL)
        watched = psutil.Process(proc.pid)
        peak = 0
        stop = threading.Event()

        def sample() -> None:
            nonlocal peak
            while not stop.is_set():
                try:
                    peak = max(peak, tree_rss(watched))
                except psutil.Error:
                    break
                time.sleep(0.05)

        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
        code = proc.wait()
        stop.set()
        sampler.join()
        seconds = time.perf_counter() - t0
        if code != 0:
            raise SystemExit(f"run failed with exit status {code}")
    return trials / seconds, peak / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--executors", nargs="+", default=["process", "dask"])
    args = parser.parse_args()
    for executor in args.executors:
        peaks = []
        for n in args.sizes:
            rate, peak = measure(n, executor)
            peaks.append(peak)
            print(f"{executor:8s} {n:>9,d} trials: {rate:>9,.0f} trials/s (end to end, incl. "
                  f"start-up), peak RSS of the process tree {peak:,.0f} MiB", flush=True)
        print(f"{executor:8s} peak RSS ratio {args.sizes[-1]:,d} / {args.sizes[0]:,d} trials: "
              f"{peaks[-1] / peaks[0]:.2f}x", flush=True)


if __name__ == "__main__":
    main()

"""Runner overhead and parallel speed-up, measured through the public Runner API.

Prints (1) trials/s for a trivial experiment (one uniform draw per trial) with 2 process
workers, and (2) the 2-worker speed-up on a CPU-bound experiment (dense eigen-decompositions),
against 1 worker in-process. Both experiments are the test suite's toy experiments.

    python benchmarks/runner_overhead.py [--trivial-trials 200000] [--burn-trials 2000]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per worker, as in the process pool
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import toy_experiments  # noqa: E402,F401 - registers the toy experiments

from trackfuse.config import build  # noqa: E402
from trackfuse.runner import Runner  # noqa: E402


def timed_run(experiment: str, trials: int, workers: int, executor: str,
              params: dict | None = None) -> float:
    raw = {"experiment": experiment, "trials": trials, "seed": 1, "params": params or {}}
    config = build(raw, f"{experiment}.yaml")
    with tempfile.TemporaryDirectory() as out:
        runner = Runner(config, Path(out), workers=workers, executor=executor, plots=False,
                        progress=False)
        t0 = time.perf_counter()
        runner.run()
        return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trivial-trials", type=int, default=200_000)
    parser.add_argument("--burn-trials", type=int, default=2000)
    args = parser.parse_args()

    n = args.trivial_trials
    seconds = timed_run("toy_trivial", n, 2, "process")
    print(f"trivial experiment, 2 process workers: {n} trials in {seconds:.2f} s "
          f"= {n / seconds:,.0f} trials/s (end to end: pool start, CSV merge, summary)")
    seconds = timed_run("toy_trivial", n, 1, "serial")
    print(f"trivial experiment, serial:            {n} trials in {seconds:.2f} s "
          f"= {n / seconds:,.0f} trials/s")

    m = args.burn_trials
    one = timed_run("toy_burn", m, 1, "serial", {"work": 20})
    two = timed_run("toy_burn", m, 2, "process", {"work": 20})
    print(f"CPU-bound experiment: 1 worker {one:.2f} s, 2 workers {two:.2f} s, "
          f"speed-up {one / two:.2f}x")


if __name__ == "__main__":
    main()

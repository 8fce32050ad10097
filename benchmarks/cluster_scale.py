"""Scaling through ``--cluster`` (dask-jobqueue) on this machine, and its per-batch cost.

Runs through the same code path as ``--cluster slurm`` (an adaptive dask-jobqueue cluster
whose jobs start dask workers), with dask-jobqueue's local job class, so each "job" is a
local process:

1. a CPU-bound experiment (the test suite's ``toy_burn``: dense eigen-decompositions) with
   ``max_jobs`` 1 and 2 (one core each), against the serial executor: wall time of the
   whole run (jobs starting, the workers' code check, the batches, merge and summary) and
   the speed-up;
2. the per-batch cost: the test suite's ``toy_trivial`` (one uniform draw per trial) in
   batches of one trial on 2 job workers: seconds per batch end to end, which is what the
   scheduler round trip plus this process's part writing cost per batch.

docs/cluster.md turns the two numbers into what 100 nodes would give.

    python benchmarks/cluster_scale.py [--burn-trials 800] [--batches 2000]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core per worker, as in the job script
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(TESTS),
                                                         os.environ.get("PYTHONPATH")]))
sys.path.insert(0, str(TESTS))

import toy_experiments  # noqa: E402,F401 - registers the toy experiments

from trackfuse.config import build  # noqa: E402
from trackfuse.runner import Runner  # noqa: E402


def timed_run(raw: dict, **how) -> tuple[float, float]:
    """``(wall, this process's CPU)`` seconds of one whole run of the config ``raw`` (a
    fresh output folder). This process hosts the scheduler and writes the parts; CPU
    seconds, unlike wall seconds, hardly depend on what else the machine runs."""
    config = build(raw, "cluster_scale.yaml")
    with tempfile.TemporaryDirectory() as out:
        runner = Runner(config, Path(out), plots=False, progress=False, **how)
        start, cpu = time.perf_counter(), time.process_time()
        runner.run()
        return time.perf_counter() - start, time.process_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--burn-trials", type=int, default=800)
    parser.add_argument("--batches", type=int, default=2000)
    args = parser.parse_args()
    burn = {"experiment": "toy_experiments:BURN", "trials": args.burn_trials, "seed": 1,
            "params": {"work": 20}, "batch_size": 8}
    print(f"load average before: {', '.join(f'{x:.1f}' for x in os.getloadavg())} "
          f"on {os.cpu_count()} cores")
    serial, cpu = timed_run(burn, executor="serial")
    print(f"toy_burn {args.burn_trials} trials in batches of 8: serial {serial:.2f} s wall, "
          f"{cpu:.2f} s CPU")
    for jobs in (1, 2):
        cluster = {"cores": 1, "memory": "2GB", "min_jobs": jobs, "max_jobs": jobs}
        wall, cpu = timed_run({**burn, "cluster": cluster}, cluster="local")
        print(f"  --cluster local, {jobs} job(s) of 1 worker: {wall:.2f} s wall "
              f"({serial / wall:.2f}x serial); this process {cpu:.2f} s CPU")
    trivial = {"experiment": "toy_experiments:TRIVIAL", "trials": args.batches, "seed": 1,
               "batch_size": 1, "cluster": {"cores": 1, "memory": "1GB", "min_jobs": 2,
                                             "max_jobs": 2}}
    wall, cpu = timed_run(trivial, cluster="local")
    n = args.batches
    print(f"toy_trivial, {n} batches of 1 trial on 2 job workers: {1e3 * wall / n:.2f} ms "
          f"wall per batch; this process (scheduler, client, part writing) "
          f"{1e3 * cpu / n:.2f} ms CPU per batch")
    wall, cpu = timed_run({**trivial, "cluster": {}}, executor="serial")
    print(f"  the same serially (no scheduler): {1e3 * wall / n:.2f} ms wall, "
          f"{1e3 * cpu / n:.2f} ms CPU per batch")
    print(f"load average after: {', '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()

"""Trials per second of the twin_sensor experiment, one process (one core).

Measures the batched implementation at clutter mean 10 for
  (a) one sensor, EKF covariance + single-sensor PDAF, and
  (b) two sensors, MGEKF + fused (parallel, (m1+1)(m2+1)-hypothesis) PDA,
for the experiment's default ``in_gate`` clutter and for ``window`` clutter (a fixed box of
+-0.03 rad about the line of sight, roughly the gate size, so about 10 false returns fall in
the gate; those returns do not depend on the filter, so every tracker sees the same data).
When Stone Soup is importable (the optional ``stonesoup`` extra) it runs Stone Soup's EKF + PDA
(the ``stonesoup_pda/ekf`` algorithm, :mod:`trackfuse.interop.stonesoup`) on the one-sensor
window scenario, on exactly the same simulated returns, in this process, and prints the ratio.

Usage: ``python benchmarks/twin_sensor_speed.py [--trials 2000] [--batch 500] [--profile]``
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import time

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.seeding import trial_streams


def params(sensors: int, algorithm: str, model: str) -> dict:
    p = EXPERIMENT.defaults()
    p.update({"sensors.count": sensors, "algorithms": [algorithm], "clutter.mean": 10.0,
              "clutter.model": model, "clutter.window": 0.03})
    return p


def ours(p: dict, trials: int, batch: int) -> float:
    """Trials per second of ``run_batch`` over ``trials`` trials in batches of ``batch``."""
    EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in range(8)])  # warm-up
    start = time.perf_counter()
    for first in range(0, trials, batch):
        rngs = [trial_streams(1, 0, t) for t in range(first, min(first + batch,
                                                                          trials))]
        EXPERIMENT.run_batch(p, rngs)
    return trials / (time.perf_counter() - start)


def stonesoup_rate(p: dict, trials: int) -> float:
    """Trials per second of Stone Soup's EKF + PDA (``stonesoup_pda/ekf``, run through
    ``trackfuse.interop.stonesoup``) on the same data as ``ours``; per-trial, so no batching."""
    return ours({**p, "algorithms": ["stonesoup_pda/ekf"]}, trials, trials)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--batch", type=int, default=500)
    parser.add_argument("--stonesoup-trials", type=int, default=20)
    parser.add_argument("--profile", action="store_true", help="cProfile case (b), in_gate")
    args = parser.parse_args()
    cases = {"(a) 1 sensor, EKF + PDAF": (1, "mspda_parallel/ekf"),
             "(b) 2 sensors, MGEKF + fused PDA": (2, "mspda_parallel/mgekf")}
    print(f"twin_sensor, 20 scans/trial, clutter mean 10, batch {args.batch}, one process")
    rates = {}
    for model in ("in_gate", "window"):
        for name, (sensors, algorithm) in cases.items():
            rates[name, model] = ours(params(sensors, algorithm, model), args.trials, args.batch)
            print(f"  trackfuse {name:34s} {model:8s} {rates[name, model]:10.1f} trials/s")
    try:
        import stonesoup  # noqa: F401
    except ImportError:
        print("  Stone Soup not installed (pip install '.[stonesoup]'): comparison skipped")
    else:
        ss = stonesoup_rate(params(1, "mspda_parallel/ekf", "window"), args.stonesoup_trials)
        mine = rates["(a) 1 sensor, EKF + PDAF", "window"]
        print(f"  Stone Soup (a) 1 sensor, EKF + PDA           window   {ss:10.1f} trials/s")
        print(f"  ratio trackfuse / Stone Soup, case (a), window: {mine / ss:.0f}x")
    if args.profile:
        p = params(2, "mspda_parallel/mgekf", "in_gate")
        rngs = [trial_streams(1, 0, t) for t in range(args.batch)]
        prof = cProfile.Profile()
        prof.runcall(EXPERIMENT.run_batch, p, rngs)
        out = io.StringIO()
        pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(15)
        print(out.getvalue())


if __name__ == "__main__":
    main()

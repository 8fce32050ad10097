"""Trials per second of the twin_sensor experiment, one process (one core).

Measures, at clutter mean 10,
  (a) one sensor, EKF covariance + single-sensor PDAF, and
  (b) two sensors, MGEKF + fused (parallel, (m1+1)(m2+1)-hypothesis) PDA,
three ways: the compiled filter loop alone (``trackfuse.tracking.pda.run_filter``, best of 5 on the
same simulated batch), its numpy oracle (``tests/pda_reference.py``, which also scores),
and the whole ``run_batch`` (random streams, simulation, filter, scoring, rows),
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
import math
import pstats
import sys
import time
from pathlib import Path

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    FILTERS,
    LossRules,
    build_scenario,
    simulate,
    stack,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda import run_filter
from trackfuse.tracking.pda_options import PDAOptions

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import pda_reference as reference  # noqa: E402 (the numpy oracle lives with the tests)


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


def filter_rates(p: dict, batch: int) -> tuple[float, float]:
    """Trials per second of the compiled filter loop (best of 5) and of the numpy reference,
    on one simulated batch of ``batch`` trials."""
    sc = build_scenario(p)
    data = stack([simulate(sc, trial_streams(1, 0, t)) for t in range(batch)])
    assoc, filt = p["algorithms"][0].split("/")
    options = PDAOptions(assoc, FILTERS[filt], P_G=sc.P_G)
    run_filter(sc, data, options)  # load (or compile) outside the timing
    best = math.inf
    for _ in range(5):
        start = time.perf_counter()
        run_filter(sc, data, options)
        best = min(best, time.perf_counter() - start)
    start = time.perf_counter()
    reference.run_filter(sc, data, options, LossRules.from_params(p))
    return batch / best, batch / (time.perf_counter() - start)


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
    print(f"twin_sensor, 20 scans/trial, clutter mean 10, batch {args.batch}, one process; "
          "trials/s of: compiled filter | numpy reference | whole run_batch")
    rates = {}
    for model in ("in_gate", "window"):
        for name, (sensors, algorithm) in cases.items():
            p = params(sensors, algorithm, model)
            compiled, reference = filter_rates(p, args.batch)
            rates[name, model] = ours(p, args.trials, args.batch)
            print(f"  trackfuse {name:34s} {model:8s} {compiled:10.1f} | {reference:8.1f} | "
                  f"{rates[name, model]:8.1f}")
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

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

Then the whole ``run_batch`` side by side with a baseline commit (installed as in
``end_to_end.py``), in fresh processes, alternating, at the experiment's default ``in_gate``
clutter: trials per wall second and per CPU second of the process (on a shared machine the
CPU figure is the steadier one), median of the repeats, and the ratio current / baseline.

``--breakdown`` prints where a case (b) trial's CPU microseconds go in this checkout (best
of 7 batches: simulation, compiled filter, scoring, the whole ``run_batch``) and what the
whole ``run_batch`` costs in the first batch of a process against the next ones (the first
pays the kernel's page faults as the process's memory grows), and with ``--baseline``
(any value) the same phases of b359dda, goal 2's baseline, in its own venv.

Usage: ``python benchmarks/twin_sensor_speed.py [--trials 2000] [--batch 500] [--profile]
[--breakdown] [--baseline b359dda] [--repeats 3]`` (``--baseline ''`` skips the comparison)
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import math
import pstats
import statistics
import subprocess
import sys
import time
from pathlib import Path

from end_to_end import install

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    FILTERS,
    LossRules,
    build_scenario,
    score_estimates,
    simulate,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda import run_filter
from trackfuse.tracking.pda_options import PDAOptions

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import pda_reference as reference  # noqa: E402 (the numpy oracle lives with the tests)

CASES = {"(a) 1 sensor, EKF + PDAF": (1, "mspda_parallel/ekf"),
         "(b) 2 sensors, MGEKF + fused PDA": (2, "mspda_parallel/mgekf")}


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
    data = simulate(sc, [trial_streams(1, 0, t) for t in range(batch)])
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


#: A fresh process of either version, ``run_batch`` run once on 8 trials (the same code for
#: both: the experiment's ``run_batch(params, streams)`` has not changed its signature).
WARMED = """
import json, sys, time
from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.seeding import trial_streams
p, trials, batch = json.loads(sys.argv[1])
EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in range(8)])
"""
#: Then times ``run_batch`` over ``trials`` trials in batches of ``batch``.
RATE = WARMED + """start, cpu = time.perf_counter(), time.process_time()
for first in range(0, trials, batch):
    EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in range(first, min(first + batch,
                                                                            trials))])
print(trials / (time.perf_counter() - start), trials / (time.process_time() - cpu))
"""


def side_by_side(baseline: str, trials: int, batch: int, repeats: int) -> None:
    """Print the whole ``run_batch`` rate of this checkout and of ``baseline``, each case
    timed in fresh processes, alternating the versions."""
    home = install(baseline)
    pythons = {"current": (sys.executable, Path(__file__).resolve().parents[1]),
               "baseline": (str(home / "venv" / "bin" / "python"), home / "src")}
    print(f"whole run_batch, in_gate clutter, trials/s (median of {repeats}), "
          f"baseline {home.name}:")
    for name, (sensors, algorithm) in CASES.items():
        arg = json.dumps([params(sensors, algorithm, "in_gate"), trials, batch])
        rates: dict[str, list[list[float]]] = {v: [] for v in pythons}
        for rep in range(repeats):
            for version in list(pythons)[::1 if rep % 2 == 0 else -1]:
                python, cwd = pythons[version]
                out = subprocess.run([python, "-c", RATE, arg], cwd=cwd, check=True,
                                     capture_output=True, text=True).stdout
                rates[version].append([float(x) for x in out.split()[-2:]])
        for i, clock in enumerate(("wall", "CPU")):
            cur, base = (statistics.median(r[i] for r in rates[v])
                         for v in ("current", "baseline"))
            print(f"  {name:34s} per {clock:4s} s: current {cur:8.1f} | baseline {base:8.1f}"
                  f" | {cur / base:.2f}x")


def breakdown(batch: int, batches: int = 7) -> None:
    """Print case (b)'s CPU microseconds a trial by phase, best of ``batches`` batches."""
    p = params(2, "mspda_parallel/mgekf", "in_gate")
    rules = LossRules.from_params(p)
    spent: dict[str, list[float]] = {k: [] for k in ("simulation", "filter", "scoring",
                                                     "whole run_batch")}
    for rep in range(batches):
        first = (rep + 1) * batch
        trials = range(first, first + batch)
        start = time.process_time()
        EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in trials])
        spent["whole run_batch"].append(time.process_time() - start)
        start = time.process_time()
        sc = build_scenario(p)
        data = simulate(sc, [trial_streams(1, 0, t) for t in trials])
        spent["simulation"].append(time.process_time() - start)
        assoc, filt = p["algorithms"][0].split("/")
        options = PDAOptions(assoc, FILTERS[filt], P_G=sc.P_G)
        start = time.process_time()
        estimates = run_filter(sc, data, options)
        spent["filter"].append(time.process_time() - start)
        start = time.process_time()
        score_estimates(sc, data, estimates, rules)
        spent["scoring"].append(time.process_time() - start)
    best = {k: min(v) / batch * 1e6 for k, v in spent.items()}
    print(f"case (b), in_gate, CPU us a trial, best of {batches} batches of {batch}: "
          + ", ".join(f"{k} {v:.1f}" for k, v in best.items())
          + f"; outside the filter {best['whole run_batch'] - best['filter']:.1f}")


#: The same phases in b359dda's code (goal 2's baseline), whose simulation ran per trial and
#: whose filter lived in ``twin_sensor.kernel``; run in its venv by ``--breakdown``.
B359DDA_PHASES = """
import sys, time
from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor import model as m
from trackfuse.experiments.twin_sensor.kernel import run_filter_compiled
from trackfuse.seeding import trial_streams
p = EXPERIMENT.defaults()
p.update({"sensors.count": 2, "algorithms": ["mspda_parallel/mgekf"], "clutter.mean": 10.0,
          "clutter.model": "in_gate"})
rules, batch = m.LossRules.from_params(p), int(sys.argv[1])
spent = {k: [] for k in ("simulation", "filter", "scoring", "whole run_batch")}
EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in range(8)])
for rep in range(7):
    trials = range((rep + 1) * batch, (rep + 2) * batch)
    s = time.process_time()
    EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in trials])
    spent["whole run_batch"].append(time.process_time() - s)
    s = time.process_time()
    sc = m.build_scenario(p)
    data = m.stack([m.simulate(sc, trial_streams(1, 0, t)) for t in trials])
    spent["simulation"].append(time.process_time() - s)
    s = time.process_time()
    est = run_filter_compiled(sc, data, m.PDAOptions("mspda_parallel", "mgekf", P_G=sc.P_G))
    spent["filter"].append(time.process_time() - s)
    s = time.process_time()
    m.score_estimates(sc, data, est, rules)
    spent["scoring"].append(time.process_time() - s)
best = {k: min(v) / batch * 1e6 for k, v in spent.items()}
print(", ".join(f"{k} {v:.1f}" for k, v in best.items())
      + f"; outside the filter {best['whole run_batch'] - best['filter']:.1f}")
"""


def baseline_breakdown(batch: int) -> None:
    """Print :data:`B359DDA_PHASES` measured in b359dda's own venv."""
    home = install("b359dda")
    out = subprocess.run([str(home / "venv" / "bin" / "python"), "-c", B359DDA_PHASES,
                          str(batch)], cwd=home / "src", check=True, capture_output=True,
                         text=True).stdout.strip()
    print(f"b359dda, the same phases: {out}")


def first_batches(batch: int, batches: int = 4) -> None:
    """Print the whole ``run_batch``'s CPU microseconds a trial in each of the first
    ``batches`` batches of a fresh process (after :data:`WARMED`'s 8-trial warm-up)."""
    code = WARMED + f"""
import resource
for first in range(0, {batches * batch}, {batch}):
    cpu, faults = time.process_time(), resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    EXPERIMENT.run_batch(p, [trial_streams(1, 0, t) for t in range(first, first + {batch})])
    print(round((time.process_time() - cpu) / {batch} * 1e6, 1),
          resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults)
"""
    arg = json.dumps([params(2, "mspda_parallel/mgekf", "in_gate"), 0, batch])
    out = subprocess.run([sys.executable, "-c", code, arg], check=True, capture_output=True,
                         text=True).stdout.split("\n")
    cells = [line.split() for line in out if line.strip()]
    print("case (b), a fresh process, CPU us a trial (page faults) in batch 1..: "
          + ", ".join(f"{us} ({faults})" for us, faults in cells))


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
    parser.add_argument("--baseline", default="b359dda")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--breakdown", action="store_true",
                        help="where case (b)'s CPU goes, by phase and by batch")
    args = parser.parse_args()
    if args.breakdown:
        breakdown(args.batch)
        first_batches(args.batch)
        if args.baseline:
            baseline_breakdown(args.batch)
        return
    print(f"twin_sensor, 20 scans/trial, clutter mean 10, batch {args.batch}, one process; "
          "trials/s of: compiled filter | numpy reference | whole run_batch")
    rates = {}
    for model in ("in_gate", "window"):
        for name, (sensors, algorithm) in CASES.items():
            p = params(sensors, algorithm, model)
            compiled, numpy_rate = filter_rates(p, args.batch)
            rates[name, model] = ours(p, args.trials, args.batch)
            print(f"  trackfuse {name:34s} {model:8s} {compiled:10.1f} | {numpy_rate:8.1f} | "
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
    if args.baseline:
        side_by_side(args.baseline, args.trials, args.batch, args.repeats)
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

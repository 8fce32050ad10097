"""Speed of the S-D assignment per instance: the Lagrangian relaxation against the exact
optimum (integer program) for S = 3 and 4 sensors, and, for S = 2, against the exact 2-D
solver and one 1000-operation run of the partheno-genetic algorithm (PGA) of paper 002.

Run ``python benchmarks/sd_assignment_speed.py`` (``--instances N`` per row, default 20).
Each instance is one scan of ``passive_sd``'s geometry (sensor 3 at 20 km, sensor 4 at
(20, 20, 0) km; angle noise 0.01 rad, P_D 0.95, false alarms 0.05 N per sensor); the table
prints the median wall time per instance of the tuple costs and of each solver, the
relaxation's median iterations and relative duality gap, and how often it reached the
optimum. The compiled kernel is warmed up before timing.
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import numpy as np

from trackfuse.association.assignment import PairWeights, solve_exact
from trackfuse.association.passive_scene import KM, SENSORS, scene_targets, simulate_scan
from trackfuse.association.pga_search import pga
from trackfuse.association.sd_assignment import solve_sd, solve_sd_exact
from trackfuse.association.sd_costs import tuple_costs

SIGMA, P_D, P_F = 0.01, 0.95, 0.05
ALL_SENSORS = np.vstack([SENSORS, [[20.0 * KM, 0.0, 0.0], [20.0 * KM, 20.0 * KM, 0.0]]])


def instance(n_targets: int, n_sensors: int, seed: int) -> np.ndarray:
    """The tuple-cost tensor of one simulated scan."""
    truth, noise, clutter, shuffle = np.random.default_rng(seed).spawn(4)
    scan = simulate_scan(scene_targets(n_targets, "random", truth), SIGMA, SIGMA, P_D, P_F,
                         noise, clutter, shuffle, sensors=ALL_SENSORS[:n_sensors])
    return tuple_costs(scan.z, scan.sensors, SIGMA, SIGMA, P_D, P_F)


def timed(fn):
    """``(result, wall seconds)`` of ``fn()``."""
    start = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - start


def row(n_targets: int, n_sensors: int, instances: int) -> str:
    costs, lagrangian, exact, others, gaps, iterations, at_opt = [], [], [], {}, [], [], 0
    for seed in range(instances):
        cost, t = timed(partial(instance, n_targets, n_sensors, seed))
        costs.append(t)
        relaxed, t = timed(partial(solve_sd, cost))
        lagrangian.append(t)
        optimum, t = timed(partial(solve_sd_exact, cost))
        exact.append(t)
        gaps.append(relaxed.gap)
        iterations.append(relaxed.iterations)
        at_opt += relaxed.primal <= optimum.primal + 1e-9 * max(1.0, abs(optimum.primal))
        if n_sensors == 2:
            gain = -cost[1:, 1:]
            _, t = timed(partial(solve_exact, gain))
            others.setdefault("exact_2d", []).append(t)
            weights = PairWeights(a=gain, a_i0=np.zeros(len(gain)),
                                  a_0j=np.zeros(gain.shape[1]), chi2=np.zeros_like(gain))
            _, t = timed(partial(pga, weights, np.random.default_rng(seed), ops=1000,
                                 repair_moves=True, staged=True, evict=True))
            others.setdefault("pga_evict", []).append(t)
    ms = {name: 1e3 * float(np.median(v)) for name, v in
          {"costs": costs, "sd_lagrangian": lagrangian, "sd_exact": exact, **others}.items()}
    extra = "  ".join(f"{k} {v:7.3f}" for k, v in ms.items() if k in others)
    return (f"S={n_sensors} N={n_targets:3d} | costs {ms['costs']:7.2f}  sd_lagrangian "
            f"{ms['sd_lagrangian']:7.2f}  sd_exact {ms['sd_exact']:7.2f}  {extra} ms | "
            f"iterations {np.median(iterations):5.1f}  gap {100 * np.median(gaps):5.2f} %  "
            f"at optimum {at_opt}/{instances}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instances", type=int, default=20, help="instances per row")
    args = parser.parse_args()
    solve_sd(instance(3, 3, 0))  # load or compile the kernel
    pga(PairWeights(a=np.zeros((1, 1)), a_i0=np.zeros(1), a_0j=np.zeros(1),
                    chi2=np.zeros((1, 1))), np.random.default_rng(0), ops=10,
        repair_moves=True, staged=True, evict=True)
    print("median wall time per instance (ms); one core")
    for n_sensors, sizes in ((2, (10, 20, 40)), (3, (5, 10, 20, 40)), (4, (5, 10, 20))):
        for n in sizes:
            print(row(n, n_sensors, args.instances), flush=True)


if __name__ == "__main__":
    main()

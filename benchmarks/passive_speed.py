"""Speed of the paper-002 pieces: weights, exact solvers, one PGA run, the whole experiment.

Run ``python benchmarks/passive_speed.py`` (add ``--profile`` for a cProfile listing of one
PGA run). Goals (issue 5): exact solve < 1 ms for 10 targets and < 50 ms for 200; one
1000-operation PGA run for 10 targets < 20 ms; the whole paper experiment
(configs/passive_association.yaml, 3 x 50 trials) < 10 s on 2 cores. Issue 16: the compiled
PGA loop (what the experiment runs) at least 10 times faster than the Python reference.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import subprocess
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

from trackfuse.association.assignment import pair_weights, solve_exact
from trackfuse.association.passive_scene import SENSORS, scene_targets, simulate_scan
from trackfuse.association.pga_search import pga as pga_compiled

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from pga_reference import pga  # noqa: E402 (the Python oracle lives with the tests)

SIGMA, P_D, P_F = 0.005, 0.95, 0.05


def scan_weights(n: int, mode: str, seed: int = 0):
    rng = np.random.default_rng(seed)
    truth, noise, clutter, shuffle = rng.spawn(4)
    scan = simulate_scan(scene_targets(n, mode, truth), SIGMA, SIGMA, P_D, P_F, noise,
                         clutter, shuffle)
    return scan, pair_weights(*scan.z, *SENSORS, SIGMA, SIGMA, P_D, P_F)


def best_of(fn, repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` calls, s."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def report(label: str, seconds: float, goal_ms: float | None = None) -> None:
    goal = f"  (goal < {goal_ms:g} ms)" if goal_ms else ""
    print(f"{label:55s} {seconds * 1e3:9.3f} ms{goal}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", action="store_true", help="cProfile one PGA run")
    parser.add_argument("--skip-experiment", action="store_true",
                        help="do not time the whole paper experiment")
    args = parser.parse_args()

    for n, mode in ((10, "paper"), (200, "random")):
        scan, w = scan_weights(n, mode)
        shape = f"{w.a.shape[0]}x{w.a.shape[1]}"
        for tri in ("unit_normal", "ml"):
            weigh = partial(pair_weights, *scan.z, *SENSORS, SIGMA, SIGMA, P_D, P_F, tri=tri)
            report(f"weights ({tri} triangulation), {n} targets ({shape})", best_of(weigh, 10))
        for method in ("lsa_clip", "lsa_augmented"):
            report(f"exact {method}, {n} targets", best_of(partial(solve_exact, w.gain, method),
                                                           50), 1.0 if n == 10 else 50.0)

    _, w10 = scan_weights(10, "paper")
    _, w200 = scan_weights(200, "random")
    ours = {"repair_moves": True, "staged": True, "evict": True}
    pga_compiled(w10, np.random.default_rng(1), ops=10)  # load (or compile) the kernel
    for name, options in (("paper-like", {}), ("ours (evicting re-pair, staged)", ours)):
        for label, solver in (("Python", pga), ("compiled", pga_compiled)):
            run = partial(solver, w10, np.random.default_rng(1), ops=1000, **options)
            report(f"PGA {name}, {label}, 1000 ops, 10 targets", best_of(run, 30), 20.0)
            run = partial(solver, w200, np.random.default_rng(1), ops=1000, **options)
            report(f"PGA {name}, {label}, 1000 ops, 200 targets", best_of(run, 5))

    if args.profile:
        prof = cProfile.Profile()
        prof.enable()
        for seed in range(20):
            pga(w10, np.random.default_rng(seed), ops=1000, **ours)
        prof.disable()
        pstats.Stats(prof).sort_stats("cumulative").print_stats(8)

    if not args.skip_experiment:
        with tempfile.TemporaryDirectory() as out:
            cfg = ROOT / "configs" / "passive_association.yaml"
            for extra in ([], ["--no-plots"]):
                start = time.perf_counter()
                subprocess.run([sys.executable, "-m", "cli.main", "run", str(cfg), "--out",
                                f"{out}/{len(extra)}", "--workers", "2", "--no-progress",
                                *extra], check=True, capture_output=True, cwd=ROOT)
                wall = time.perf_counter() - start
                what = "without figures" if extra else "with figures"
                print(f"{'whole paper experiment, 2 workers, ' + what:55s} {wall:9.2f} s"
                      "   (goal < 10 s; 3 x 50 trials, exact + 6 PGA variants)")


if __name__ == "__main__":
    main()

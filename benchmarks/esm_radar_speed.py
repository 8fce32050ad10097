"""Speed of the esm_radar experiment (paper 001); prints numbers, asserts nothing.

1. ``run_batch`` alone, in this process: the 500-trial Table 3 point (every algorithm)
   for each radar-factor model, with the runner's seeding and batch size.
2. The real runner (``trackfuse.runner.Runner``, the CLI's engine) on
   ``configs/esm_radar_snake_cross.yaml`` (2 models x 500 trials, with tables and figures) and
   ``configs/esm_radar_separation.yaml`` (9 separations x 2 models x 500 trials), on 2 workers,
   into a temporary folder so nothing is resumed.

Usage: ``python benchmarks/esm_radar_speed.py [--workers 2]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from trackfuse.config import load
from trackfuse.experiments.esm_radar import EXPERIMENT
from trackfuse.experiments.esm_radar.model import ALGORITHMS
from trackfuse.runner import Runner
from trackfuse.seeding import trial_streams

ROOT = Path(__file__).resolve().parents[1]


def time_run_batch(model: str, trials: int = 500, repeats: int = 3) -> float:
    params = dict(EXPERIMENT.defaults(), algorithms=list(ALGORITHMS))
    params["radar.factor_model"] = model
    size = EXPERIMENT.batch_size
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for first in range(0, trials, size):
            EXPERIMENT.run_trials(params, [trial_streams(1, 0, t) for t in
                                           range(first, min(first + size, trials))])
        best = min(best, time.perf_counter() - t0)
    return best


def time_runner(config: str, workers: int, plots: bool) -> tuple[float, int]:
    cfg = load(ROOT / "configs" / config)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        outcome = Runner(cfg, Path(out), workers=workers, plots=plots, progress=False).run()
        return time.perf_counter() - t0, outcome.total_trials


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    for model in ("table", "derived"):
        s = time_run_batch(model)
        print(f"run_batch, 500 trials x {len(ALGORITHMS)} algorithms, {model:7s}: {s:6.3f} s "
              f"({1e3 * s / 500:.2f} ms/trial)")
    for config, plots in (("esm_radar_snake_cross.yaml", True),
                          ("esm_radar_snake_cross.yaml", False),
                          ("esm_radar_separation.yaml", True),
                          ("esm_radar_separation.yaml", False)):
        s, n = time_runner(config, args.workers, plots)
        print(f"runner, {config:28s} {n:5d} trials, {args.workers} workers, "
              f"{'with' if plots else 'no  '} figures/tables: {s:6.2f} s")


if __name__ == "__main__":
    main()

"""The range bias the first update adds (docs/papers/twin_sensor.md, W000-3): the mean change
of the range error made by the scan-1 update of the MGEKF + PDA, against the first-order
formula ``2 sigma_r^2 sigma_c^2 / (r (sigma_c^2 + r^2 sigma^2 / S))``.

Usage::

    python examples/first_update_shift.py --trials 4000 --seed 77
    python examples/first_update_shift.py --trials 20000 --seed 77 78 79 --only paper
    python examples/first_update_shift.py --trials 20000 --seed 77 --only paper \\
        --set gate.pg=0.999999
    trackfuse run configs/twin_sensor_rmse_vs_bound.yaml
    python examples/first_update_shift.py --run results/twin_sensor_rmse_vs_bound/seed20051006-<id>

For each setting (the experiment's defaults without clutter, which are the paper's scenario,
then one factor changed at a time; ``--only`` picks settings by name, ``--set KEY=VALUE``
changes every setting as ``trackfuse run --set`` does) and each seed, it simulates trials
``0 .. trials-1`` at sweep point 0 with the experiment's own code, cut to their first scan
(fast; the scan-1 noise of a one-scan trial is not that of the same trial run in full), takes
each trial's prior range error (the initial estimate's distance from sensor 1 minus the true
one) and its range error after the scan-1 update of ``mspda_parallel/mgekf``, and prints the
mean shift with its standard error and 95 % t interval over the trials of all seeds given. As
``tests/test_twin_sensor.py::test_first_update_adds_the_predicted_range_bias`` does with 2000
trials. Takes about 10 s per 20,000 trials.

With ``--run RUN_DIR`` (a finished ``twin_sensor`` run with a point without clutter) it pairs
the run's own numbers instead: each trial's scan-1 range error of ``mspda_parallel/mgekf``
from its ``trials.csv`` with its prior range error, recomputed from the trial's streams (the
initial estimate comes from the stream common to every point). It first checks that the
experiment's code, run in full, gives the run's scan-1 errors for the first trials, then
prints the paired shift (scan-1 error minus prior error, same trials) with its 95 % t
interval beside the unpaired mean of each: the scan-1 mean alone carries the prior's
sampling spread. On ``twin_sensor_rmse_vs_bound.yaml`` (seed 20051006, 1000 trials) this is
the number docs/results.md and docs/papers/twin_sensor.md quote.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import yaml

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import build_scenario, simulate
from trackfuse.rundata import load
from trackfuse.seeding import trial_streams
from trackfuse.stats import t_interval

SETTINGS = {
    "paper": {},
    "cue_2km": {"init.sigma_range": 2000.0},
    "cue_40km": {"init.sigma_range": 40000.0},
    "one_sensor": {"sensors.count": 1},
    "half_cross_range": {"init.sigma_angle": 0.01 / np.sqrt(2) / 2},
    "platform_still": {"platform.speed": 0.0, "platform.climb": 0.0},
}


def formula(p: dict) -> float:
    """The first-order shift (m), summed over the two cross-range axes."""
    start = np.asarray(p["target.position"], dtype=float)
    r = float(np.linalg.norm(start - np.asarray(p["platform.start"], dtype=float)))
    sigma_r, sigma_c = p["init.sigma_range"], r * p["init.sigma_angle"]
    return 2 * sigma_r**2 * sigma_c**2 / (
        r * (sigma_c**2 + r**2 * p["sensors.sigma_az"]**2 / p["sensors.count"]))


ALGORITHM = "mspda_parallel/mgekf"


def prior_errors(p: dict, seed: int, point: int, trials: range) -> np.ndarray:
    """Each trial's prior range error (m): its initial estimate's distance from sensor 1 at
    scan 1 minus the true one."""
    sc = build_scenario(p)
    x0 = simulate(sc, [trial_streams(seed, point, t) for t in trials]).x0
    r_true = np.linalg.norm(sc.x_start[:3] - sc.platform[1])
    return np.linalg.norm(x0[:, :3] - sc.platform[1], axis=1) - r_true


def scan1_errors(p: dict, seed: int, point: int, trials: range) -> np.ndarray:
    """Each trial's range error (m) after the scan-1 update of :data:`ALGORITHM`."""
    p = dict(p, algorithms=[ALGORITHM])
    rows = EXPERIMENT.run_batch(p, [trial_streams(seed, point, t) for t in trials])
    return np.array([next(r for r in trial if r["scan"] == 1)["range_err_m"] for trial in rows])


def shifts(p: dict, seed: int, trials: int) -> np.ndarray:
    """Range change (m) made by the scan-1 update in each trial, cut to its first scan."""
    p = dict(p, **{"scan.count": 1})
    return scan1_errors(p, seed, 0, range(trials)) - prior_errors(p, seed, 0, range(trials))


def interval_text(x: np.ndarray) -> str:
    """``mean [low, high]`` (m) with the 95 % t interval of the mean of ``x``."""
    lo, hi = t_interval(x.mean(), x.std(ddof=1), len(x))
    return f"{x.mean():.0f} [{float(lo):.0f}, {float(hi):.0f}]"


def run_shift(folder: Path) -> str:
    """The paired first-update shift of a finished run (module docstring, ``--run``)."""
    run = load(folder)
    point = next(i for i, p in enumerate(run.points) if float(p["clutter.mean"]) == 0.0)
    p = run.point_params(point)
    rows = run.trials.query("point == @point and scan == 1 and algorithm == @ALGORITHM")
    rows = rows.sort_values("trial")
    trials = range(int(rows["trial"].min()), int(rows["trial"].max()) + 1)
    if len(rows) != len(trials):
        sys.exit(f"{folder}: trials missing at point {point}")
    scan1 = rows["range_err_m"].to_numpy()
    seed = int(run.config["seed"])
    check = scan1_errors(p, seed, point, trials[:20])
    if not np.array_equal(check, scan1[:20]):
        sys.exit(f"{folder}: the experiment's code does not give this run's scan-1 errors")
    prior = prior_errors(p, seed, point, trials)
    return (f"{folder.name}: seed {seed}, point {point} (clutter 0), {len(trials)} trials, "
            f"{ALGORITHM}: shift {interval_text(scan1 - prior)} m (paired, 95 %); scan-1 "
            f"error {interval_text(scan1)} m; prior error {interval_text(prior)} m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=4000)
    parser.add_argument("--seed", type=int, nargs="+", default=[77])
    parser.add_argument("--only", nargs="+", choices=list(SETTINGS), default=list(SETTINGS))
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--run", type=Path, metavar="RUN_DIR")
    args = parser.parse_args()
    if args.run is not None:
        print(run_shift(args.run))
        return
    common = {"clutter.mean": 0.0}
    for item in args.set:
        key, _, value = item.partition("=")
        common[key] = yaml.safe_load(value)
    print(f"{args.trials} trials per seed, seeds {' '.join(map(str, args.seed))}, "
          f"{' '.join(f'{k}={v}' for k, v in common.items())}")
    for name in args.only:
        p = EXPERIMENT.defaults()
        p.update(common)
        p.update(SETTINGS[name])
        d = np.concatenate([shifts(p, seed, args.trials) for seed in args.seed])
        mean, sd = d.mean(), d.std(ddof=1)
        lo, hi = t_interval(mean, sd, len(d))
        print(f"{name}: {mean:.0f} +- {sd / np.sqrt(len(d)):.0f} m (95 % [{float(lo):.0f}, "
              f"{float(hi):.0f}], {len(d)} trials); formula {formula(p):.0f} m")


if __name__ == "__main__":
    main()

"""The range bias the first update adds (docs/papers/twin_sensor.md, W000-3): the mean change
of the range error made by the scan-1 update of the MGEKF + PDA, against the first-order
formula ``2 sigma_r^2 sigma_c^2 / (r (sigma_c^2 + r^2 sigma^2 / S))``.

Usage::

    python examples/first_update_shift.py --trials 4000 --seed 77
    python examples/first_update_shift.py --trials 20000 --seed 77 78 79 --only paper
    python examples/first_update_shift.py --trials 20000 --seed 77 --only paper \\
        --set gate.pg=0.999999

For each setting (the experiment's defaults without clutter, which are the paper's scenario,
then one factor changed at a time; ``--only`` picks settings by name, ``--set KEY=VALUE``
changes every setting as ``trackfuse run --set`` does) and each seed, it simulates trials
``0 .. trials-1`` at sweep point 0 with the experiment's own code (the streams ``trackfuse
run`` gives those trials), takes each trial's prior range error (the initial estimate's
distance from sensor 1 minus the true one) and its range error after the scan-1 update of
``mspda_parallel/mgekf``, and prints the mean shift with its standard error and 95 % t
interval over the trials of all seeds given. As ``tests/test_twin_sensor.py::
test_first_update_adds_the_predicted_range_bias`` does with 2000 trials. Takes about 10 s per
20,000 trials.
"""

from __future__ import annotations

import argparse

import numpy as np
import yaml

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import build_scenario, simulate
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


def shifts(p: dict, seed: int, trials: int) -> np.ndarray:
    """Range change (m) made by the scan-1 update in each trial."""
    p = dict(p, **{"scan.count": 1, "algorithms": ["mspda_parallel/mgekf"]})

    def streams():  # fresh generators: the simulation below and the filter draw alike
        return [trial_streams(seed, 0, t) for t in range(trials)]

    sc = build_scenario(p)
    x0 = np.stack([simulate(sc, s).x0 for s in streams()])
    r_true = np.linalg.norm(sc.x_start[:3] - sc.platform[1])
    prior_err = np.linalg.norm(x0[:, :3] - sc.platform[1], axis=1) - r_true
    scan1_err = np.array([rows[0]["range_err_m"] for rows in EXPERIMENT.run_batch(p, streams())])
    return scan1_err - prior_err


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=4000)
    parser.add_argument("--seed", type=int, nargs="+", default=[77])
    parser.add_argument("--only", nargs="+", choices=list(SETTINGS), default=list(SETTINGS))
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
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

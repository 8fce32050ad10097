"""Coverage of the 95 % interval a sequential trial count reports, by simulation.

A sequential rule (``trials: {min, max, until: {metric, half_width}}``,
:mod:`trackfuse.sequential`) looks at the data at fixed counts and stops when the
interval is narrow enough, so the interval reported is not a fixed-n interval. This script
applies the same rule (the same looks, :meth:`~trackfuse.sequential.SequentialRule.looks`,
and the same intervals as ``summary.csv``) to simulated trials whose true value is known and
counts how often the final interval covers it:

* a 0/1 metric (Bernoulli(p) trials) with the Wilson interval, at several p;
* a mean (exponential trials, skewed) with the Student-t interval.

Usage: ``python examples/sequential_coverage.py [--reps 20000] [--seed 1]``
(about a minute). docs/runner.md (Sequential trial counts) quotes its output.
"""

from __future__ import annotations

import argparse

import numpy as np

from trackfuse.sequential import SequentialRule
from trackfuse.stats import t_interval, wilson_interval

#: The rule of the issue that asked for sequential counts, with the summary's batch of 25.
RULE = SequentialRule(min=100, max=20000, metric="correct", half_width=0.01)
BATCH = 25


def binary_coverage(rule: SequentialRule, p: float, reps: int, rng: np.random.Generator,
                    batch_size: int = BATCH) -> tuple[float, float]:
    """``(coverage, mean trials)`` of the final Wilson interval of ``reps`` sequential runs
    of Bernoulli(``p``) trials."""
    looks = np.array(rule.looks(batch_size))
    steps = np.diff(looks, prepend=0)
    successes = np.cumsum(rng.binomial(steps, p, size=(reps, len(looks))), axis=1)
    low, high = wilson_interval(successes, looks[None, :].repeat(reps, axis=0))
    return _final(rule, looks, low, high, p)


def mean_coverage(rule: SequentialRule, scale: float, reps: int, rng: np.random.Generator,
                  batch_size: int = BATCH) -> tuple[float, float]:
    """``(coverage, mean trials)`` of the final Student-t interval of ``reps`` sequential
    runs of exponential trials of mean ``scale`` (sums of squares kept per look)."""
    looks = np.array(rule.looks(batch_size))
    x = rng.exponential(scale, size=(reps, looks[-1]))
    total = np.cumsum(x, axis=1)[:, looks - 1]
    squares = np.cumsum(x**2, axis=1)[:, looks - 1]
    mean = total / looks
    std = np.sqrt(np.maximum(squares - looks * mean**2, 0.0) / (looks - 1))
    low, high = t_interval(mean, std, looks[None, :].repeat(reps, axis=0))
    return _final(rule, looks, low, high, scale)


def _final(rule: SequentialRule, looks: np.ndarray, low: np.ndarray, high: np.ndarray,
           truth: float) -> tuple[float, float]:
    """Coverage and mean count of the interval at each run's stopping look: the first look
    whose half-width meets the rule, else the last (``max``)."""
    met = (high - low) / 2 <= rule.half_width
    met[:, -1] = True
    stop = met.argmax(axis=1)
    rows = np.arange(len(stop))
    covered = (low[rows, stop] <= truth) & (truth <= high[rows, stop])
    return float(covered.mean()), float(looks[stop].mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"rule: {RULE.words()}; looks {RULE.looks(BATCH)}; {args.reps} runs each; "
          f"Monte Carlo s.e. about {np.sqrt(0.95 * 0.05 / args.reps):.4f}")
    for p in (0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 0.95, 0.98):
        coverage, trials = binary_coverage(RULE, p, args.reps, rng)
        print(f"0/1 metric, p = {p:4.2f}, Wilson: coverage {coverage:.4f}, mean trials "
              f"{trials:7.0f}")
    mean_rule = SequentialRule(min=20, max=5000, metric="error", half_width=0.05)
    for scale in (0.1, 0.5, 1.0, 2.0):
        coverage, trials = mean_coverage(mean_rule, scale, min(args.reps, 2000), rng)
        print(f"mean of exponential({scale:g}), t, {mean_rule.words()}: coverage "
              f"{coverage:.4f}, mean trials {trials:7.0f}")


if __name__ == "__main__":
    main()

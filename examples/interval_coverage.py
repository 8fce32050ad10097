"""What the report's 95 % means, measured on a large population of ``twin_sensor_orbit``
runs of nearest neighbour (docs/statistics.md; trackfuse/stats.py).

Usage, on a run of the shipped orbit config with more trials and the two nearest-neighbour
algorithms only (removing algorithms changes no other algorithm's numbers, so trials 0-49
are those of the shipped 50-trial run)::

    trackfuse run configs/twin_sensor_orbit.yaml --set trials=4000 \\
        --set 'algorithms=[nn/mgekf,nn/ekf]' --workers 2 --no-plots --out /tmp/pop
    python examples/interval_coverage.py /tmp/pop/twin_sensor_orbit/seed20051001-<id>

The run takes about 50 s on two cores and writes a 320 MB ``trials.csv``; the script about
35 s. It takes the run's trials as the population and prints three measurements:

1. **RMSE intervals.** The final-scan squared range errors of each algorithm at clutter 0
   and 9 are the population; its RMSE is the true value. ``--replications`` samples of 50
   and of 8 runs, each drawn without replacement, get the report's interval
   (:func:`trackfuse.stats.rmse_intervals`, 2000 resamples, seed 0), the same interval
   without Hesterberg's expansion, and the percentile bootstrap the report used before.
   Printed: the fraction of samples whose interval covers the true RMSE, with its Monte
   Carlo standard error ``sqrt(c (1 - c) / replications)``, and the median ratio of the
   report's interval width to the percentile interval's.
2. **Losses across clutter levels.** A run's loss indicators at the levels 0-9 (and 0-15)
   are correlated: the levels share the run's truth and noise. The *design effect* of the
   pooled loss count is ``Var(K) / sum_l p_l (1 - p_l)``, where ``K`` is the number of
   levels at which one run lost its track and ``p_l`` the loss rate at level ``l``: the
   variance of the count over its variance if the (run, level) outcomes were independent.
   Printed with a 95 % percentile bootstrap interval over runs (2000 resamples), for both
   loss rules at the last scan. Then the coverage, over samples of 50 runs, of two Wilson
   intervals: the pooled one (losses in 50 x 10 (run, level) pairs, for the population's
   mean rate over the levels 0-9) and the one the report uses (runs that lost a track at
   any level 0-9, for the population's fraction of such runs).
3. **Null comparisons.** Consecutive disjoint 50-trial blocks of the run (trials 0-49
   against 50-99, 100-149 against 150-199, ...) are compared as two runs with different
   seeds are (:func:`trackfuse.compare.compare_trials`, unpaired, regression gate
   Bonferroni-adjusted over every gated cell, family-wise level 0.05). Both blocks come
   from the same code, so any cell called a regression or an improvement is a false
   alarm. Printed: how many comparisons flag any cell, with a 95 % Wilson interval.

On a run of fewer than 100 trials only the design effect is printed.
"""

from __future__ import annotations

import argparse

import numpy as np

import trackfuse
from trackfuse.compare import compare_trials
from trackfuse.stats import (
    _bootstrap_t,
    _resample_counts,
    percentile_mean_intervals,
    rmse_intervals,
    wilson_interval,
)

ALGORITHMS = ("nn/mgekf", "nn/ekf")
RESAMPLES = 2000  # as the report (trackfuse/experiments/twin_sensor/report.py)
BLOCK = 50


def percentile_rmse_intervals(squared: np.ndarray) -> np.ndarray:
    """The percentile bootstrap the report used before, ``(R, n) -> (R, 2)``."""
    return np.sqrt(percentile_mean_intervals(squared, RESAMPLES, 0))


def unexpanded_rmse_intervals(squared: np.ndarray) -> np.ndarray:
    """:func:`rmse_intervals` with its quantiles at 0.025 and 0.975 (no expansion)."""
    n = squared.shape[1]
    t = _bootstrap_t(squared, _resample_counts(n, RESAMPLES, 0))
    q_lo = np.quantile(t, 0.025, axis=1, method="lower")
    q_hi = np.quantile(t, 0.975, axis=1, method="higher")
    mean, se = squared.mean(axis=1), squared.std(axis=1, ddof=1) / np.sqrt(n)
    return np.sqrt(np.clip(np.column_stack([mean - q_hi * se, mean - q_lo * se]), 0, None))


def coverage_text(intervals: np.ndarray, truth: float) -> str:
    c = float(np.mean((intervals[:, 0] <= truth) & (truth <= intervals[:, 1])))
    return f"{c:.3f} (s.e. {np.sqrt(c * (1 - c) / len(intervals)):.3f})"


def rmse_coverage(final, replications: int, rng: np.random.Generator) -> None:
    print(f"1. RMSE interval coverage, final scan, {replications} samples per cell "
          "(nominal 0.95):")
    for (level, algorithm), cell in final[final["clutter.mean"].isin([0, 9])].groupby(
            ["clutter.mean", "algorithm"]):
        population = cell["range_sq_err_m2"].to_numpy()
        truth = np.sqrt(population.mean())
        for n in (50, 8):
            idx = np.stack([rng.choice(len(population), n, replace=False)
                            for _ in range(replications)])
            sq = population[idx]
            report = rmse_intervals(list(sq))
            percentile = percentile_rmse_intervals(sq)
            ratio = np.median((report[:, 1] - report[:, 0])
                              / (percentile[:, 1] - percentile[:, 0]))
            print(f"  {algorithm}, clutter {level:g}, n = {n}: report (bootstrap-t) "
                  f"{coverage_text(report, truth)}, without expansion "
                  f"{coverage_text(unexpanded_rmse_intervals(sq), truth)}, percentile "
                  f"{coverage_text(percentile, truth)}; width ratio {ratio:.2f}")


def design_effect(losses: np.ndarray) -> float:
    """``Var(K) / sum_l p_l (1 - p_l)`` of a (runs, levels) 0/1 array; NaN with no loss."""
    p = losses.mean(axis=0)
    independent = float((p * (1 - p)).sum())
    return float(losses.sum(axis=1).var()) / independent if independent > 0 else np.nan


def loss_matrix(final, algorithm: str, rule: str, top: int) -> np.ndarray:
    rows = final[(final["algorithm"] == algorithm) & (final["clutter.mean"] <= top)]
    return rows.pivot(index="trial", columns="clutter.mean", values=rule).to_numpy()


def losses_across_levels(final, replications: int, rng: np.random.Generator) -> None:
    print("2. Design effect of the pooled loss count (95 % bootstrap interval over runs):")
    boot = rng.integers(0, final["trial"].nunique(), (RESAMPLES, final["trial"].nunique()))
    for algorithm in ALGORITHMS:
        for rule in ("lost_gate", "lost_angle"):
            texts = []
            for top in (9, 15):
                x = loss_matrix(final, algorithm, rule, top)
                d = [design_effect(x[i]) for i in boot]
                lo, hi = np.nanquantile(d, [0.025, 0.975])
                texts.append(f"levels 0-{top} {design_effect(x):.2f} [{lo:.2f}, {hi:.2f}]")
            print(f"  {algorithm}, {rule}: " + "; ".join(texts))
    runs = final["trial"].nunique()
    if runs < 2 * BLOCK:
        return
    print(f"   Coverage over {replications} samples of {BLOCK} runs, levels 0-9 "
          "(nominal 0.95):")
    for algorithm in ALGORITHMS:
        for rule in ("lost_gate", "lost_angle"):
            x = loss_matrix(final, algorithm, rule, 9)
            pooled_truth, any_truth = x.mean(), x.max(axis=1).mean()
            idx = np.stack([rng.choice(runs, BLOCK, replace=False)
                            for _ in range(replications)])
            pooled = np.column_stack(wilson_interval(x[idx].sum(axis=(1, 2)), x[0].size * BLOCK))
            any_level = np.column_stack(wilson_interval(x[idx].max(axis=2).sum(axis=1), BLOCK))
            print(f"  {algorithm}, {rule}: pooled rate {pooled_truth:.4f}, Wilson over "
                  f"{x[0].size * BLOCK} pairs covers {coverage_text(pooled, pooled_truth)}; "
                  f"any-level fraction {any_truth:.4f}, Wilson over {BLOCK} runs covers "
                  f"{coverage_text(any_level, any_truth)}")


def null_comparisons(run) -> None:
    trials = run.trials
    pairs = trials["trial"].nunique() // (2 * BLOCK)
    experiment = run.experiment
    keys = [*run.sweep, *experiment.row_keys]
    blocks = dict(list(trials.groupby(trials["trial"] // BLOCK)))
    flagged, gated = 0, set()
    for k in range(pairs):
        base, new = blocks[2 * k].copy(), blocks[2 * k + 1].copy()
        base["trial"] -= 2 * k * BLOCK
        new["trial"] -= (2 * k + 1) * BLOCK
        result = compare_trials(base, new, keys, binary=experiment.binary_metrics,
                                better=experiment.directions, paired=False,
                                skip=experiment.categorical_metrics)
        gated.add(result.gated)
        flagged += bool(result.cells["verdict"].isin(["regression", "improvement"]).any())
    lo, hi = (100 * float(v) for v in wilson_interval(flagged, pairs))
    print(f"3. Null comparisons of disjoint {BLOCK}-trial blocks: {flagged} of {pairs} flag a "
          f"regression or an improvement in any of {', '.join(map(str, sorted(gated)))} gated "
          f"cells ({100 * flagged / pairs:.1f} %, 95 % Wilson [{lo:.1f}, {hi:.1f}] %)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a twin_sensor_orbit run folder with nn/mgekf and nn/ekf")
    parser.add_argument("--replications", type=int, default=1000)
    args = parser.parse_args()
    run = trackfuse.load(args.run)
    trials = run.trials
    final = trials[(trials["scan"] == trials["scan"].max())
                   & trials["algorithm"].isin(ALGORITHMS)]
    if sorted(final["algorithm"].unique()) != sorted(ALGORITHMS) or \
            list(run.sweep) != ["clutter.mean"]:
        raise SystemExit(f"{args.run}: not a clutter sweep of {' and '.join(ALGORITHMS)}")
    runs = final["trial"].nunique()
    print(f"population: {runs} runs per level, {run.config['experiment']} seed "
          f"{run.config['seed']}, levels {final['clutter.mean'].min():g}-"
          f"{final['clutter.mean'].max():g}")
    rng = np.random.default_rng(0)
    if runs >= 2 * BLOCK:
        rmse_coverage(final, args.replications, rng)
    losses_across_levels(final, args.replications, rng)
    if runs >= 2 * BLOCK:
        null_comparisons(run)


if __name__ == "__main__":
    main()

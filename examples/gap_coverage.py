"""What the passive_assoc report's 95 % interval of the mean gap ``J* - J`` means, measured on
a large population of ``passive_association`` runs (docs/papers/passive_assoc.md, "Metrics
and intervals"; :func:`trackfuse.experiments.passive_assoc.report.gap_interval`).

Usage, on a run of the shipped config with more trials (every trial's scene, noise and PGA
streams come from its own seed, so trials 0-49 are those of the shipped 50-trial run)::

    trackfuse run configs/passive_association.yaml --set trials=2000 --workers 2 \\
        --no-plots --out /tmp/gapcov
    python examples/gap_coverage.py /tmp/gapcov/passive_association/seed20080401-<id>

The run takes about 25 s on two cores and writes a 26 MB ``trials.csv``; the script about
35 s with 1000 replications. It takes the run's trials as the population: per point and
PGA variant, the per-run gaps at the variant's last checkpoint (or at ``--ops``), whose
mean is the true mean gap. ``--replications`` samples of ``--runs`` runs (default 50, the
shipped config's trials), each drawn without replacement, get the report's interval
(:func:`gap_interval`, called once per sample as the report calls it once per table cell:
expanded bootstrap-t, 4000 resamples, generator 2008, lower end clipped at 0) and the
percentile bootstrap the report used before (the 0.025 and 0.975 quantiles of the means of
the same 4000 resamples). Printed per point and variant: the fraction of the population's
runs at ``J*``, the true mean gap, the fraction of samples whose interval covers it with
its Monte Carlo standard error ``sqrt(c (1 - c) / replications)``, and how many samples
hold at most one run off ``J*`` and how many get the report's degenerate intervals:
``[0, 0]`` (every run of the sample at ``J*``) and an infinite upper end (too few runs off
``J*`` to bound the mean), with the fewest and the most runs off ``J*`` among the latter.
"""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd

import trackfuse
from trackfuse.experiments.passive_assoc.report import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    gap_interval,
)
from trackfuse.stats import percentile_mean_intervals

RUNS = 50  # trials of configs/passive_association.yaml


def percentile_gap_intervals(samples: np.ndarray) -> np.ndarray:
    """The percentile bootstrap the report used before (commit 316f7b0 replaced it),
    ``(R, n) -> (R, 2)``: the same resamples (generator :data:`BOOTSTRAP_SEED`) for every
    sample, as one call per sample drew them."""
    return percentile_mean_intervals(samples, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED)


def report_gap_intervals(samples: np.ndarray) -> np.ndarray:
    """:func:`gap_interval` of each row of ``samples``, ``(R, n) -> (R, 2)``."""
    return np.array([gap_interval(s) for s in samples])


def covered(intervals: np.ndarray, truth: float) -> np.ndarray:
    return (intervals[:, 0] <= truth) & (truth <= intervals[:, 1])


def coverage_text(hits: np.ndarray) -> str:
    c = float(hits.mean())
    return f"{c:.3f} (s.e. {np.sqrt(c * (1 - c) / len(hits)):.3f})"


def measure(population: np.ndarray, runs: int, replications: int,
            rng: np.random.Generator) -> dict[str, np.ndarray | float]:
    """Coverage of the population mean of ``population`` over ``replications`` samples of
    ``runs`` values drawn without replacement: ``truth``, the per-sample 0/1 ``report`` and
    ``percentile`` hits, the report's intervals ``report_intervals`` and the number of
    values above 0 (runs off ``J*``) in each sample, ``off``."""
    truth = float(population.mean())
    samples = np.stack([population[rng.choice(len(population), runs, replace=False)]
                        for _ in range(replications)])
    report = report_gap_intervals(samples)
    return {"truth": truth, "report": covered(report, truth),
            "percentile": covered(percentile_gap_intervals(samples), truth),
            "report_intervals": report, "off": (samples > 0).sum(axis=1)}


def final_rows(trials: pd.DataFrame, ops: int | None) -> pd.DataFrame:
    """The PGA rows at each variant's last checkpoint, or at ``ops``."""
    pga = trials[trials["algorithm"] != "exact"]
    last = pga.groupby("algorithm")["ops"].transform("max") if ops is None else ops
    return pga[pga["ops"] == last]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a passive_assoc run folder (trials.csv)")
    parser.add_argument("--runs", type=int, default=RUNS, help="runs per sample")
    parser.add_argument("--replications", type=int, default=1000)
    parser.add_argument("--ops", type=int, help="checkpoint (default: each variant's last)")
    args = parser.parse_args()
    run = trackfuse.load(args.run)
    if run.config["experiment"] != "passive_assoc":
        raise SystemExit(f"{args.run}: not a passive_assoc run")
    rows = final_rows(run.trials, args.ops)
    keys = [k for k in run.sweep if k != "algorithms"]
    population = rows.groupby(["point", "algorithm"])["trial"].nunique()
    if rows.empty or population.min() <= args.runs:
        raise SystemExit(f"{args.run}: needs more than {args.runs} runs per point and variant")
    print(f"population: {population.min()}-{population.max()} runs per point, "
          f"{run.config['experiment']} seed {run.config['seed']}; {args.replications} "
          f"samples of {args.runs} runs (nominal 0.95)")
    rng = np.random.default_rng(0)
    for (_, algorithm), cell in rows.groupby(["point", "algorithm"], sort=True):
        gaps = cell.sort_values("trial")["gap"].to_numpy(float)
        m = measure(gaps, args.runs, args.replications, rng)
        iv, off = m["report_intervals"], m["off"]
        infinite = np.isinf(iv[:, 1])
        k = f" ({off[infinite].min()}-{off[infinite].max()} runs off J*)" if infinite.any() else ""
        where = ", ".join(f"{k} = {cell[k].iloc[0]}" for k in keys)
        print(f"  {where}, {algorithm} at ops {cell['ops'].iloc[0]}: at J* "
              f"{100 * cell['at_opt'].mean():.1f} % of runs, mean gap {m['truth']:.6g}; "
              f"report (bootstrap-t) {coverage_text(m['report'])}, percentile "
              f"{coverage_text(m['percentile'])}; samples with at most one run off J*: "
              f"{100 * np.mean(off <= 1):.1f} %, report [0, 0]: {100 * np.mean(iv[:, 1] == 0):.1f} "
              f"%, upper end infinite: {100 * infinite.mean():.1f} %{k}")


if __name__ == "__main__":
    main()

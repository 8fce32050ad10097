"""Two numbers of docs/papers/esm_radar.md (W001-8) that no column of a run holds.

Usage, on a finished ``esm_radar`` run (every point of a run shares its sensor data)::

    trackfuse run configs/esm_radar_snake_cross.yaml --no-plots
    python examples/esm_radar_spread.py results/esm_radar_snake_cross/seed20170101-<id>

The docs quote the correlation of the Table 3 run (``esm_radar_snake_cross.yaml``) and the
changed decisions of the ``esm_radar_baseline_spread.yaml`` run.

The script re-simulates point 0 of the run from its seed and resolved config with the
experiment's own code, checks that the TDOA-DF range errors equal the run's
``esm_range_error_per_scan_m`` (so they are the run's data), and prints

* the correlation between the per-sample 1-sigma of the TDOA-DF range and its error over
  every (trial, scan) sample, with a 95 % percentile interval from 2000 resamples of trials;
* how many trials' decisions of ``traditional`` change when, in the ``per_sample`` spread,
  the radar range spread alone is made static (its ``nominal`` value), and when, in the
  ``nominal`` spread, it alone is recomputed per sample.
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

import trackfuse
from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    TRUE_TRACK,
    decode_series,
    differences,
    esm_errors,
    evaluate,
    simulate,
)
from trackfuse.seeding import batch_streams


def main(folder: str) -> None:
    run = trackfuse.load(folder)
    params, n = run.point_params(0), run.config["trials"]
    sim = simulate(params, batch_streams(run.config["seed"], 0, range(n)))
    err = esm_errors(sim)[0]                                    # (N, K) m
    rows = run.trials[(run.trials["point"] == 0) & run.trials["alpha_per_scan"].notna()]
    stored = decode_series(rows.sort_values("trial")["esm_range_error_per_scan_m"])
    assert np.array_equal(np.round(err), stored, equal_nan=True), "not this run's data"

    sd = np.sqrt(sim.P_esm[..., 0, 0])                          # (N, K) m
    ok = np.isfinite(sd).all(axis=1)
    sd, err = sd[ok], err[ok]
    r = np.corrcoef(sd.ravel(), err.ravel())[0, 1]
    rng = np.random.default_rng(0)
    boot = [np.corrcoef(sd[i].ravel(), err[i].ravel())[0, 1]
            for i in rng.integers(0, len(sd), (2000, len(sd)))]
    low, high = np.percentile(boot, [2.5, 97.5])
    print(f"correlation of the per-sample TDOA-DF range sd with its error: {r:.3f} "
          f"[{low:.3f}, {high:.3f}] over {sd.size} samples ({len(sd)} trials)")

    diff = differences(sim)
    esm_var = sim.P_esm[..., None, 0, 0]                        # (N, K, 1)
    radar_var = sim.P_radar[..., 0, 0]                          # (N, K, J) per sample
    esm_nominal, radar_nominal = sim.sd_nominal[:, 0] ** 2
    per_sample = diff.var                                       # (N, K, J, 5)
    nominal = np.broadcast_to(diff.var_nominal, per_sample.shape)

    def with_range(var: np.ndarray, range_var: np.ndarray) -> np.ndarray:
        out = var.copy()  # keeps the uninformative variance of a missing ESM range
        out[..., 0] = np.where(np.isfinite(range_var), range_var, var[..., 0])
        return out

    def chosen(var: np.ndarray) -> np.ndarray:  # traditional with the summed variances var
        case = dataclasses.replace(diff, var=var, ml_cache={})
        return evaluate(ALGORITHMS["traditional"], case, sim.alpha,
                        {**params, "baseline.spread": "per_sample"})["chosen"]

    for words, base, changed in (
            ("per_sample, radar range spread static", chosen(per_sample),
             chosen(with_range(per_sample, esm_var + radar_nominal))),
            ("nominal, radar range spread per sample", chosen(nominal),
             chosen(with_range(nominal, esm_nominal + radar_var)))):
        print(f"traditional, {words}: {np.count_nonzero(base != changed)} of {n} trials "
              f"change their decision (correct {np.mean(base == TRUE_TRACK):.3f} -> "
              f"{np.mean(changed == TRUE_TRACK):.3f})")


if __name__ == "__main__":
    main(*sys.argv[1:])

"""Why the manoeuvre index filters the range difference with an acceleration model: the mean
NIS of a constant-velocity filter on ``c dt`` in straight flight (docs/papers/esm_radar.md,
W001-4), a number no column of a run holds.

Usage, on a finished run of the weave config (its first point is straight flight with the
NIS index, its second the paper's 1 km weave)::

    trackfuse run configs/esm_radar_weave.yaml --no-plots
    python examples/esm_radar_cv_nis.py results/esm_radar_weave/seed20170105-<id>

The script re-simulates the two points from the run's seed and resolved config with the
experiment's own code, checks that the constant-acceleration index it computes equals the
run's ``alpha_per_scan`` (so these are the run's data), then runs a 1-D constant-velocity
Kalman filter (white acceleration variance ``q``, two-point start) on the same ``c dt`` and
prints, for several ``q``, the mean NIS over scans and trials with a 95 % t interval over
trials. A model that fits gives 1.
"""

from __future__ import annotations

import sys

import numpy as np
from scipy import stats

import trackfuse
from trackfuse.association.manoeuvre import cv_innovations
from trackfuse.experiments.esm_radar.model import (
    SCAN_SERIES,
    C,
    encode_series,
    manoeuvre_alpha,
    simulate,
)
from trackfuse.seeding import batch_streams

Q_VALUES = (0.01, 0.1, 1.0, 10.0)  # white acceleration variances, m^2/s^4


def main(folder: str) -> None:
    run = trackfuse.load(folder)
    n = run.config["trials"]
    for point in (0, 1):
        params = run.point_params(point)
        if params["alpha.index"] != "nis_tdoa":
            raise SystemExit(f"point {point} of {folder} is not an NIS-index point")
        sim = simulate(params, batch_streams(run.config["seed"], run.draw_points[point],
                                             range(n)))
        alpha = manoeuvre_alpha(params, sim.x_esm, sim.P_esm, "nis_tdoa")
        rows = run.trials[(run.trials["point"] == point) & run.trials["alpha_per_scan"].notna()]
        stored = rows.sort_values("trial").drop_duplicates("trial")["alpha_per_scan"]
        assert list(stored) == encode_series(alpha, SCAN_SERIES["alpha_per_scan"]), \
            "not this run's data"

        z, R = C * sim.x_esm[..., 3], C**2 * sim.P_esm[..., 3, 3]   # (N, K) m, m^2
        ok = np.isfinite(z).all(axis=1) & np.isfinite(R).all(axis=1)
        words = "straight flight" if params["snake.amplitude"] == 0 else (
            f"weave of {params['snake.amplitude']:g} m")
        print(f"point {point}, {words}, {ok.sum()} trials:")
        for q in Q_VALUES:
            nu, S = cv_innovations(z[ok], R[ok], params["esm.period"], q)
            per_trial = np.nanmean(nu**2 / S, axis=1)
            mean, se = per_trial.mean(), per_trial.std(ddof=1) / np.sqrt(len(per_trial))
            half = stats.t.ppf(0.975, len(per_trial) - 1) * se
            print(f"  q = {q:g} m^2/s^4: mean NIS of the CV filter on c dt {mean:.3f} "
                  f"[{mean - half:.3f}, {mean + half:.3f}]")


if __name__ == "__main__":
    main(*sys.argv[1:])

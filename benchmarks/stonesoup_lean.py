"""Stone Soup's EKF + PDA two ways, on the same returns: its usual objects and a lean loop.

The twin-sensor speed benchmark (``twin_sensor_speed.py``) compares our compiled filter with
Stone Soup run the usual way (``stonesoup_pda/ekf`` through :mod:`trackfuse.interop.stonesoup`:
a ``PDAHypothesiser`` per scan, which predicts the state and the measurement once per
detection). To keep the comparison honest this script also times the leanest loop Stone
Soup's public API allows for the same filter: per scan one ``predictor.predict`` and one
``updater.predict_measurement``; the gate, the likelihoods and the PDA weights of all
returns at once in numpy; ``updater.update`` only for the validated returns, each given the
shared measurement prediction; the mixture collapsed in floats
(:func:`trackfuse.interop.stonesoup.collapse`, as the usual path does). Both loops see the
same simulated returns of case (a) of ``twin_sensor_speed.py`` (one sensor, window clutter
of mean 10), and the script checks that they give the same estimates (with the analytic
measurement Jacobian; with Stone Soup's numerical one the two loops' estimates differ, a
difference not traced here, so only the timing is comparable there).

Usage: ``python benchmarks/stonesoup_lean.py [--trials 20] [--jacobian analytic]`` (needs the
``stonesoup`` extra)
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from twin_sensor_speed import params

from trackfuse.chi2 import chi2_quantile
from trackfuse.experiments.twin_sensor.model import build_scenario, simulate
from trackfuse.experiments.twin_sensor.stonesoup import _returns, run_stonesoup
from trackfuse.interop import stonesoup as ss
from trackfuse.seeding import trial_streams


def lean_track(sc, b, n: int, rs: np.random.RandomState,
               exact_jacobian: bool) -> tuple[np.ndarray, np.ndarray]:
    """Stone Soup EKF + PDA over trial ``n`` of ``b`` (one sensor): estimates ``(K, 6)`` and
    covariances ``(K, 6, 6)`` in our state order."""
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.updater.kalman import ExtendedKalmanUpdater

    predictor = ExtendedKalmanPredictor(ss.transition_model(sc.F, sc.Q_filter, rs))
    updater = ExtendedKalmanUpdater(None)
    gate = chi2_quantile(sc.P_G, 2)
    P_D = float(sc.P_D[0])
    state = ss.gaussian_prior(b.x0[n], sc.P0, sc.times[0])
    X, P = np.empty((sc.K, 6)), np.empty((sc.K, 6, 6))
    for k in range(1, sc.K + 1):
        model = ss.angle_model(sc.sensor_pos[k, 0], sc.R[0], rs, exact_jacobian)
        prediction = predictor.predict(state, timestamp=ss.timestamp(sc.times[k]))
        measured = updater.predict_measurement(prediction, model)
        centre, S = ss.measurement_gate(measured)
        z, lam = _returns(sc, b, n, k, 0, centre, S)
        nu = np.angle(np.exp(1j * (z - centre)))  # (M, 2), azimuth first, wrapped
        d2 = np.einsum("mi,ij,mj->m", nu, np.linalg.inv(S), nu)
        inside = d2 <= gate
        log_l = (-0.5 * d2[inside] - math.log(2 * math.pi) - 0.5 * math.log(np.linalg.det(S))
                 + math.log(P_D) - math.log(lam))
        weights = np.concatenate([[1.0 - P_D * sc.P_G], np.exp(log_l)])
        detections = ss.detections(z[inside], sc.times[k], model)
        states = [prediction] + [updater.update(SingleHypothesis(prediction, d, measured))
                                 for d in detections]
        mean, covar = ss.collapse(
            np.stack([np.asarray(s.state_vector, dtype=float)[:, 0] for s in states]),
            np.stack([np.asarray(s.covar, dtype=float) for s in states]),
            weights / weights.sum())
        state = ss.gaussian_prior(*ss.state_from_stonesoup(mean, covar), sc.times[k])
        X[k - 1], P[k - 1] = ss.state_from_stonesoup(mean, covar)
    return X, P


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--jacobian", choices=["analytic", "numerical"], default="analytic",
                        help="the EKF's measurement Jacobian (the experiment's default is "
                             "Stone Soup's numerical one; the estimates of the two loops are "
                             "compared with the analytic one, where they agree)")
    args = parser.parse_args()
    ss.require_stonesoup()
    p = {**params(1, "stonesoup_pda/ekf", "window"), "stonesoup.process_noise": "ours",
         "stonesoup.jacobian": args.jacobian}
    exact = args.jacobian == "analytic"
    sc = build_scenario(p)
    streams = [trial_streams(1, 0, t) for t in range(args.trials)]
    b = simulate(sc, list(streams))
    run_stonesoup("stonesoup_pda/ekf", p, sc, b, streams[:1])  # imports outside the timing
    start = time.perf_counter()
    usual = run_stonesoup("stonesoup_pda/ekf", p, sc, b, streams)
    usual_s = time.perf_counter() - start
    start = time.perf_counter()
    lean = [lean_track(sc, b, n, ss.algorithm_random_state(s.common, "lean"), exact)
            for n, s in enumerate(streams)]
    lean_s = time.perf_counter() - start
    X = np.stack([x for x, _ in lean])
    P = np.stack([c for _, c in lean])
    dx = np.nanmax(np.abs(X - usual.X) / (1.0 + np.abs(usual.X)))
    dp = np.nanmax(np.abs(P - usual.P) / (1.0 + np.abs(usual.P)))
    print(f"Stone Soup EKF + PDA ({p['stonesoup.jacobian']} Jacobian), 1 sensor, window "
          f"clutter mean 10, {args.trials} trials x {sc.K} scans, one process")
    print(f"  usual objects (PDAHypothesiser per scan): {args.trials / usual_s:8.1f} trials/s")
    print(f"  lean loop (shared predictions, numpy weights): {args.trials / lean_s:8.1f} "
          "trials/s")
    print(f"  same estimates: largest relative difference {dx:.1e} (mean), {dp:.1e} "
          "(covariance)")


if __name__ == "__main__":
    main()

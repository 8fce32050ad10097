"""A trackfuse plugin built from Stone Soup components: PDA against nearest neighbour.

A target moves at nearly constant velocity in the plane; a Stone Soup linear position
sensor reports it (probability ``pd``) among Poisson clutter uniform in a square about it.
Two Stone Soup trackers see the same detections in every trial: Kalman + PDA and Kalman +
nearest neighbour. trackfuse supplies the seeds, sweep, batches, resume, Monte Carlo
intervals and report. Run it from this folder (so that Python finds ``clutter_tracker``)::

    cd examples/stonesoup_plugin
    PYTHONPATH=. trackfuse run clutter.yaml --out /tmp/stonesoup-plugin

The recipe is ``docs/stonesoup.md`` (section "Your own experiment from Stone Soup parts").
"""

from __future__ import annotations

from datetime import datetime, timedelta

import numpy as np
from stonesoup.dataassociator.neighbour import NearestNeighbour
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.updater.kalman import KalmanUpdater

from trackfuse.experiments.base import Experiment, FigureSpec, Metric, Param
from trackfuse.interop.stonesoup import algorithm_random_state, gaussian_pda_update
from trackfuse.seeding import TrialStreams

EPOCH = datetime(2000, 1, 1)
ALGORITHMS = ("pda", "nn")


def simulate(params, streams: TrialStreams):
    """Truth ``(K+1, 4)`` and per-scan detections ``[(z (M, 2), is_target (M,))]``.

    Truth and target-measurement noise come from Stone Soup's own models, fed a
    ``RandomState`` derived from the common stream (the same at every sweep point); clutter
    comes from the point stream (it changes with the swept clutter rate).
    """
    rs = algorithm_random_state(streams.common, "truth")
    q, sigma, box = float(params["q"]), float(params["sigma"]), float(params["box"])
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q)] * 2)
    transition.random_state = rs
    sensor = LinearGaussian(4, (0, 2), np.eye(2) * sigma**2)
    sensor.random_state = rs
    dt = timedelta(seconds=1)
    truth = [GaussianState(StateVector([0.0, 10.0, 0.0, 5.0]), np.eye(4), timestamp=EPOCH)]
    scans = []
    for k in range(1, int(params["scans"]) + 1):
        x = transition.function(truth[-1], noise=True, time_interval=dt)
        truth.append(GaussianState(x, np.eye(4), timestamp=EPOCH + k * dt))
        z_target = np.asarray(sensor.function(truth[-1], noise=True), dtype=float).ravel()
        seen = rs.random_sample() < float(params["pd"])
        n = streams.point.poisson(float(params["clutter_mean"]))
        clutter = np.asarray(x, dtype=float)[[0, 2], 0] + streams.point.uniform(-box, box,
                                                                               (n, 2))
        z = np.vstack([z_target[None]] * seen + [clutter])
        scans.append((z, np.arange(len(z)) < seen))
    return np.hstack([np.asarray(t.state_vector, dtype=float) for t in truth]).T, scans, sensor


def track(algorithm: str, params, truth, scans, sensor) -> np.ndarray:
    """Position errors ``(K,)`` (m) of one Stone Soup tracker on the simulated scans."""
    predictor = KalmanPredictor(CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(float(params["q"]))] * 2))
    updater = KalmanUpdater(sensor)
    density = float(params["clutter_mean"]) / (2.0 * float(params["box"])) ** 2
    if algorithm == "pda":
        hypothesiser = PDAHypothesiser(predictor, updater, max(density, 1e-200),
                                       prob_detect=float(params["pd"]), prob_gate=0.99)
    else:
        associator = NearestNeighbour(DistanceHypothesiser(predictor, updater, Mahalanobis(),
                                                           missed_distance=3.0))
    state = GaussianState(StateVector(truth[0]), np.diag([100.0, 25.0, 100.0, 25.0]),
                          timestamp=EPOCH)
    errors = []
    for k, (z, _) in enumerate(scans, 1):
        when = EPOCH + timedelta(seconds=k)
        dets = [Detection(StateVector(zi), timestamp=when, measurement_model=sensor) for zi in z]
        if algorithm == "pda":
            state = gaussian_pda_update(hypothesiser.hypothesise(state, dets, when), updater)
        else:
            t = Track([state])
            hyp = associator.associate({t}, set(dets), when)[t]
            state = updater.update(hyp) if hyp else hyp.prediction
        est = np.asarray(state.state_vector, dtype=float).ravel()
        errors.append(np.hypot(est[0] - truth[k, 0], est[2] - truth[k, 2]))
    return np.asarray(errors)


def run_trial(params, streams: TrialStreams) -> list[dict]:
    """One trial: both trackers on the same detections; one row per tracker."""
    truth, scans, sensor = simulate(params, streams)
    rows = []
    for name in ALGORITHMS:
        err = track(name, params, truth, scans, sensor)
        rows.append({"algorithm": name, "final_pos_sq_err_m2": float(err[-1] ** 2),
                     "lost": int(err[-1] > float(params["lost_m"]))})
    return rows


EXPERIMENT = Experiment(
    name="stonesoup_clutter",
    title="Stone Soup Kalman + PDA against Kalman + nearest neighbour in clutter (plugin)",
    params=(
        Param("scans", 15, "scans per trial", "scans", kind=int, low=1, high=1000),
        Param("q", 0.5, "acceleration noise of truth and filters", "m^2/s^3", low=0.0,
              high=1e4),
        Param("sigma", 5.0, "position measurement noise standard deviation", "m", low=1e-3,
              high=1e4),
        Param("pd", 0.9, "detection probability", "1", low=0.0, high=1.0),
        Param("clutter_mean", 5.0, "mean false detections per scan", "returns/scan", low=0.0,
              high=1000.0),
        Param("box", 60.0, "half-width of the clutter square about the target", "m",
              low=1.0, high=1e6),
        Param("lost_m", 50.0, "final position error above which the track counts as lost",
              "m", low=0.0, high=1e6),
    ),
    run_trial=run_trial,
    metrics=(
        Metric("final_pos_sq_err_m2", "m^2", "squared position error at the last scan",
               better="lower"),
        Metric("lost", "1", "final error above lost_m", binary=True, better="lower"),
    ),
    report="clutter_report",
    figures={"lost": FigureSpec("tracks lost against the clutter rate, 95 % Wilson bands")},
)

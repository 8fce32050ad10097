"""The Stone Soup adapter (trackfuse.interop.stonesoup): conversions agree with our own
measurement and motion models, the mixture collapse and the resampler are right, and Stone
Soup's randomness comes from the trial alone. Skipped when the optional extra is absent;
the test without Stone Soup runs in a subprocess that blocks its import."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from trackfuse.interop import stonesoup as ss
from trackfuse.seeding import trial_streams
from trackfuse.tracking.models import cv_process_noise, cv_transition
from trackfuse.tracking.sensors import azel, azel_jacobian

BLOCK_STONESOUP = "import sys; sys.modules['stonesoup'] = None\n"


def test_without_stonesoup_trackfuse_imports_and_a_stonesoup_algorithm_names_the_extra():
    code = BLOCK_STONESOUP + (
        "import trackfuse.runner, trackfuse.experiments.twin_sensor as t\n"
        "from trackfuse.experiments.twin_sensor import model\n"
        "from trackfuse.seeding import trial_streams\n"
        "p = t.EXPERIMENT.defaults(); p['algorithms'] = ['stonesoup_pda/ekf']\n"
        "p['scan.count'] = 2\n"
        "try:\n    model.run_batch(p, [trial_streams(1, 0, 0)])\n"
        "except ImportError as err:\n    print(err)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out.count("\n") == 0 and "pip install 'trackfuse[stonesoup]'" in out


pytest.importorskip("stonesoup")


def _state(rng):
    x = np.concatenate([rng.uniform(-5e4, 5e4, 3) + [0, 1.2e5, 4e3], rng.normal(0, 30, 3)])
    A = rng.normal(size=(6, 6))
    return x, A @ A.T + np.diag([1e6, 1e6, 1e6, 100, 100, 100])


def test_state_order_round_trips():
    x, P = _state(np.random.default_rng(1))
    xs, Ps = ss.state_to_stonesoup(x, P)
    assert xs.shape == (6, 1) and xs[1, 0] == x[3]  # Stone Soup: (x, vx, y, vy, z, vz)
    back = ss.state_from_stonesoup(xs, Ps)
    np.testing.assert_array_equal(back[0], x)
    np.testing.assert_array_equal(back[1], P)


def test_angle_model_measures_our_azimuth_and_elevation_and_our_gate():
    from stonesoup.updater.kalman import ExtendedKalmanUpdater
    rng = np.random.default_rng(2)
    sensor = np.array([1.5e5, 2e3, 2.5e3])
    R = np.diag([0.01**2, 0.02**2])
    for _ in range(5):
        x, P = _state(rng)
        model = ss.angle_model(sensor, R, exact_jacobian=True)
        prior = ss.gaussian_prior(x, P, 0.0)
        centre, S = ss.measurement_gate(ExtendedKalmanUpdater(model).predict_measurement(prior))
        np.testing.assert_allclose(centre, azel(x[:3] - sensor), rtol=0, atol=1e-12)
        H = azel_jacobian(x[:3] - sensor)
        np.testing.assert_allclose(S, H @ P @ H.T + R, rtol=1e-12, atol=1e-20)


def test_stonesoup_finite_difference_jacobian_is_off_for_a_negative_coordinate():
    """The reason for ElevationBearingExactJacobian (docs/stonesoup.md): Stone Soup's step
    ``1e8 * spacing(x)`` is negative for ``x < 0`` and floored to 1e-8 m."""
    x = np.array([-23838.8, 97849.1 + 2e3, 32922.6 + 2.5e3, 0.0, 0.0, 0.0])
    sensor = np.array([1.5e5, 2e3, 2.5e3])
    prior = ss.gaussian_prior(x, np.eye(6), 0.0)
    exact = ss.angle_model(sensor, np.eye(2), exact_jacobian=True).jacobian(prior)
    numerical = np.asarray(ss.angle_model(sensor, np.eye(2)).jacobian(prior), dtype=float)
    np.testing.assert_allclose(exact, azel_jacobian(x[:3] - sensor)[::-1][:, ss.TO_STONESOUP],
                               rtol=1e-12)
    dx = ss.TO_STONESOUP.tolist().index(0)  # Stone Soup column of our x
    assert np.abs(numerical[:, dx] / exact[:, dx] - 1).max() > 1e-3


def test_detections_keep_order_and_put_elevation_first():
    model = ss.angle_model(np.zeros(3), np.eye(2) * 1e-4)
    z = np.array([[0.1, 0.2], [0.3, -0.4], [-1.0, 0.05]])
    dets = ss.detections(z, 3.0, model)
    assert [tuple(np.asarray(d.state_vector, dtype=float)[:, 0]) for d in dets] == \
        [(0.2, 0.1), (-0.4, 0.3), (0.05, -1.0)]
    assert all(d.timestamp == ss.timestamp(3.0) and d.measurement_model is model for d in dets)


def test_transition_model_predicts_as_our_cv_model():
    from stonesoup.predictor.kalman import KalmanPredictor
    x, P = _state(np.random.default_rng(3))
    F, Q = cv_transition(2.0), cv_process_noise(2.0, 900.0)
    predicted = KalmanPredictor(ss.transition_model(F, Q)).predict(ss.gaussian_prior(x, P, 0),
                                                                   timestamp=ss.timestamp(2))
    xp, Pp = ss.estimate(predicted)
    np.testing.assert_allclose(xp, F @ x, rtol=1e-12)
    np.testing.assert_allclose(Pp, F @ P @ F.T + Q, rtol=1e-10)


def test_collapse_equals_stonesoup_gm_reduce_single():
    from stonesoup.functions import gm_reduce_single
    from stonesoup.types.array import StateVectors
    rng = np.random.default_rng(4)
    x = rng.normal(size=(4, 6))
    P = np.stack([_state(rng)[1] for _ in range(4)])
    w = rng.random(4)
    mean, covar = ss.collapse(x, P, w)
    ref_mean, ref_covar = gm_reduce_single(StateVectors(x.T), P.transpose(1, 2, 0), w)
    np.testing.assert_allclose(mean, np.asarray(ref_mean, dtype=float)[:, 0], rtol=1e-12)
    np.testing.assert_allclose(covar, np.asarray(ref_covar, dtype=float), rtol=1e-10)


def test_gaussian_pda_update_with_one_sure_return_is_the_kalman_update():
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.updater.kalman import ExtendedKalmanUpdater
    x, P = _state(np.random.default_rng(5))
    sensor = np.array([1.5e5, 0.0, 2e3])
    model = ss.angle_model(sensor, np.eye(2) * 1e-4)
    predictor = ExtendedKalmanPredictor(ss.transition_model(np.eye(6), np.zeros((6, 6))))
    updater = ExtendedKalmanUpdater(model)
    hyp = PDAHypothesiser(predictor, updater, clutter_spatial_density=1e-300, prob_detect=1.0,
                          prob_gate=0.99)
    prior = ss.gaussian_prior(x, P, 0.0)
    z = azel(x[:3] - sensor) + 0.002
    hypotheses = hyp.hypothesise(prior, ss.detections(z[None], 0.0, model), ss.timestamp(0))
    got = ss.estimate(ss.gaussian_pda_update(hypotheses, updater))
    want = ss.estimate(updater.update(hypotheses[1]))
    np.testing.assert_allclose(got[0], want[0], rtol=1e-9)
    np.testing.assert_allclose(got[1], want[1], rtol=1e-6)


def _particles(weights):
    from stonesoup.types.array import StateVectors
    from stonesoup.types.state import ParticleState
    n = len(weights)
    return ParticleState(StateVectors(np.arange(6 * n, dtype=float).reshape(6, n)),
                         log_weight=np.log(np.asarray(weights) / np.sum(weights)))


def test_seeded_resampler_follows_its_own_random_state_only():
    weights = np.random.default_rng(6).random(200) ** 8

    def resampled(global_seed):
        np.random.seed(global_seed)
        rs = np.random.RandomState(np.random.PCG64(7))
        out = ss.SeededSystematicResampler(rs).resample(_particles(weights))
        return np.asarray(out.state_vector, dtype=float)

    a, b = resampled(1), resampled(2)
    np.testing.assert_array_equal(a, b)
    # systematic resampling keeps each particle floor(N w) or ceil(N w) times
    counts = np.bincount(a[0].astype(int), minlength=200)  # row 0 holds particle indices
    expected = 200 * weights / weights.sum()
    assert (np.abs(counts - expected) < 1.0 + 1e-9).all()


def test_seeded_resampler_leaves_a_healthy_particle_set_alone():
    particles = _particles(np.ones(50))
    rs = np.random.RandomState(np.random.PCG64(0))
    assert ss.SeededSystematicResampler(rs).resample(particles) is particles


def test_algorithm_random_state_depends_on_seed_trial_and_algorithm_only():
    def first(seed, point, trial, name, use_stream_first=False):
        common = trial_streams(seed, point, trial).common
        if use_stream_first:
            common.spawn(3)
            common.random(10)
        return ss.algorithm_random_state(common, name).random_sample(3)

    ref = first(1, 0, 2, "stonesoup_pda/pf")
    np.testing.assert_array_equal(ref, first(1, 5, 2, "stonesoup_pda/pf", True))
    for other in (first(2, 0, 2, "stonesoup_pda/pf"), first(1, 0, 3, "stonesoup_pda/pf"),
                  first(1, 0, 2, "stonesoup_pda/ekf")):
        assert not np.isin(ref, other).any()


def test_the_stonesoup_plugin_example_runs_through_the_cli(tmp_path):
    from conftest import ROOT, cli_env
    example = ROOT / "examples" / "stonesoup_plugin"
    env = cli_env()
    env["PYTHONPATH"] = f"{example}:{env['PYTHONPATH']}"
    proc = subprocess.run([sys.executable, "-m", "trackfuse", "run", "clutter.yaml", "--out",
                           str(tmp_path), "--workers", "1", "--trials", "12", "--no-progress"],
                          cwd=example, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    report = Path(proc.stdout.strip().splitlines()[-1].removeprefix("report: "))
    assert (report.parent / "figures" / "lost.png").exists()
    trials = pd.read_csv(report.parent / "trials.csv")
    assert set(trials["algorithm"]) == {"pda", "nn"}
    # paired: both trackers see the same detections; without clutter, PDA (no clutter
    # density) and nearest neighbour make the same update on most trials
    zero = trials[trials["clutter_mean"] == 0].pivot(index="trial", columns="algorithm",
                                                     values="final_pos_sq_err_m2")
    assert len(zero) == 12 and np.isclose(zero["pda"], zero["nn"], rtol=1e-9).mean() > 0.5

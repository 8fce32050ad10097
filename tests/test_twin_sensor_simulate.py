"""The batched simulation is, number for number, each trial simulated on its own."""

import numpy as np
import pytest
from pda_reference import disk_points

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    MAX_SENSORS,
    build_scenario,
    simulate,
    truth_trajectory,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import azel


def clutter_one(rng, mean, K, S):
    """One trial's clutter counts ``(K, S)`` and uniforms ``(total, 2)`` drawn round by
    round: every round one gap and two position uniforms per scan and sensor (of
    ``MAX_SENSORS``); a cell keeps its arrivals at or below ``mean``."""
    clock = np.ones((K, MAX_SENSORS))  # exp(-arrival)
    kept = [[[] for _ in range(MAX_SENSORS)] for _ in range(K)]
    while (clock > np.exp(-mean)).any():
        draw = rng.random((K, MAX_SENSORS, 3))
        clock = clock * draw[..., 0]
        for k, s in zip(*np.nonzero(clock > np.exp(-mean)), strict=True):
            kept[k][s].append(draw[k, s, 1:])
    counts = np.array([[len(kept[k][s]) for s in range(S)] for k in range(K)])
    uniforms = [u for k in range(K) for s in range(S) for u in kept[k][s]]
    return counts, np.array(uniforms).reshape(-1, 2)


def simulate_one(sc, streams):
    """One trial drawn and computed on its own (the simulation before it was batched)."""
    g_truth, g_init, g_noise = streams.common.spawn(3)
    x_true = truth_trajectory(sc, g_truth)
    x0 = x_true[0] + sc.P0_chol @ g_init.standard_normal(6)
    S = sc.R.shape[0]
    P_D = np.concatenate([sc.P_D, np.zeros(MAX_SENSORS - len(sc.P_D))])
    detected = (g_noise.random((sc.K, MAX_SENSORS)) < P_D)[:, :S]
    los = azel(x_true[1:, None, :3] - sc.sensor_pos[1:])
    unit_noise = g_noise.standard_normal((sc.K, MAX_SENSORS, 2))[:, :S]
    z_target = wrap(los + sc.noise_sd * unit_noise)
    n_clutter, u = clutter_one(g_noise, sc.clutter_mean, sc.K, S)
    if sc.clutter_model == "in_gate":
        clutter = disk_points(u[:, 0], u[:, 1])
    else:
        centre = np.repeat(los.reshape(-1, 2), n_clutter.ravel(), axis=0)
        clutter = centre + sc.window * (2.0 * u - 1.0)
        clutter[:, 0] = wrap(clutter[:, 0])
    return x_true, x0, detected, los, z_target, n_clutter, clutter


def stacked(sc, streams):
    """The per-trial simulations stacked and padded as a batch: ``(arrays..., clutter, ok)``."""
    trials = [simulate_one(sc, s) for s in streams]
    counts = np.stack([t[5] for t in trials])
    C = max(int(counts.max()) if counts.size else 0, 1)
    ok = np.arange(C) < counts[..., None]
    clutter = np.zeros(ok.shape + (2,))
    clutter[ok] = np.concatenate([t[6] for t in trials])
    return [np.stack([t[i] for t in trials]) for i in range(5)] + [clutter, ok]


@pytest.mark.parametrize("overrides", [
    {}, {"clutter.mean": 0.0}, {"clutter.model": "window"}, {"sensors.count": 1},
    {"target.q": 4.0, "target.velocity": [-150.0, 80.0, 0.0]},
    {"sensors.pd": 0.7, "sensors.baseline": 20000.0, "clutter.model": "window"}])
def test_a_batch_equals_its_trials_simulated_one_by_one(overrides):
    p = {**EXPERIMENT.defaults(), "clutter.mean": 6.0, "clutter.window": 0.03, **overrides}
    sc = build_scenario(p)
    batch = simulate(sc, [trial_streams(3, 1, t) for t in range(9)])
    want = stacked(sc, [trial_streams(3, 1, t) for t in range(9)])
    names = ("x_true", "x0", "detected", "los", "z_target", "clutter", "clutter_ok")
    for name, expected in zip(names, want, strict=True):
        np.testing.assert_array_equal(getattr(batch, name), expected, err_msg=name)

"""twin_sensor's clutter nested across levels: each level keeps its Poisson law, a lower
level's returns are a subset of a higher level's in the same trial, and the numbers do not
depend on the worker count or the batch size."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from trackfuse.config import load
from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import build_scenario, simulate
from trackfuse.runner import Runner
from trackfuse.seeding import trial_streams
from trackfuse.tracking.nested_clutter import NestedClutter

#: False-alarm rate of each statistical check below (deterministic seeds: a fixed outcome,
#: but a wrong law fails them with near certainty at these sample sizes).
ALPHA = 1e-3


def nested_poisson(rngs: list[np.random.Generator], mean: float, cells: int):
    """Counts ``(N, cells)`` and uniforms ``(2, total)`` of each generator's nested clutter."""
    clutter = NestedClutter(mean, len(rngs), cells)
    for trial, rng in enumerate(rngs):
        clutter.draw(trial, rng)
    return clutter.counts, clutter.uniforms()


def assert_poisson(counts: np.ndarray, mean: float) -> None:
    """``counts`` look like independent ``Poisson(mean)`` draws: the sample mean within
    its normal band, the index of dispersion ``sum (x - mean)^2 / mean`` within the
    chi-square band of ``n`` degrees of freedom, and a chi-square goodness of fit on the
    counts (tail merged so every expected cell holds at least 5)."""
    n = counts.size
    z = stats.norm.ppf(1 - ALPHA / 2)
    assert abs(counts.mean() - mean) <= z * np.sqrt(mean / n), counts.mean()
    dispersion = ((counts - mean) ** 2).sum() / mean
    assert stats.chi2.ppf(ALPHA / 2, n) <= dispersion <= stats.chi2.ppf(1 - ALPHA / 2, n)
    top = int(stats.poisson.isf(5.0 / n, mean))  # P(X > top) * n < 5: merged into top
    observed = np.bincount(np.minimum(counts, top), minlength=top + 1)
    expected = n * stats.poisson.pmf(np.arange(top + 1), mean)
    expected[-1] = n * stats.poisson.sf(top - 1, mean)
    assert stats.chisquare(observed, expected).pvalue > ALPHA


@pytest.mark.parametrize("mean", [0.4, 3.0, 9.0, 40.0])
def test_every_level_is_poisson_of_its_mean(mean):
    counts, uniforms = nested_poisson([np.random.default_rng(17)], mean, 20000)
    assert counts.shape == (1, 20000)
    assert_poisson(counts[0], mean)
    assert uniforms.shape == (2, counts.sum())
    for u in uniforms:  # the kept arrivals' positions stay uniform on [0, 1)
        assert stats.kstest(u, "uniform").pvalue > ALPHA


def test_a_level_without_clutter_has_no_returns():
    counts, uniforms = nested_poisson([np.random.default_rng(2)] * 3, 0.0, 50)
    assert counts.shape == (3, 50) and not counts.any() and uniforms.shape == (2, 0)


def reference_nested(rng: np.random.Generator, mean: float, cells: int):
    """The same process drawn one round at a time (no blocks): per cell, the arrivals at
    or below ``mean`` and their uniforms."""
    clock = np.ones(cells)  # product of the gap uniforms: exp(-arrival)
    kept: list[list[np.ndarray]] = [[] for _ in range(cells)]
    while (clock > np.exp(-mean)).any():
        draw = rng.random((cells, 3))
        clock = clock * draw[:, 0]
        for c in np.flatnonzero(clock > np.exp(-mean)):
            kept[c].append(draw[c, 1:])
    counts = np.array([len(k) for k in kept])
    return counts, np.array([u for k in kept for u in k]).reshape(-1, 2).T


@pytest.mark.parametrize("mean", [0.0, 2.5, 30.0])
def test_the_blocks_read_each_stream_as_single_rounds_would(mean):
    """A batch of trials, some of which need more than one block of rounds (400 cells),
    gives each trial what its own stream drawn round by round gives."""
    seeds = range(6)
    counts, uniforms = nested_poisson([np.random.default_rng(s) for s in seeds], mean, 400)
    want = [reference_nested(np.random.default_rng(s), mean, 400) for s in seeds]
    np.testing.assert_array_equal(counts, np.stack([w[0] for w in want]))
    np.testing.assert_array_equal(uniforms, np.concatenate([w[1] for w in want], axis=1))
    if mean:  # one trial, not all, needed a second block (the first has this many rounds)
        more = counts.max(axis=1) >= int(mean + 4.0 * np.sqrt(mean)) + 2
        assert more.any() and not more.all()


def cell_sets(batch) -> dict[tuple[int, ...], set[tuple[float, float]]]:
    """Each clutter cell's returns ``{(trial, scan, sensor): {(a, b), ...}}``."""
    out: dict[tuple[int, ...], set[tuple[float, float]]] = {}
    for cell in np.ndindex(batch.clutter_ok.shape[:3]):
        points = batch.clutter[cell][batch.clutter_ok[cell]]
        out[cell] = {tuple(p) for p in points}
    return out


@pytest.mark.parametrize("model", ["in_gate", "window"])
def test_a_lower_level_sees_a_subset_of_a_higher_levels_returns(model):
    streams = lambda: [trial_streams(31, 0, t) for t in range(12)]  # noqa: E731
    levels = (0.0, 1.0, 4.0, 4.5, 9.0, 15.0)
    sets = []
    for level in levels:
        p = {**EXPERIMENT.defaults(), "scan.count": 6, "clutter.model": model,
             "clutter.window": 0.05, "clutter.mean": level}
        sets.append(cell_sets(simulate(build_scenario(p), streams())))
    grew = 0
    for low, high in zip(sets, sets[1:], strict=False):
        for cell, points in low.items():
            assert points <= high[cell], cell
            grew += len(high[cell]) > len(points)
    assert grew > 0  # the levels differ: the subsets are not all equal


@pytest.mark.parametrize("model", ["in_gate", "window"])
def test_each_level_through_the_simulation_is_poisson_and_one_sensor_sees_sensor_1s(model):
    """The counts ``simulate`` hands the filters, over trials, scans and sensors, follow the
    level's law; a one-sensor point keeps sensor 1's returns of the two-sensor point."""
    streams = lambda: [trial_streams(8, 3, t) for t in range(150)]  # noqa: E731
    p = {**EXPERIMENT.defaults(), "clutter.model": model, "clutter.mean": 6.0}
    two = simulate(build_scenario(p), streams())
    assert_poisson(two.clutter_ok.sum(axis=-1).ravel(), 6.0)
    one = simulate(build_scenario({**p, "sensors.count": 1}), streams())
    np.testing.assert_array_equal(one.clutter_ok, two.clutter_ok[:, :, :1, :one.clutter.shape[3]])
    np.testing.assert_array_equal(one.clutter, two.clutter[:, :, :1, :one.clutter.shape[3]])


def test_the_truth_and_noise_are_the_same_at_every_level():
    base = {**EXPERIMENT.defaults(), "scan.count": 5, "target.q": 50.0}
    ref = simulate(build_scenario({**base, "clutter.mean": 0.0}), [trial_streams(4, 0, 1)])
    got = simulate(build_scenario({**base, "clutter.mean": 12.0}), [trial_streams(4, 0, 1)])
    for name in ("x_true", "x0", "detected", "los", "z_target"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name), err_msg=name)


CONFIG = """
experiment: twin_sensor
trials: 9
seed: 3
batch_size: {batch}
params:
  scan.count: 4
  clutter.model: {model}
  clutter.window: 0.05
  algorithms: [mspda_parallel/mgekf, nn/ekf]
sweep:
  clutter.mean: [0, 2.5, 7]
"""


@pytest.mark.slow  # two worker processes, each loading the compiled filter
@pytest.mark.parametrize("model", ["in_gate", "window"])
def test_one_and_two_workers_and_any_batch_size_write_identical_csvs(model, write_config,
                                                                     tmp_path):
    runs = []
    for batch, executor, workers in ((2, "serial", 1), (5, "process", 2)):
        config = load(write_config(CONFIG.format(batch=batch, model=model)))
        runs.append(Runner(config, tmp_path / str(batch), executor=executor, workers=workers,
                           progress=False, plots=False).run().folder)
    for name in ("trials.csv", "summary.csv"):
        assert (runs[0] / name).read_bytes() == (runs[1] / name).read_bytes(), name


def test_padded_disk_points_are_the_numpy_disk_points_bit_for_bit():
    """The compiled placement of the in-gate clutter gives exactly the numpy disk points
    (same square root, sine and cosine) in each cell's first slots, zero after them."""
    from pda_reference import disk_points

    from trackfuse.tracking.nested_clutter import padded_disk_points

    rng = np.random.default_rng(11)
    counts = rng.poisson(6.0, (30, 4, 2))
    uniforms = rng.random((2, counts.sum()))
    slots = counts.max()
    points, valid = padded_disk_points(counts, uniforms, slots)
    np.testing.assert_array_equal(valid, np.arange(slots) < counts[..., None])
    np.testing.assert_array_equal(points[valid], disk_points(uniforms[0], uniforms[1]))
    assert not points[~valid].any()

"""The compiled twin-sensor filter loop against its plain numpy reference (pinned to 1e-9)."""

from dataclasses import replace

import numpy as np
import pytest

from trackfuse.experiments.twin_sensor import EXPERIMENT, kernel
from trackfuse.experiments.twin_sensor.kernel import run_filter_compiled
from trackfuse.experiments.twin_sensor.model import (
    ALGORITHMS,
    BINARY_METRICS,
    FILTERS,
    LossRules,
    build_scenario,
    run_batch,
    run_filter,
    score_estimates,
    simulate,
    stack,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda import PDAOptions

CASES = [(algorithm, {}) for algorithm in ALGORITHMS] + [
    ("mspda_parallel/ekf", {"sensors.count": 1}),
    ("nn/mgekf", {"sensors.count": 1}),
    ("mspda_sequential/ekf", {"sensors.count": 1}),
    ("mspda_parallel/mgekf", {"clutter.model": "window", "clutter.window": 0.03}),
    ("mspda_parallel/mgekf", {"pda.joint_cov": "blockdiag"}),
    ("paper_approx/mgekf", {"pda.density": "nonparametric"}),
    ("mspda_parallel/mgekf", {"pda.density": "nonparametric"}),
    ("mspda_parallel/mgekf", {"filter.mg_at": "combined"}),
    ("mspda_sequential/mgekf", {"filter.mg_at": "combined"}),
    ("nn/mgekf", {"filter.mg_at": "combined"}),
    ("nn/mgekf", {"sensors.pd": 0.8}),
    ("paper_approx/ekf", {"sensors.pd": 0.0}),
    ("mspda_parallel/ekf", {"sensors.pd": 0.0, "clutter.mean": 0.0}),
    ("mspda_parallel/mgekf", {"clutter.mean": 0.0}),
    ("mspda_parallel/mgekf", {"sensors.baseline": 20000.0, "sensor2.noise_ratio": 2.0}),
    ("mspda_sequential/mgekf", {"target.q": 4.0, "target.velocity": [-150.0, 80.0, 0.0]}),
]


def _setup(overrides: dict, trials: int = 40):
    p = EXPERIMENT.defaults()
    p.update({"clutter.mean": 6.0, **overrides})
    sc = build_scenario(p)
    batch = stack([simulate(sc, trial_streams(11, 0, t)) for t in range(trials)])
    return p, sc, batch, LossRules.from_params(p)


def _options(p: dict, sc, algorithm: str) -> PDAOptions:
    assoc, filt = algorithm.split("/")
    return PDAOptions(assoc, FILTERS[filt], p["pda.joint_cov"], p["pda.density"],
                      p["filter.mg_at"], sc.P_G)


def _assert_pinned(got: dict, ref: dict) -> None:
    """Flags and counts equal; every other metric within 1e-9 of its batch-wide magnitude."""
    for key, want in ref.items():
        have = got[key]
        np.testing.assert_array_equal(np.isnan(have), np.isnan(want), err_msg=key)
        if key in BINARY_METRICS or key == "n_valid":
            np.testing.assert_array_equal(have, want, err_msg=key)
            continue
        scale = np.nanmax(np.abs(want)) if np.isfinite(want).any() else 1.0
        assert np.nanmax(np.abs(have - want), initial=0.0) <= 1e-9 * scale, key


@pytest.mark.parametrize("algorithm, overrides", CASES,
                         ids=[f"{a}-{'-'.join(f'{k}={v}' for k, v in o.items())}"
                              for a, o in CASES])
def test_compiled_filter_equals_the_numpy_reference(algorithm, overrides):
    p, sc, batch, rules = _setup(overrides)
    options = _options(p, sc, algorithm)
    got = score_estimates(sc, batch, run_filter_compiled(sc, batch, options), rules)
    _assert_pinned(got, run_filter(sc, batch, options, rules))
    if p["clutter.mean"] > 0 and p["sensors.pd"] > 0:
        assert got["n_valid"].mean() > 1.0  # clutter really was gated


@pytest.fixture
def python_kernel(monkeypatch):
    """The kernel's pure-Python path, what ``NUMBA_DISABLE_JIT=1`` runs: every compiled
    function of the module replaced by its Python source."""
    for name, value in vars(kernel).items():
        if hasattr(value, "py_func"):
            monkeypatch.setattr(kernel, name, value.py_func)


ZERO_LOGS = [(a, {"clutter.mean": 0.0}) for a in ALGORITHMS] + [
    ("paper_approx/ekf", {"sensors.pd": 0.0})]


@pytest.mark.parametrize("algorithm, overrides", ZERO_LOGS,
                         ids=[f"{a}-{k}={v}" for a, o in ZERO_LOGS for k, v in o.items()])
def test_the_python_path_takes_the_log_of_zero_as_the_compiled_one(
        python_kernel, algorithm, overrides):
    """No clutter (clutter density 0) or no detection (P_D 0): the compiled ``log`` gives
    -inf, Python's ``math.log`` raised ``ValueError: math domain error``."""
    p, sc, batch, rules = _setup(overrides, trials=2)
    options = _options(p, sc, algorithm)
    got = score_estimates(sc, batch, kernel.run_filter_compiled(sc, batch, options), rules)
    _assert_pinned(got, run_filter(sc, batch, options, rules))


def test_a_diverged_trial_is_flagged_alike_and_leaves_the_others_untouched():
    p, sc, batch, rules = _setup({})
    x0 = batch.x0.copy()
    x0[3, 0] = np.nan
    broken = replace(batch, x0=x0)
    for algorithm in ("mspda_parallel/mgekf", "mspda_sequential/ekf", "nn/mgekf"):
        options = _options(p, sc, algorithm)
        got = score_estimates(sc, broken, run_filter_compiled(sc, broken, options), rules)
        _assert_pinned(got, run_filter(sc, broken, options, rules))
        assert got["lost_angle"][3].all() and got["lost_gate"][3].all()
        assert np.isnan(got["nees"][3]).all() and (got["n_valid"][3] == 0).all()
        clean = score_estimates(sc, batch, run_filter_compiled(sc, batch, options), rules)
        for key in got:
            np.testing.assert_array_equal(np.delete(got[key], 3, axis=0),
                                          np.delete(clean[key], 3, axis=0), err_msg=key)


def test_rows_do_not_depend_on_how_trials_are_batched():
    """Each trial is filtered on its own, so any batch split writes the same bytes (what
    lets the batch size follow the work)."""
    p = EXPERIMENT.defaults()
    p.update({"clutter.mean": 9.0, "algorithms": ["mspda_parallel/mgekf", "nn/ekf",
                                                  "mspda_sequential/mgekf"]})
    def streams(trials: range) -> list:  # fresh generators each time: they are consumed
        return [trial_streams(3, 0, t) for t in trials]

    whole = list(run_batch(p, streams(range(7))))
    parts = list(run_batch(p, streams(range(2)))) + list(run_batch(p, streams(range(2, 7))))
    assert whole == parts  # trial by trial, every row and value

"""The compiled twin-sensor filter loop against its plain numpy reference (pinned to 1e-9)."""

from dataclasses import replace

import numpy as np
import pda_reference as reference
import pytest
import twin_sensor_pinned as pinned

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    ALGORITHMS,
    run_batch,
    score_estimates,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking import pda as kernel

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


@pytest.mark.parametrize("algorithm, overrides", CASES,
                         ids=[f"{a}-{'-'.join(f'{k}={v}' for k, v in o.items())}"
                              for a, o in CASES])
def test_compiled_filter_equals_the_numpy_reference(algorithm, overrides):
    p, sc, batch, rules = pinned.setup(overrides)
    options = pinned.options(p, sc, algorithm)
    got = score_estimates(sc, batch, kernel.run_filter(sc, batch, options), rules)
    pinned.assert_pinned(got, reference.run_filter(sc, batch, options, rules))
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
    p, sc, batch, rules = pinned.setup(overrides, trials=2)
    options = pinned.options(p, sc, algorithm)
    got = score_estimates(sc, batch, kernel.run_filter(sc, batch, options), rules)
    pinned.assert_pinned(got, reference.run_filter(sc, batch, options, rules))


def test_a_diverged_trial_is_flagged_alike_and_leaves_the_others_untouched():
    p, sc, batch, rules = pinned.setup({})
    x0 = batch.x0.copy()
    x0[3, 0] = np.nan
    broken = replace(batch, x0=x0)
    for algorithm in ("mspda_parallel/mgekf", "mspda_sequential/ekf", "nn/mgekf"):
        options = pinned.options(p, sc, algorithm)
        got = score_estimates(sc, broken, kernel.run_filter(sc, broken, options), rules)
        pinned.assert_pinned(got, reference.run_filter(sc, broken, options, rules))
        assert got["lost_angle"][3].all() and got["lost_gate"][3].all()
        assert np.isnan(got["nees"][3]).all() and (got["n_valid"][3] == 0).all()
        clean = score_estimates(sc, batch, kernel.run_filter(sc, batch, options), rules)
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

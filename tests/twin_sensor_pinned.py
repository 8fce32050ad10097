"""The compiled twin-sensor kernel against its numpy reference: a batch, an algorithm's
options and the 1e-9 comparison, shared by the kernel tests and the cold-compile tests."""

from __future__ import annotations

import numpy as np

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    BINARY_METRICS,
    FILTERS,
    LossRules,
    build_scenario,
    simulate,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda_options import PDAOptions


def setup(overrides: dict, trials: int = 40):
    """``(params, scenario, batch, loss rules)`` of ``trials`` trials with 6 false returns
    per scan on average, unless ``overrides`` says otherwise."""
    p = EXPERIMENT.defaults()
    p.update({"clutter.mean": 6.0, **overrides})
    sc = build_scenario(p)
    batch = simulate(sc, [trial_streams(11, 0, t) for t in range(trials)])
    return p, sc, batch, LossRules.from_params(p)


def options(p: dict, sc, algorithm: str) -> PDAOptions:
    """The :class:`PDAOptions` of ``algorithm`` (``assoc/filter``) under params ``p``."""
    assoc, filt = algorithm.split("/")
    return PDAOptions(assoc, FILTERS[filt], p["pda.joint_cov"], p["pda.density"],
                      p["filter.mg_at"], sc.P_G)


def assert_pinned(got: dict, ref: dict) -> None:
    """Flags and counts equal; every other metric within 1e-9 of its batch-wide magnitude."""
    for key, want in ref.items():
        have = got[key]
        np.testing.assert_array_equal(np.isnan(have), np.isnan(want), err_msg=key)
        if key in BINARY_METRICS or key == "n_valid":
            np.testing.assert_array_equal(have, want, err_msg=key)
            continue
        scale = np.nanmax(np.abs(want)) if np.isfinite(want).any() else 1.0
        assert np.nanmax(np.abs(have - want), initial=0.0) <= 1e-9 * scale, key

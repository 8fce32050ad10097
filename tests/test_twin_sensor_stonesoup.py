"""Stone Soup's filters in twin_sensor: the same returns as ours (with the exact Jacobian the
Stone Soup EKF + PDA *is* ours), unchanged data for our algorithms, and rows byte-identical
across executors, worker counts, resume and numpy's global random state."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
from conftest import ctrl_c_at_part

pytest.importorskip("stonesoup")

from trackfuse.config import ConfigError, build  # noqa: E402
from trackfuse.experiments.twin_sensor import EXPERIMENT, model  # noqa: E402
from trackfuse.experiments.twin_sensor.stonesoup import STONESOUP_ALGORITHMS  # noqa: E402
from trackfuse.runner import RunInterrupted, Runner  # noqa: E402
from trackfuse.seeding import trial_streams  # noqa: E402

SMALL = {"scan.count": 6, "sensors.count": 1, "stonesoup.particles": 60}


def _params(**kw):
    p = EXPERIMENT.defaults()
    p.update(SMALL)
    p.update(kw)
    return p


@pytest.mark.parametrize("clutter_model", ["in_gate", "window"])
def test_stonesoup_ekf_with_the_exact_jacobian_is_our_ekf_pda(clutter_model):
    p = _params(**{"clutter.mean": 4.0, "clutter.model": clutter_model, "clutter.window": 0.03,
                   "scan.count": 12, "stonesoup.jacobian": "analytic",
                   "algorithms": ["mspda_parallel/ekf", "stonesoup_pda/ekf"]})
    rows = model.run_batch(p, [trial_streams(3, 0, t) for t in range(6)])
    for key in ("range_err_m", "nees", "n_valid"):
        ours = np.array([r[key] for t in rows for r in t
                         if r["algorithm"] == "mspda_parallel/ekf"])
        theirs = np.array([r[key] for t in rows for r in t
                           if r["algorithm"] == "stonesoup_pda/ekf"])
        np.testing.assert_allclose(theirs, ours, rtol=1e-6, atol=1e-6)
    assert np.mean([r["n_valid"] for t in rows for r in t]) > 1.0  # clutter was validated


def test_adding_stonesoup_algorithms_leaves_our_rows_unchanged():
    streams = lambda: [trial_streams(5, 1, t) for t in range(3)]  # noqa: E731
    p = _params(**{"clutter.mean": 3.0, "algorithms": ["mspda_parallel/mgekf"]})
    alone = model.run_batch(p, streams())
    p["algorithms"] = ["stonesoup_pda/pf", "mspda_parallel/mgekf", "stonesoup_pda/ukf"]
    mixed = model.run_batch(p, streams())
    strip = lambda rows: [{k: v for k, v in r.items() if k != "cpu_time_s"}  # noqa: E731
                          for t in rows for r in t if r["algorithm"] == "mspda_parallel/mgekf"]
    assert strip(alone) == strip(mixed)


def test_every_stonesoup_filter_tracks_one_and_two_sensors():
    for sensors in (1, 2):
        p = _params(**{"clutter.mean": 2.0, "sensors.count": sensors,
                       "sensors.baseline": 20000.0, "algorithms": list(STONESOUP_ALGORITHMS)})
        rows = model.run_batch(p, [trial_streams(7, 0, t) for t in range(3)])
        sc = model.build_scenario(p)  # the same trials' initial estimates, drawn afresh
        start = model.simulate(sc, [trial_streams(7, 0, t) for t in range(3)])
        prior = (np.linalg.norm(start.x0[:, :3] - sc.platform[0], axis=1)
                 - np.linalg.norm(start.x_true[:, 0, :3] - sc.platform[0], axis=1))
        for name in STONESOUP_ALGORITHMS:
            last = [r for t in rows for r in t if r["algorithm"] == name and r["scan"] == 6]
            assert all(np.isfinite(r["nees"]) and r["n_valid"] >= 0.5 for r in last), name
            # no divergence: the range error stays of the size of these trials' initial
            # range errors (20 km standard deviation; the 20 s give little range)
            rmse = np.sqrt(np.mean([r["range_sq_err_m2"] for r in last]))
            assert rmse < 2.0 * np.sqrt(np.mean(prior**2)), name


def test_particle_filter_ignores_numpy_global_random_state():
    p = _params(**{"clutter.mean": 3.0, "algorithms": ["stonesoup_pda/pf"]})

    def rows(seed):
        np.random.seed(seed)
        out = model.run_batch(p, [trial_streams(9, 0, t) for t in range(2)])
        return [{k: v for k, v in r.items() if k != "cpu_time_s"} for t in out for r in t]

    assert rows(1) == rows(2)


CONFIG = {"experiment": "twin_sensor", "trials": 4, "seed": 21, "batch_size": 2,
          "params": {**SMALL, "algorithms": ["mspda_parallel/ekf", *STONESOUP_ALGORITHMS]},
          "sweep": {"clutter.mean": [0.0, 3.0]}}


def _run(out, **kw):
    return Runner(build(CONFIG, "stonesoup.yaml"), out, progress=False, plots=False,
                  **kw).run()


def test_rows_identical_across_executors_workers_and_resume(tmp_path):
    serial = _run(tmp_path / "serial", executor="serial")
    reference = (serial.folder / "trials.csv").read_bytes()
    assert b"stonesoup_pda/pf" in reference and b"failed" not in reference
    pooled = _run(tmp_path / "pooled", executor="process", workers=2)
    assert (pooled.folder / "trials.csv").read_bytes() == reference
    with ctrl_c_at_part(3), pytest.raises(RunInterrupted):
        _run(tmp_path / "resumed", executor="serial")
    resumed = _run(tmp_path / "resumed", executor="process", workers=1)
    assert 0 < resumed.computed_trials < 8
    assert (resumed.folder / "trials.csv").read_bytes() == reference
    assert json.loads((resumed.folder / "manifest.json").read_text())["sessions"] == 2


def test_a_stonesoup_algorithm_without_stonesoup_is_one_config_error(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "stonesoup" else real(name, *a))
    raw = {"experiment": "twin_sensor",
           "sweep": {"algorithms": [["mspda_parallel/ekf"], ["stonesoup_pda/ukf"]]}}
    with pytest.raises(ConfigError, match=r"sweep\.algorithms: stonesoup_pda/ukf needs "
                                          r"Stone Soup.*pip install 'trackfuse\[stonesoup\]'"):
        build(raw, "cfg.yaml")
    raw = {"experiment": "twin_sensor", "params": {"algorithms": ["mspda_parallel/ekf"]}}
    assert build(raw, "cfg.yaml").params["algorithms"] == ["mspda_parallel/ekf"]

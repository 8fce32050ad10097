"""IPDA (track existence) in the twin-sensor experiment: the compiled filter against its numpy
oracle (1e-9), its false-track rate on clutter alone against the design value of an
independent simulation of the existence chain, confirmation on a clean target, the state
estimate shared with the parallel PDA, and identical rows whatever the worker count."""

from dataclasses import replace
from pathlib import Path

import ipda_reference as reference
import numpy as np
import pandas as pd
import pytest
import twin_sensor_pinned as pinned
from conftest import trackfuse

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.checks import config_problem
from trackfuse.experiments.twin_sensor.model import (
    EXISTENCE_METRICS,
    IPDA_ALGORITHMS,
    METRICS,
    run_batch,
    score_estimates,
    score_existence,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking import ipda as ipda_kernel
from trackfuse.tracking import pda as pda_kernel
from trackfuse.tracking.ipda import run_ipda
from trackfuse.tracking.ipda_options import ExistenceModel, track_decisions
from trackfuse.tracking.pda_options import PDAOptions

ROOT = Path(__file__).resolve().parents[1]


def _options(p: dict, sc, algorithm: str) -> PDAOptions:
    """The state-update options of an IPDA ``algorithm`` (the parallel PDA's)."""
    return pinned.options(p, sc, algorithm.replace("ipda/", "mspda_parallel/"))


def _run(sc, batch, options, model, rules) -> dict:
    est, existence = run_ipda(sc, batch, options, model)
    return {**score_estimates(sc, batch, est, rules), **score_existence(existence, model)}


CASES = [("ipda/mgekf", {}), ("ipda/ekf", {}), ("ipda/mgekf", {"sensors.count": 1}),
         ("ipda/ekf", {"sensors.count": 1, "sensors.pd": 0.7}),
         ("ipda/mgekf", {"pda.joint_cov": "blockdiag"}),
         ("ipda/mgekf", {"clutter.model": "window", "clutter.window": 0.03}),
         ("ipda/mgekf", {"pda.density": "nonparametric", "sensors.pd": 0.8}),
         ("ipda/mgekf", {"filter.mg_at": "combined"}),
         ("ipda/mgekf", {"clutter.mean": 0.0}),
         ("ipda/mgekf", {"clutter.mean": 0.0, "sensors.pd": 0.6}),
         ("ipda/ekf", {"clutter.mean": 15.0, "sensors.pd": 0.9, "sensor2.pd_ratio": 0.5,
                       "ipda.persistence": 0.9, "ipda.initial": 0.2}),
         ("ipda/mgekf", {"target.q": 4.0, "target.velocity": [-150.0, 80.0, 0.0]})]


@pytest.mark.parametrize("algorithm, overrides", CASES,
                         ids=[f"{a}-{'-'.join(f'{k}={v}' for k, v in o.items())}"
                              for a, o in CASES])
def test_compiled_ipda_equals_the_numpy_reference(algorithm, overrides):
    p, sc, batch, rules = pinned.setup(overrides)
    options, model = _options(p, sc, algorithm), ExistenceModel.from_params(p)
    got = _run(sc, batch, options, model, rules)
    want = reference.run_ipda(sc, batch, options, model, rules)
    pinned.assert_pinned(got, want)
    existence = want["existence"]
    if p["clutter.mean"] == 0 and p["sensors.pd"] == 1:  # every scan validates the target
        assert (existence == 1).all()  # where no clutter is expected: Lambda infinite
    else:
        assert np.nanmin(existence) < 0.5 < np.nanmax(existence)  # it moved both ways


@pytest.fixture
def python_kernel(monkeypatch):
    """The kernels' pure-Python path, what ``NUMBA_DISABLE_JIT=1`` runs: every compiled
    function of the PDA and IPDA modules replaced by its Python source."""
    for module in (pda_kernel, ipda_kernel):
        for name, value in vars(module).items():
            if hasattr(value, "py_func"):
                monkeypatch.setattr(module, name, value.py_func)


@pytest.mark.parametrize("overrides", [{"clutter.mean": 0.0}, {"sensors.count": 1}])
def test_the_python_path_equals_the_reference(python_kernel, overrides):
    """Without clutter the null hypothesis's weight is zero once a return is validated:
    the existence update must not divide by it (Python raises where compiled code gives
    inf)."""
    p, sc, batch, rules = pinned.setup(overrides, trials=2)
    options, model = _options(p, sc, "ipda/mgekf"), ExistenceModel.from_params(p)
    est, existence = ipda_kernel.run_ipda(sc, batch, options, model)
    got = {**score_estimates(sc, batch, est, rules), **score_existence(existence, model)}
    pinned.assert_pinned(got, reference.run_ipda(sc, batch, options, model, rules))


def test_a_diverged_trial_has_no_existence_and_is_terminated():
    p, sc, batch, rules = pinned.setup({})
    x0 = batch.x0.copy()
    x0[3, 0] = np.nan
    broken = replace(batch, x0=x0)
    options, model = _options(p, sc, "ipda/mgekf"), ExistenceModel.from_params(p)
    got = _run(sc, broken, options, model, rules)
    pinned.assert_pinned(got, reference.run_ipda(sc, broken, options, model, rules))
    assert np.isnan(got["existence"][3]).all() and got["lost_existence"][3].all()
    assert np.isfinite(got["existence"][[0, 1, 2, 4]]).all()


def test_ipda_estimates_are_the_parallel_pdas_bit_for_bit():
    """Given existence, IPDA's association probabilities are the PDA's: every state metric
    of ``ipda/F`` is the one of ``mspda_parallel/F`` on the same trials."""
    p = EXPERIMENT.defaults()
    p.update({"clutter.mean": 8.0, "algorithms": ["mspda_parallel/mgekf", "ipda/mgekf",
                                                  "mspda_parallel/ekf", "ipda/ekf"]})
    rows = pd.DataFrame([r for trial in run_batch(p, [trial_streams(5, 0, t) for t in range(6)])
                         for r in trial])
    for filt in ("mgekf", "ekf"):
        pda = rows[rows["algorithm"] == f"mspda_parallel/{filt}"].reset_index(drop=True)
        ipda = rows[rows["algorithm"] == f"ipda/{filt}"].reset_index(drop=True)
        pd.testing.assert_frame_equal(pda[list(METRICS)], ipda[list(METRICS)])
        assert pda[list(EXISTENCE_METRICS)].isna().all().all()
        assert ipda[list(EXISTENCE_METRICS)].notna().all().all()


def test_runs_without_ipda_keep_their_columns():
    """The existence columns are written only by runs with an IPDA algorithm (the other
    runs' ``trials.csv`` keep their bytes)."""
    p = EXPERIMENT.defaults()
    p["algorithms"] = ["mspda_parallel/mgekf"]
    row = run_batch(p, [trial_streams(5, 0, 0)])[0][0]
    assert not set(EXISTENCE_METRICS) & set(row)
    assert EXPERIMENT.missing_metrics(list(row)) == []


def _design_false_confirmations(model: ExistenceModel, P_D: np.ndarray, P_G: float,
                                clutter: float, scans: int, trials: int,
                                rng: np.random.Generator) -> np.ndarray:
    """Whether each of ``trials`` tracks on clutter alone is confirmed within ``scans`` scans,
    simulated from the existence chain alone. In-gate clutter is uniform in the gate, so a
    false return's squared whitened distance is ``gamma U`` (``U`` uniform) and its
    ``N(nu; 0, S) / lambda = gamma exp(-gamma U / 2) / (2 clutter)``, whatever the filter's
    state; two sensors with block-diagonal pair weights multiply their ratios."""
    gamma = -2.0 * np.log1p(-P_G)
    psi = np.full(trials, model.initial)
    confirmed, terminated = np.zeros(trials, bool), np.zeros(trials, bool)
    for _ in range(scans):
        Lam = np.ones(trials)
        for p_d in P_D:
            counts = rng.poisson(clutter, trials)
            u = rng.random((trials, max(int(counts.max()), 1)))
            ratio = gamma * np.exp(-0.5 * gamma * u) / (2.0 * clutter)
            ratio[np.arange(u.shape[1]) >= counts[:, None]] = 0.0
            Lam *= 1.0 - p_d * P_G + p_d * ratio.sum(axis=1)
        pred = model.persistence * psi
        psi = Lam * pred / (1.0 - pred + Lam * pred)
        terminated |= psi < model.terminate
        confirmed |= (psi >= model.confirm) & ~terminated
    return confirmed


@pytest.mark.parametrize("overrides", [{"sensors.count": 1},
                                       {"sensors.count": 2, "pda.joint_cov": "blockdiag"}])
def test_false_track_rate_on_clutter_alone_matches_its_design_value(overrides):
    """No target return at all (only clutter): the share of tracks whose existence reaches
    the confirmation threshold is the probability the existence chain crosses it, simulated
    here without the filter."""
    params = {"clutter.mean": 3.0, "sensors.pd": 0.9, "scan.count": 15, "ipda.confirm": 0.8,
              **overrides}
    p, sc, batch, rules = pinned.setup(params, trials=1500)
    silent = replace(batch, detected=np.zeros_like(batch.detected))
    model = ExistenceModel.from_params(p)
    got = _run(sc, silent, _options(p, sc, "ipda/mgekf"), model, rules)
    rate = got["confirmed"][:, -1].mean()
    design = _design_false_confirmations(model, sc.P_D, sc.P_G, 3.0, sc.K, 20000,
                                         np.random.default_rng(1)).mean()
    assert 0.02 < design < 0.5  # a rate the test can resolve
    sd = np.sqrt(design * (1 - design) * (1 / 1500 + 1 / 20000))
    assert abs(rate - design) < 4.0 * sd, (rate, design)


def test_existence_rises_to_confirmation_on_a_clean_target():
    """The paper's target seen every scan (P_D = 1) among one false return per gate: the
    tracks are confirmed within a few scans and stay."""
    p, sc, batch, rules = pinned.setup({"clutter.mean": 1.0}, trials=100)
    model = ExistenceModel.from_params(p)
    got = _run(sc, batch, _options(p, sc, "ipda/mgekf"), model, rules)
    assert got["confirmed"][:, 4].mean() >= 0.95  # within five scans
    assert got["lost_existence"][:, -1].mean() <= 0.05
    assert np.median(got["existence"][:, -1]) > 0.99


def test_track_decisions_latch_and_termination_comes_first():
    model = ExistenceModel(confirm=0.9, terminate=0.1)
    existence = np.array([[0.5, 0.95, 0.5, 0.2, 0.5],    # confirmed at scan 2, kept
                          [0.5, 0.05, 0.95, 0.99, 0.9],  # terminated first: never confirmed
                          [0.95, 0.5, 0.05, 0.5, 0.95],  # confirmed, then terminated
                          [0.5, 0.5, np.nan, np.nan, np.nan]])  # diverged: terminated
    confirmed, terminated = track_decisions(existence, model)
    np.testing.assert_array_equal(confirmed, [[0, 1, 1, 1, 1], [0, 0, 0, 0, 0],
                                              [1, 1, 1, 1, 1], [0, 0, 0, 0, 0]])
    np.testing.assert_array_equal(terminated, [[0, 0, 0, 0, 0], [0, 1, 1, 1, 1],
                                               [0, 0, 1, 1, 1], [0, 0, 1, 1, 1]])


def test_a_termination_threshold_above_confirmation_is_refused():
    p = EXPERIMENT.defaults()
    p.update({"ipda.terminate": 0.5, "ipda.confirm": 0.4})
    assert config_problem(p, {}, "grid")[0] == "ipda.terminate"
    p["ipda.terminate"] = 0.1
    key, text = config_problem(p, {"ipda.confirm": [0.9, 0.05]}, "grid")
    assert key == "ipda.confirm" and "0.05" in text
    assert config_problem(p, {"ipda.confirm": [0.9, 0.5]}, "grid") is None


def test_ipda_has_its_looks():
    assert set(IPDA_ALGORITHMS) <= set(EXPERIMENT.looks)


@pytest.mark.slow
def test_one_and_two_workers_write_the_same_rows(tmp_path):
    config = ROOT / "configs" / "ci" / "twin_sensor_ipda_ci.yaml"
    for workers in ("1", "2"):
        proc = trackfuse("run", config, "--out", tmp_path / workers, "--workers", workers,
                         "--no-progress", "--no-plots", timeout=600)
        assert proc.returncode == 0, proc.stderr
    one, two = (next((tmp_path / w).glob("*/*/trials.csv")) for w in ("1", "2"))
    assert one.read_bytes() == two.read_bytes()
    trials = pd.read_csv(one)
    assert set(EXISTENCE_METRICS) <= set(trials.columns)
    assert "ipda/mgekf" in set(trials["algorithm"])

"""An esm_radar config whose trials would all fail is refused before any trial runs."""

from __future__ import annotations

import itertools

import pytest
from conftest import trackfuse

from trackfuse.config import ConfigError, build
from trackfuse.experiments.esm_radar import EXPERIMENT
from trackfuse.seeding import trial_streams

LITERAL = "experiment: esm_radar\ntrials: 2\nparams:\n  alpha.index: literal\n"


def _raw(params: dict, sweep: dict | None = None, mode: str = "grid") -> dict:
    return {"experiment": "esm_radar", "params": params, "sweep": sweep or {},
            "sweep_mode": mode}


def test_validate_refuses_the_literal_index_with_the_default_chi2_alpha_max(write_config):
    """`validate` accepted `alpha.index: literal` (with `alpha.max_mode` left at `chi2`);
    `run` then failed every trial with a ValueError."""
    cfg = write_config(LITERAL)
    result = trackfuse("validate", cfg)
    assert result.returncode != 0, result.stdout
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr, result.stderr
    assert f"{cfg}: params.alpha.max_mode: 'chi2' needs alpha.index 'nis_tdoa'" in result.stderr
    assert "allowed with the 'literal' index: 'fixed'" in result.stderr
    assert "dynamic weights of improved" in result.stderr
    assert trackfuse("validate", cfg, "--set", "alpha.max_mode=fixed").returncode == 0


@pytest.mark.parametrize("index, max_mode, algorithms", list(itertools.product(
    ("nis_tdoa", "literal"), ("chi2", "fixed", "running_max"),
    (["improved"], ["improved_3f", "chi2"], ["traditional", "improved_static", "chi2_lrt"]))))
def test_the_check_refuses_exactly_the_configs_whose_trials_fail(index, max_mode, algorithms):
    params = {"alpha.index": index, "alpha.max_mode": max_mode, "algorithms": algorithms,
              "scan.count": 10}
    try:
        build(_raw(params), "cfg.yaml")
        refused = False
    except ConfigError:
        refused = True
    resolved = dict(EXPERIMENT.defaults(), **params)
    try:
        EXPERIMENT.run_trial(resolved, trial_streams(0, 0, 0))
        failed = False
    except ValueError:
        failed = True
    assert refused == failed
    assert failed == (index == "literal" and max_mode == "chi2" and algorithms[0] != "traditional")


def test_every_sweep_point_is_checked_and_named():
    zipped = {"alpha.index": ["nis_tdoa", "literal"], "alpha.max_mode": ["chi2", "chi2"]}
    with pytest.raises(ConfigError, match=r"^cfg\.yaml: sweep\.alpha\.max_mode: 'chi2' needs "
                                          r".*at the sweep point alpha\.index=literal, "
                                          r"alpha\.max_mode=chi2\)$"):
        build(_raw({}, zipped, "zip"), "cfg.yaml")
    build(_raw({}, dict(zipped, **{"alpha.max_mode": ["chi2", "fixed"]}), "zip"), "cfg.yaml")
    with pytest.raises(ConfigError, match=r"^cfg\.yaml: params\.alpha\.max_mode: .* at the "
                                          r"sweep point algorithms=\['improved'\]\)$"):
        build(_raw({"alpha.index": "literal"},
                   {"algorithms": [["chi2"], ["improved"]]}), "cfg.yaml")
    # a sweep that never runs a dynamic-weight algorithm with the literal index is fine
    build(_raw({"algorithms": ["chi2"]}, {"alpha.index": ["nis_tdoa", "literal"]}), "cfg.yaml")

"""A passive_assoc config asking the paper scene for more targets than it has is refused
before any trial runs (trackfuse/experiments/passive_assoc/checks.py)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import trackfuse

from trackfuse.association.passive_scene import scene_targets
from trackfuse.config import ConfigError, build

ELEVEN = "experiment: passive_assoc\ntrials: 2\nparams:\n  targets.n: 11\n"


def _raw(params: dict, sweep: dict | None = None) -> dict:
    return {"experiment": "passive_assoc", "params": params, "sweep": sweep or {}}


def test_validate_refuses_eleven_targets_of_the_paper_scene(write_config):
    """`validate` accepted `targets.n: 11` (the schema allows 2000 for random scenes); `run`
    then failed every trial with 'paper scene has 1..10 targets'."""
    cfg = write_config(ELEVEN)
    result = trackfuse("validate", cfg)
    assert result.returncode == 2, result.stdout
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr, result.stderr
    assert f"{cfg}: params.targets.n: got 11; allowed with scene.mode: paper: 1..10" \
        in result.stderr
    assert trackfuse("validate", cfg, "--set", "scene.mode=random").returncode == 0


@pytest.mark.parametrize("n", [1, 10, 11, 2000])
@pytest.mark.parametrize("mode", ["paper", "random"])
def test_the_check_refuses_exactly_the_scenes_that_cannot_be_built(n, mode):
    refused = mode == "paper" and n > 10
    try:
        scene_targets(n, mode, np.random.default_rng(0))
        buildable = True
    except ValueError:
        buildable = False
    assert buildable != refused
    for raw in (_raw({"scene.mode": mode, "targets.n": n}),
                _raw({"scene.mode": mode}, {"targets.n": [5, n]})):
        if refused:
            with pytest.raises(ConfigError, match="targets.n"):
                build(raw, "t.yaml")
        else:
            build(raw, "t.yaml")

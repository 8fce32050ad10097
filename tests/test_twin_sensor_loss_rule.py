"""The loss-window rule of paper 000's headline metric, pinned at its edge: a track off target
for exactly ``w - 1`` consecutive scans is kept, for ``w`` it is lost (angle rule and gate
rule alike), and once lost it stays lost."""

import numpy as np
import pytest

from trackfuse.experiments.twin_sensor import EXPERIMENT
from trackfuse.experiments.twin_sensor.model import (
    LossRules,
    build_scenario,
    score_estimates,
    simulate,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda_options import Estimates

START = 4  # the first off-target scan (0-based)


def _scored(off_scans: int, window: int, rule: str) -> np.ndarray:
    """The ``lost_<rule>`` flags ``(K,)`` of one trial whose estimate sits on the truth except
    for ``off_scans`` consecutive scans from :data:`START` (far off in angle for the angle
    rule, the target return outside every gate for the gate rule)."""
    sc = build_scenario(EXPERIMENT.defaults())
    b = simulate(sc, [trial_streams(3, 0, 0)])
    X = b.x_true[:, 1:].copy()  # (1, K, 6): exactly on target
    inside = np.ones((1, sc.K), dtype=bool)
    off = slice(START, START + off_scans)
    if rule == "angle":
        X[0, off, 2] += 50_000.0  # 50 km up: hundreds of noise sd in elevation
    else:
        inside[0, off] = False
    est = Estimates(X, np.broadcast_to(np.eye(6) * 1e6, (1, sc.K, 6, 6)).copy(),
                    np.zeros((1, sc.K, len(sc.R)), dtype=np.int64), inside)
    rules = LossRules(gate_window=window, angle_sigmas=3.0, angle_window=window,
                      nees_limit=1e9)
    return score_estimates(sc, b, est, rules)[f"lost_{rule}"][0]


@pytest.mark.parametrize("rule", ["angle", "gate"])
@pytest.mark.parametrize("window", [2, 3, 5])
def test_a_track_off_target_for_one_scan_less_than_the_window_is_kept(rule, window):
    assert not _scored(window - 1, window, rule).any()


@pytest.mark.parametrize("rule", ["angle", "gate"])
@pytest.mark.parametrize("window", [2, 3, 5])
def test_a_track_off_target_for_the_whole_window_is_lost_from_its_last_scan_on(rule, window):
    lost = _scored(window, window, rule)
    first = START + window - 1
    assert not lost[:first].any()
    assert lost[first:].all()  # permanent, though the estimate is back on target

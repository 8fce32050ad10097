"""The counting test and the SPRT as esm_radar algorithms (docs/papers/esm_radar.md, "Tests
over the track history"): they leave the other algorithms' numbers unchanged."""

import pytest

from trackfuse.experiments import get
from trackfuse.experiments.esm_radar.model import run_batch
from trackfuse.seeding import trial_streams

EXPERIMENT = get("esm_radar")


def rows(algorithms, trials=40, **changes):
    params = {**EXPERIMENT.defaults(), "algorithms": algorithms, **changes}
    table = run_batch(params, [trial_streams(3, 0, t) for t in range(trials)])
    return [r for t in range(trials) for r in table[t]]


def test_adding_the_history_tests_changes_no_other_algorithm():
    before = rows(["traditional", "improved", "chi2"])
    after = [r for r in rows(["traditional", "improved", "chi2", "counting", "sprt"])
             if r["algorithm"] not in ("counting", "sprt")]
    assert before == after


@pytest.mark.parametrize("name", ["counting", "sprt"])
def test_the_history_tests_find_the_radar_track_of_a_separated_target(name):
    found = rows([name], **{"target.separation": 200.0})
    assert all(r["correct"] == 1 and r["decided"] == 1 for r in found)


@pytest.mark.parametrize("name", ["counting", "sprt"])
def test_a_stricter_design_abstains_where_the_data_are_too_short(name):
    """Five scans cannot reach a 1e-6 false-association rate with p_false = 0.5."""
    short = rows([name], trials=5, **{"scan.count": 5, "history.p_false": 0.5,
                                      "history.alpha": 1e-6, "sprt.beta": 1e-6})
    assert all(r["decided"] == 0 and r["chosen"] == 0 for r in short)


def test_p_false_at_or_above_p_gate_is_refused():
    with pytest.raises(ValueError, match="history.p_false"):
        rows(["counting"], trials=1, **{"history.p_false": 0.99, "history.p_gate": 0.99})

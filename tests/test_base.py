"""trackfuse.experiments.base: the experiment declaration refuses metric names that the runner
writes itself (they would be silently dropped from summaries and comparisons)."""

from __future__ import annotations

import pytest

from trackfuse.experiments.base import Experiment, Metric


def _trial(params, streams):
    return [{"algorithm": "a", "x": 1.0}]


@pytest.mark.parametrize("name", ["error", "status", "trial", "point", "algorithm"])
def test_a_metric_named_after_a_runner_column_or_row_key_is_refused(name):
    with pytest.raises(ValueError, match="row columns"):
        Experiment(name="clash", title="t", params=(), run_trial=_trial,
                   metrics=(Metric(name, "1", "clashes"),))


def test_ordinary_metric_names_are_accepted():
    exp = Experiment(name="fine", title="t", params=(), run_trial=_trial,
                     metrics=(Metric("miss", "m", "fine", better="lower"),))
    assert exp.directions == {"miss": "lower"}

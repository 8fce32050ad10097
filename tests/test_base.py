"""trackfuse.experiments.base: the experiment declaration refuses metric names that the runner
writes itself (they would be silently dropped from summaries and comparisons), and a plugin's
declaration mistakes where they are made (helper-8's plugin audit)."""

from __future__ import annotations

import pytest

from trackfuse.experiments.base import Experiment, Metric, Param


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


@pytest.mark.parametrize(("param", "words"), [
    # `list` and `validate steps=x` crashed with an AttributeError traceback
    (dict(key="steps", default=5, doc="d", kind="int"), "kind='int'"),
    (dict(key="density", default=1.0, doc="d", low=50, high=0), "low=50 is above high=0"),
    (dict(key="pd", default=1.9, doc="d", low=0.0, high=1.0), "default 1.9 is outside"),
    (dict(key="mode", default="truthy", doc="d", kind=str, choices=("a", "b")),
     "default 'truthy' is not one of its choices"),
    # no kind: a float; `gate.enabled=false` was refused while `=0` was accepted
    (dict(key="gate.enabled", default=True, doc="d"), "default True is not a number"),
    (dict(key="names", default="a", doc="d", kind=list), "allowed: a non-empty list"),
    (dict(key="ops", default=[1.5], doc="d", kind=list, item_kind=str), "item_kind"),
])
def test_a_param_declaration_mistake_is_refused_where_it_is_made(param, words):
    with pytest.raises(ValueError, match=f"Param {param['key']!r}: .*") as caught:
        Param(**param)
    assert words in str(caught.value)


def test_an_experiment_declaration_mistake_is_refused_where_it_is_made():
    def declare(params=(), metrics=()):
        return Experiment(name="bad", title="t", params=params, run_trial=_trial,
                          metrics=metrics)

    x = Param("x", 1.0, "d")
    with pytest.raises(ValueError, match="parameters declared twice: x"):
        declare(params=(x, Param("x", 2.0, "d")))
    # a metric named like a swept parameter overwrote its column in trials.csv
    with pytest.raises(ValueError, match="or parameters"):
        declare(params=(x,), metrics=(Metric("x", "1", "clash"),))
    # 'smaller' was shown as "smaller is better" and left the metric ungated
    with pytest.raises(ValueError, match=r"metrics \['miss'\]: better must be"):
        declare(metrics=(Metric("miss", "1", "d", better="smaller"),))


@pytest.mark.parametrize("name", ["", " ", "two\nlines", "tab\there", " padded", 7])
def test_a_metric_name_that_cannot_head_a_csv_column_is_refused(name):
    """A metric named "" became 'Unnamed: 4' in the summary and escaped the regression
    gate; one with a line break left summary.csv empty: both exited 0."""
    with pytest.raises(ValueError, match="Metric .*: the name"):
        Metric(name, "1", "odd")


def test_a_row_key_or_a_metric_declared_twice_is_refused():
    with pytest.raises(ValueError, match="row keys"):
        Experiment(name="bad", title="t", params=(), run_trial=_trial, row_keys=("a\nb",))
    with pytest.raises(ValueError, match="metrics declared twice: x"):
        Experiment(name="bad", title="t", params=(), run_trial=_trial,
                   metrics=(Metric("x", "1", "d"), Metric("x", "m", "d")))

"""Rates a report derives from a run's 0/1 columns, drawn by the kit like any metric.

A :class:`Rate` is a 0/1 outcome of each row computed from the row's own columns (a false
association: decided but not correct), so ``summary.csv`` stays what the runner wrote:
:func:`with_rates` returns a view of a run whose summary has each rate's rows appended in
``summary.csv``'s long form (mean, 95 % Wilson interval, as the runner gives a binary
metric) and whose experiment declares each as a binary metric, so a
:class:`~trackfuse.reportkit.spec.Plot` names it as it names a metric of the run.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from trackfuse.experiments.base import Metric
from trackfuse.rundata import RunData, succeeded_rows
from trackfuse.stats import wilson_interval


@dataclass(frozen=True)
class Rate:
    """A 0/1 outcome per row: ``name`` (the metric name the plot uses), ``label`` (its axis
    label), ``of`` (the rows' frame to a 0/1 (or boolean) series, one value per row) and
    ``algorithms``: the only ones it is computed for (``()``: every one), so a rate that is
    0 by construction for the others (no decision of a method that always decides) draws
    no curve for them."""

    name: str
    label: str
    of: Callable[[pd.DataFrame], pd.Series]
    algorithms: tuple[str, ...] = ()


def rate_rows(trials: pd.DataFrame, keys: Sequence[str], rates: Sequence[Rate]
              ) -> pd.DataFrame:
    """Each rate's mean and 95 % Wilson interval per group of ``keys`` (``point``, the
    swept keys, the row keys), in ``summary.csv``'s long form (``metric``, ``n``,
    ``mean``, ``std``, ``ci_low``, ``ci_high``, ``interval``)."""
    keys = [k for k in keys if k in trials]
    out = []
    for rate in rates:
        rows = trials[trials["algorithm"].isin(rate.algorithms)] if rate.algorithms else trials
        if rows.empty:
            continue
        frame = rows[keys].assign(_hit=rate.of(rows).astype(float).to_numpy())
        grouped = frame.groupby(keys, sort=False)["_hit"].agg(["size", "sum", "std"])
        low, high = wilson_interval(grouped["sum"].to_numpy(), grouped["size"].to_numpy())
        out.append(grouped.reset_index().assign(
            metric=rate.name, n=grouped["size"].to_numpy(),
            mean=grouped["sum"].to_numpy() / grouped["size"].to_numpy(),
            ci_low=np.asarray(low), ci_high=np.asarray(high), interval="wilson",
        ).drop(columns=["size", "sum"]))
    return pd.concat(out, ignore_index=True) if out else pd.DataFrame()


def with_rates(run: RunData, rates: Sequence[Rate]) -> RunData:
    """A view of ``run`` (the same folder, read once) whose ``summary`` has the rows of
    ``rates`` appended (:func:`rate_rows` over the run's succeeded rows) and whose
    experiment declares each as a binary metric with its label."""
    keys = ["point", *run.sweep, *run.experiment.row_keys]
    extra = rate_rows(succeeded_rows(run.trials), list(dict.fromkeys(keys)), rates)
    metrics = tuple(Metric(r.name, "1", r.label, binary=True, label=r.label) for r in rates)
    view = copy.copy(run)
    view.__dict__["summary"] = pd.concat([run.summary, extra], ignore_index=True)
    view.__dict__["experiment"] = replace(run.experiment,
                                          metrics=(*run.experiment.metrics, *metrics))
    return view

"""Rates a report derives from a run's 0/1 columns (a false association: decided but not
correct), appended to a view of the run's summary as binary metrics, so a plot names them as
it names a metric; ``summary.csv`` itself stays as the runner wrote it."""

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
    """A 0/1 outcome per row: ``name`` and axis ``label``, ``of`` (rows -> 0/1 series), and
    ``algorithms`` it is computed for (``()``: every one), so a rate 0 by construction draws no
    curve."""

    name: str
    label: str
    of: Callable[[pd.DataFrame], pd.Series]
    algorithms: tuple[str, ...] = ()


def rate_rows(trials: pd.DataFrame, keys: Sequence[str], rates: Sequence[Rate]
              ) -> pd.DataFrame:
    """Each rate's mean and 95 % Wilson interval per group of ``keys``, as ``summary.csv`` rows."""
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
    """A view of ``run`` with ``rates`` appended to its summary and declared as binary metrics."""
    keys = ["point", *run.sweep, *run.experiment.row_keys]
    extra = rate_rows(succeeded_rows(run.trials), list(dict.fromkeys(keys)), rates)
    metrics = tuple(Metric(r.name, "1", r.label, binary=True, label=r.label) for r in rates)
    view = copy.copy(run)
    view.__dict__["summary"] = pd.concat([run.summary, extra], ignore_index=True)
    view.__dict__["experiment"] = replace(run.experiment,
                                          metrics=(*run.experiment.metrics, *metrics))
    return view

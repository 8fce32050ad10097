"""The contract between the runner and an experiment.

An experiment module is the only place that knows its science. It exposes one module-level
``EXPERIMENT = Experiment(...)`` that declares:

* ``params``: its parameter schema (flat dotted keys such as ``"clutter.mean"``) with
  defaults, units, bounds and choices. The runner validates configs against it and passes the
  resolved values to the trial functions as a flat ``dict[str, Any]``.
* ``run_trial(params, streams) -> list[dict]``: one Monte Carlo trial. ``streams`` is a
  :class:`~trackfuse.seeding.TrialStreams`: ``streams.common`` is the same generator at every
  sweep point (draw truth, initial estimates, measurement noise and algorithm randomness
  from it: common random numbers), ``streams.point`` is specific to the sweep point (draw
  what a swept parameter changes, such as clutter). The trial returns tidy rows, one per
  algorithm (and per value of any extra key in ``row_keys``, e.g. a scan index). Every
  algorithm in a trial sees the same simulated data (paired comparisons). A trial is a pure
  function of ``params`` and ``streams``.
* ``run_batch(params, streams) -> list[list[dict]]`` (optional): the same for a batch of
  trials, returning one row list per :class:`~trackfuse.seeding.TrialStreams`, in order.
  Each trial must draw its data from its own streams only, so the rows are identical to
  ``[run_trial(params, s) for s in streams]`` up to floating-point reassociation inside
  vectorized algebra.
* ``figures(trials, summary, config) -> dict[str, Figure]``: paper-style figures drawn from
  the saved CSV tables alone (no recomputation of trials). ``config`` is the resolved config
  as a plain dict (``params``, ``sweep``, ``trials``, ``seed``, ...).
* ``tables(trials, summary, config) -> dict[str, DataFrame]`` (optional): extra report tables
  written as CSV and Markdown.

Row columns: the runner adds ``point``, ``trial`` and the swept parameter values; the
experiment supplies ``algorithm``, the keys listed in ``row_keys`` and numeric metric columns.
Metrics listed in ``binary_metrics`` are 0/1 and get Wilson intervals in the summary; every
other numeric column gets a mean with a Student-t interval. Columns whose name ends in
``_time_s`` are wall/CPU-time measurements: the runner keeps them out of ``trials.csv`` (which
must be byte-identical for any worker count) and writes them to ``timings.csv`` instead.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from trackfuse.seeding import TrialStreams

Row = dict[str, Any]
Params = Mapping[str, Any]


@dataclass(frozen=True)
class Param:
    """One parameter of an experiment's schema.

    ``kind`` is one of ``float``, ``int``, ``bool``, ``str`` or ``list`` (a non-empty list of
    numbers, or of strings when ``choices`` is given); ``low``/``high`` are inclusive bounds
    for numbers (and for every element of a list); ``choices`` restricts strings (or numbers,
    or every element of a list) to a fixed set.
    """

    key: str
    default: Any
    doc: str
    unit: str = ""
    kind: type = float
    low: float | None = None
    high: float | None = None
    choices: tuple[Any, ...] | None = None


@dataclass(frozen=True)
class Experiment:
    """A registered experiment kind (see the module docstring for the contract)."""

    name: str
    title: str
    params: tuple[Param, ...]
    run_trial: Callable[[Params, TrialStreams], list[Row]]
    figures: Callable[[pd.DataFrame, pd.DataFrame, dict], dict[str, Any]] | None = None
    run_batch: Callable[[Params, Sequence[TrialStreams]], list[list[Row]]] | None = None
    tables: Callable[[pd.DataFrame, pd.DataFrame, dict], dict[str, pd.DataFrame]] | None = None
    row_keys: tuple[str, ...] = ("algorithm",)
    binary_metrics: tuple[str, ...] = ()
    batch_size: int = 25
    description: str = ""
    schema: dict[str, Param] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "schema", {p.key: p for p in self.params})

    def defaults(self) -> dict[str, Any]:
        """Every parameter at its default value, keyed by dotted name."""
        return {p.key: p.default for p in self.params}

    def run_trials(self, params: Params, streams: Sequence[TrialStreams]) -> list[list[Row]]:
        """Run a batch of trials, vectorized when the experiment offers ``run_batch``."""
        if self.run_batch is not None:
            return self.run_batch(params, streams)
        return [self.run_trial(params, s) for s in streams]

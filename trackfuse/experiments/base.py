"""The contract between the runner and an experiment: :class:`Experiment` and what it declares.

An experiment module exposes ``EXPERIMENT = Experiment(...)``: its parameters
(:class:`Param`), ``run_trial`` (one trial, a pure function of the params and its
streams) and optionally ``run_batch``, its row keys, metrics (:class:`Metric`) and figures
(:class:`FigureSpec`). The contract: ``docs/runner.md``, "The experiment contract", and
``docs/plugins.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from trackfuse.reportkit.looks import Look
from trackfuse.reportkit.spec import Plot
from trackfuse.rowformat import RUNNER_COLUMNS, TIME_SUFFIX

if TYPE_CHECKING:  # only for annotations: declaring an experiment loads no numpy
    from trackfuse.seeding import TrialStreams

Row = dict[str, Any]
Params = Mapping[str, Any]
ALGORITHMS_PARAM = "algorithms"
#: The kinds a :class:`Param` can be.
KINDS = (float, int, bool, str, list)


@dataclass(frozen=True)
class Param:
    """One parameter of an experiment's schema; the fields are described in ``docs/plugins.md``.

    ``draws=False`` marks a parameter that changes only what is computed, not what is simulated:
    points differing only in such keys share their point stream.
    """

    key: str
    default: Any
    doc: str
    unit: str = ""
    kind: type = float
    low: float | None = None
    high: float | None = None
    choices: tuple[Any, ...] | None = None
    length: int | None = None
    item_kind: type = float
    draws: bool = True
    #: What figures and tables call it (``"false returns per scan"``); ``""``: its key.
    label: str = ""
    #: Its short name in panel titles (``"N"``, ``"$p_m$"``); ``""``: the label.
    symbol: str = ""
    #: ``((value, word), ...)``: what figures call some of its values (``("table", "radar
    #: factors from their own noise")``); a value without a word is printed as it is.
    words: tuple[tuple[Any, str], ...] = ()

    def __post_init__(self) -> None:
        if problem := self._declaration_problem():
            raise ValueError(f"Param {self.key!r}: {problem}")

    def _declaration_problem(self) -> str | None:
        """What is wrong with this declaration (default against kind, bounds, choices), else
        ``None``."""
        if self.kind not in KINDS or self.item_kind not in (float, int):
            return (f"kind={self.kind!r}, item_kind={self.item_kind!r}; allowed: kind one of "
                    "float, int, bool, str, list and item_kind float or int (the types)")
        if self.low is not None and self.high is not None and self.low > self.high:
            return f"low={self.low} is above high={self.high}"
        if self.kind is list and not (isinstance(self.default, list) and self.default):
            return f"default {self.default!r}; allowed: a non-empty list for kind=list"
        for value in self.default if self.kind is list else [self.default]:
            if problem := self._value_problem(value):
                return f"default {value!r} {problem}"
        return None

    def _value_problem(self, value: Any) -> str | None:
        if self.choices is not None:
            return None if value in self.choices else "is not one of its choices"
        wanted = self.item_kind if self.kind is list else self.kind
        if wanted in (bool, str):
            return None if isinstance(value, wanted) else f"is not a {wanted.__name__}"
        if isinstance(value, bool) or not isinstance(value, int | float):
            return "is not a number (a flag takes kind=bool, a word kind=str)"
        if (self.low is not None and value < self.low) or \
                (self.high is not None and value > self.high):
            return f"is outside [{self.low}, {self.high}]"
        return None


Better = Literal["lower", "higher"]
Aggregate = Literal["mean", "rms"]
#: The values :attr:`Metric.aggregate` may take.
AGGREGATES = ("mean", "rms")


@dataclass(frozen=True)
class Metric:
    """One metric column of an experiment's rows; the fields are described in ``docs/plugins.md``.

    ``optional``: a column only some algorithms write (NaN on the others' rows), left out of a
    run without them.
    """

    name: str
    unit: str
    doc: str
    binary: bool = False
    better: Better | None = None
    categorical: bool = False
    bounds: tuple[float, float] | None = None
    aggregate: Aggregate = "mean"
    #: What figures and tables call it (``"tracks lost"``); ``""``: its name.
    label: str = ""
    optional: bool = False

    @property
    def percent(self) -> bool:
        """Shown in % (a 0/1 rate or a fraction): figures and tables alike."""
        return self.binary or self.bounds == FRACTION

    def __post_init__(self) -> None:
        if problem := column_name_problem(self.name):
            raise ValueError(f"Metric {self.name!r}: {problem}")
        if self.aggregate not in AGGREGATES:
            raise ValueError(f"Metric {self.name!r}: aggregate={self.aggregate!r}; allowed: "
                             f"{', '.join(AGGREGATES)}")
        if self.aggregate == "rms" and (self.binary or self.categorical):
            raise ValueError(f"Metric {self.name!r}: aggregate='rms' is for an error in a "
                             "unit; allowed: a metric neither binary nor categorical")


def column_name_problem(name: object) -> str | None:
    """What is wrong with ``name`` as a ``trials.csv`` column (empty, or not on one line), else
    ``None``."""
    if not isinstance(name, str) or not name.strip():
        return "the name is empty or not a string; allowed: a non-empty str"
    if not name.isprintable() or name != name.strip():
        return ("the name holds a line break, a control character or leading or trailing "
                "white space; allowed: printable text")
    return None


#: :attr:`Metric.bounds` of a fraction, and of a quantity that cannot be negative.
FRACTION, NON_NEGATIVE = (0.0, 1.0), (0.0, math.inf)


@dataclass(frozen=True)
class FigureSpec:
    """One report figure: a one-line ``caption``, the ``paper`` figure it stands for (``""``: an
    extension), and ``plot``, the figure as data (``None``: the report module draws it).
    """

    caption: str
    paper: str = ""
    plot: Plot | None = None


@dataclass(frozen=True)
class Experiment:
    """A registered experiment kind (the contract: module docstring)."""

    name: str
    title: str
    params: tuple[Param, ...]
    run_trial: Callable[[Params, TrialStreams], list[Row]]
    metrics: tuple[Metric, ...] = ()
    report: str | None = None
    figures: Mapping[str, FigureSpec] = field(default_factory=dict, compare=False)
    run_batch: Callable[[Params, Sequence[TrialStreams]], list[list[Row]]] | None = None
    row_keys: tuple[str, ...] = ("algorithm",)
    batch_size: int = 25
    #: Optional last check of a config: ``check(params, sweep, sweep_mode)`` returns
    #: ``(key, problem)`` for a config that cannot run (a missing optional dependency, a
    #: degenerate geometry), else ``None``.
    check: Callable[[Params, Mapping[str, list[Any]], str], tuple[str, str] | None] | None = None
    #: Modules the process pool's fork server imports before it forks workers (a module
    #: that loads a compiled kernel, say), so every worker starts with them in memory.
    preload: tuple[str, ...] = ()
    #: Algorithm name -> how figures draw it and call it (:class:`Look`).
    looks: Mapping[str, Look] = field(default_factory=dict, compare=False)
    #: Row key -> ``(label, unit)`` in figures (``{"ops": ("genetic operations", "count")}``).
    row_labels: Mapping[str, tuple[str, str]] = field(default_factory=dict, compare=False)
    schema: dict[str, Param] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "schema", {p.key: p for p in self.params})
        if problem := self._declaration_problem():
            raise ValueError(f"experiment {self.name!r}: {problem}")

    def _declaration_problem(self) -> str | None:
        """What is wrong with the declaration (a duplicate parameter, a metric named like a runner
        column, row key or parameter, a bad ``better``), else ``None``.
        """
        if len(self.schema) < len(self.params):
            twice = sorted({p.key for p in self.params if
                            sum(q.key == p.key for q in self.params) > 1})
            return f"parameters declared twice: {', '.join(twice)}"
        if odd := [k for k in self.row_keys if column_name_problem(k)]:
            return f"row keys {odd}: {column_name_problem(odd[0])}"
        if twice := sorted({m.name for m in self.metrics
                            if sum(n.name == m.name for n in self.metrics) > 1}):
            return f"metrics declared twice: {', '.join(twice)}"
        taken = [m.name for m in self.metrics
                 if m.name in (*RUNNER_COLUMNS, *self.row_keys, *self.schema)]
        if taken:
            return (f"metric names {taken} are row columns of the runner {RUNNER_COLUMNS}, "
                    f"row keys {self.row_keys} or parameters")
        if odd := [m.name for m in self.metrics if m.better not in (None, "lower", "higher")]:
            return f"metrics {odd}: better must be 'lower', 'higher' or None"
        return None

    @property
    def binary_metrics(self) -> tuple[str, ...]:
        """Names of the 0/1 metrics (Wilson intervals)."""
        return tuple(m.name for m in self.metrics if m.binary)

    @property
    def metric_bounds(self) -> dict[str, tuple[float, float]]:
        """``{name: (low, high)}`` of the metrics with :attr:`Metric.bounds`."""
        return {m.name: m.bounds for m in self.metrics if m.bounds is not None}

    @property
    def rms_metrics(self) -> tuple[str, ...]:
        """Names of the metrics summarized as a root mean square (:attr:`Metric.aggregate`)."""
        return tuple(m.name for m in self.metrics if m.aggregate == "rms")

    @property
    def categorical_metrics(self) -> tuple[str, ...]:
        """Names of the metrics that are labels, not quantities (never averaged)."""
        return tuple(m.name for m in self.metrics if m.categorical)

    @property
    def directions(self) -> dict[str, Better]:
        """Metric name -> ``"lower"`` or ``"higher"`` for every metric with a direction."""
        return {m.name: m.better for m in self.metrics if m.better is not None}

    @property
    def drawing(self) -> tuple[str, ...]:
        """Keys of the parameters that change what is simulated (:attr:`Param.draws`)."""
        return tuple(p.key for p in self.params if p.draws)

    @property
    def algorithms(self) -> tuple[str, ...]:
        """Every algorithm a config may choose: the choices of the ``algorithms`` parameter
        (``()`` when the experiment has none)."""
        param = self.schema.get(ALGORITHMS_PARAM)
        return tuple(str(c) for c in param.choices) if param and param.choices else ()

    def missing_metrics(self, columns: Collection[str]) -> list[str]:
        """Declared metrics absent from ``columns``, except timings (``*_time_s``) and optional
        ones."""
        return [m.name for m in self.metrics if m.name not in columns
                and not m.name.endswith(TIME_SUFFIX) and not m.optional]

    def defaults(self) -> dict[str, Any]:
        """Every parameter at its default value, keyed by dotted name."""
        return {p.key: p.default for p in self.params}

    def run_trials(self, params: Params, streams: Sequence[TrialStreams]) -> list[list[Row]]:
        """Run a batch of trials, vectorized when the experiment offers ``run_batch``."""
        if self.run_batch is not None:
            return self.run_batch(params, streams)
        return [self.run_trial(params, s) for s in streams]

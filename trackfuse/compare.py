"""Compare two runs of one experiment cell by cell, and gate regressions for CI.

A cell is one sweep point (matched by its swept values), one value of the row keys and one
metric; for each cell both runs have: both means, ``new - base`` with its 95 % interval, a
p-value and the test. Runs of one root seed are paired by trial index (paired t; Newcombe's
paired score interval and exact McNemar for 0/1 metrics), others unpaired (Welch; Newcombe's
hybrid score interval and 'N-1' chi-square). A metric with a declared direction regresses
when its one-sided, Bonferroni-adjusted bound lies beyond the tolerance on the bad side;
:meth:`Comparison.gate_failure` says why a gate fails (a regression, a base cell the new run
lacks, nothing compared). Users' view: ``docs/statistics.md`` and ``docs/outputs.md``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from trackfuse.config import did_you_mean
from trackfuse.rowformat import RUNNER_COLUMNS
from trackfuse.rundata import RunData, succeeded_rows
from trackfuse.stats import (
    PairedBinary,
    no_spread_p,
    paired_t_p,
    proportion_difference_interval,
    t_interval,
    two_proportion_p,
    welch_interval,
)

BETTER = ("lower", "higher")
#: The value :func:`config_differences` gives a swept key's ``params`` entry.
SWEPT = "(swept)"


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare_trials`.

    ``cells``: one row per cell with the key columns, ``metric``, ``better``, ``n_base``,
    ``n_new``, ``base``, ``new``, ``diff``, ``ci_low``, ``ci_high`` (95 %), ``p_value``,
    ``test`` and ``verdict`` (``regression``, ``improvement``, ``no significant change``,
    or for ungated metrics ``differs`` / ``no significant difference``).
    ``paired``: whether trials were paired. ``gated``: number of gated cells.
    ``alpha``: the family-wise false-alarm level of the gate. ``only_base_cells``,
    ``only_new_cells``: the key columns and ``metric`` of the cells of one run that were not
    compared (a sweep point, row key or metric the other run lacks)."""

    cells: pd.DataFrame
    paired: bool
    gated: int
    alpha: float
    only_base_cells: pd.DataFrame
    only_new_cells: pd.DataFrame
    #: How the trials were (or were not) paired, in words (set by :func:`compare_runs`).
    pairing: str = ""
    #: ``(key, base value, new value)`` for each config value that differs (``compare_runs``).
    config_differences: tuple[tuple[str, object, object], ...] = ()

    @property
    def regressions(self) -> pd.DataFrame:
        """The cells whose verdict is ``regression``."""
        return self.cells[self.cells["verdict"] == "regression"]

    @property
    def only_base(self) -> int:
        """Number of cells of the base run missing from the comparison."""
        return len(self.only_base_cells)

    @property
    def only_new(self) -> int:
        """Number of cells of the new run missing from the comparison."""
        return len(self.only_new_cells)

    def gate_failure(self) -> str | None:
        """Why the regression gate fails, in one line, or ``None`` when it passes.

        It fails on a regression, on any cell of the base run left out (the new run no
        longer produces it), when no cell was compared and when no compared cell is gated."""
        names = list(self.only_base_cells.columns)
        reasons = []
        if self.cells.empty:
            reasons.append("nothing compared (the runs share no cell)")
        elif not self.gated:
            reasons.append(f"nothing gated (no metric of the {len(self.cells)} compared cells "
                           "is declared better lower or higher)")
        if len(self.regressions):
            reasons.append(f"{len(self.regressions)} regressions, e.g. "
                           f"{cell_name(self.regressions.iloc[0], names)}")
        if self.only_base:
            reasons.append(f"{self.only_base} cells of BASE missing from NEW, e.g. "
                           f"{cell_name(self.only_base_cells.iloc[0], names)}")
        return "; ".join(reasons) or None

    def bottom_line(self) -> str:
        """The comparison in one line: the gate's verdicts (regressions, improvements) over
        the gated cells, then how many ungated cells differ at their own 95 %."""
        if self.cells.empty:
            return "bottom line: nothing compared (the runs share no cell)"
        verdicts = self.cells["verdict"].value_counts()
        regressions, improvements = verdicts.get("regression", 0), verdicts.get("improvement", 0)
        if not self.gated:
            gate = "nothing gated (no metric declares a better direction)"
        elif regressions or improvements:
            gate = (f"{_count(regressions, 'regression')} and "
                    f"{_count(improvements, 'improvement')} in {self.gated} gated cells")
        else:
            gate = f"no significant change in any of the {self.gated} gated cells"
        ungated = len(self.cells) - self.gated
        differ = f"; {verdicts.get('differs', 0)} of {ungated} cells not gated differ" \
            if ungated else ""
        missing = f"; {self.only_base} cells of BASE missing from NEW" if self.only_base else ""
        return f"bottom line: {gate}{differ}{missing}"


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def cell_name(row: pd.Series, names: Sequence[str]) -> str:
    """``key=value, ..., metric=name``: a cell named by its ``names`` columns."""
    return ", ".join(f"{key}={row[key]}" for key in names)


def metric_columns(frame: pd.DataFrame, keys: Sequence[str]) -> list[str]:
    """Numeric columns of ``frame`` that are neither keys nor bookkeeping columns."""
    return [c for c in frame.columns if c not in keys and c not in RUNNER_COLUMNS
            and pd.api.types.is_numeric_dtype(frame[c])]


def _long(frame: pd.DataFrame, keys: Sequence[str], metrics: Sequence[str]) -> pd.DataFrame:
    """Rows of finished trials melted to ``[*keys, trial, metric, value]``. The metric
    columns are melted under their positions, so that a metric may be called ``value`` or
    ``metric`` (pandas refuses a melted column named like a column of the frame)."""
    rows = succeeded_rows(frame)[[*keys, "trial", *metrics]]
    rows.columns = [*keys, "trial", *range(len(metrics))]
    long = rows.melt(id_vars=[*keys, "trial"], var_name="metric", value_name="value")
    long["metric"] = np.asarray(list(metrics), dtype=object)[long["metric"].to_numpy(int)]
    return long.dropna(subset=["value"])


def _paired_cells(base: pd.DataFrame, new: pd.DataFrame, keys: list[str],
                  binary: set[str], level: float) -> pd.DataFrame:
    merged = base.merge(new, on=[*keys, "trial", "metric"], suffixes=("_base", "_new"))
    merged["d"] = merged["value_new"] - merged["value_base"]
    merged["both"] = (merged["value_base"] == 1) & (merged["value_new"] == 1)
    g = merged.groupby([*keys, "metric"], sort=False, dropna=False).agg(
        n=("d", "size"), base=("value_base", "mean"), new=("value_new", "mean"),
        diff=("d", "mean"), sd=("d", "std"), k1=("value_base", "sum"),
        k2=("value_new", "sum"), both=("both", "sum")).reset_index()
    is_bin = g["metric"].isin(binary).to_numpy()
    t_low, t_high = t_interval(g["diff"], g["sd"], g["n"], level)
    t_p = paired_t_p(g["diff"], g["sd"], g["n"])
    b = PairedBinary.from_counts(g["n"], g["k1"], g["k2"], g["both"], level)
    g["n_base"] = g["n_new"] = g["n"]
    g["ci_low"] = np.where(is_bin, b.low, t_low)
    g["ci_high"] = np.where(is_bin, b.high, t_high)
    g["p_value"] = np.where(is_bin, b.p, t_p)
    g["test"] = np.where(is_bin, "paired Newcombe / exact McNemar", "paired t")
    flat = ~is_bin & (g["sd"] == 0).to_numpy() & (g["diff"] != 0).to_numpy()
    return _without_spread(g, flat, no_spread_p(g["n"]), level, "sign test")


def _unpaired_cells(base: pd.DataFrame, new: pd.DataFrame, keys: list[str],
                    binary: set[str], level: float) -> pd.DataFrame:
    def agg(frame: pd.DataFrame) -> pd.DataFrame:
        return frame.groupby([*keys, "metric"], sort=False, dropna=False)["value"].agg(
            ["size", "mean", "std", "sum"])

    g = agg(base).merge(agg(new), how="inner", left_index=True, right_index=True,
                        suffixes=("_b", "_n")).reset_index()
    is_bin = g["metric"].isin(binary).to_numpy()
    w_low, w_high, w_p = welch_interval(g["mean_b"], g["std_b"], g["size_b"], g["mean_n"],
                                        g["std_n"], g["size_n"], level)
    b_low, b_high = proportion_difference_interval(g["sum_b"], g["size_b"], g["sum_n"],
                                                   g["size_n"], level=level)
    b_p = two_proportion_p(g["sum_b"], g["size_b"], g["sum_n"], g["size_n"])
    out = g[[*keys, "metric"]].copy()
    out["n_base"], out["n_new"] = g["size_b"], g["size_n"]
    out["base"], out["new"] = g["mean_b"], g["mean_n"]
    out["diff"] = g["mean_n"] - g["mean_b"]
    out["ci_low"] = np.where(is_bin, b_low, w_low)
    out["ci_high"] = np.where(is_bin, b_high, w_high)
    out["p_value"] = np.where(is_bin, b_p, w_p)
    out["test"] = np.where(is_bin, "Newcombe / N-1 chi-square", "Welch t")
    flat = ~is_bin & (g["std_b"] == 0).to_numpy() & (g["std_n"] == 0).to_numpy() \
        & (out["diff"] != 0).to_numpy()
    return _without_spread(out, flat, no_spread_p(g["size_b"], g["size_n"]), level,
                           "permutation test")


def _without_spread(cells: pd.DataFrame, flat: np.ndarray, p_exact: np.ndarray, level: float,
                    test: str) -> pd.DataFrame:
    """``cells`` where the ``flat`` ones (every difference, or every value of each run,
    equal and the difference not 0: a t interval of zero width and p 0) read the exact test
    ``test`` instead: its p-value ``p_exact``, and the difference as its interval only if
    that p reaches ``1 - level``, else no bound at all (two trials of each cannot show a
    difference at 95 %: the most extreme outcome has p 1/3)."""
    shown = flat & (p_exact <= 1 - level)
    for end, unbounded in (("ci_low", -np.inf), ("ci_high", np.inf)):
        cells[end] = np.where(shown, cells["diff"], np.where(flat, unbounded, cells[end]))
    cells["p_value"] = np.where(flat, p_exact, cells["p_value"])
    cells["test"] = np.where(flat, f"{test} (no spread)", cells["test"])
    return cells


def compare_trials(base: pd.DataFrame, new: pd.DataFrame, keys: Sequence[str],
                   binary: Sequence[str] = (), better: Mapping[str, str] | None = None,
                   paired: bool = True, tolerance: Mapping[str, float] | None = None,
                   alpha: float = 0.05, metrics: Sequence[str] | None = None,
                   family_wise: bool = True, skip: Sequence[str] = ()) -> Comparison:
    """Compare the trial rows of two runs (see the module docstring).

    Parameters: ``base``, ``new`` ``trials.csv`` frames of the two runs. ``keys`` columns that
    identify a cell besides the metric: the swept keys and the experiment's row keys (not ``point``:
    points are matched by their swept values). ``binary`` 0/1 metrics. ``better`` metric ->
    ``"lower"`` or ``"higher"`` (gated metrics). ``paired`` pair trials by index (same root seed) or
    treat the runs as independent. ``tolerance`` metric -> the worsening (in the metric's unit) that
    is accepted; default 0. ``alpha`` family-wise false-alarm level of the regression gate.
    ``metrics`` compare only these metrics (default: every metric present in both runs).
    ``family_wise`` Bonferroni-adjust the gate over the gated cells (default); ``False`` gates every
    cell at ``alpha`` on its own. ``skip`` columns that are labels, not quantities (categorical
    metrics): never compared."""
    keys, binary, better = list(keys), set(binary), dict(better or {})
    tolerance = dict(tolerance or {})
    wanted = None if metrics is None else set(metrics)

    def compared_metrics(frame: pd.DataFrame) -> list[str]:
        return [m for m in metric_columns(frame, keys) if m not in skip
                and (wanted is None or m in wanted)]

    b_long = _long(base, keys, compared_metrics(base))
    n_long = _long(new, keys, compared_metrics(new))
    cells_at = _paired_cells if paired else _unpaired_cells
    cells = cells_at(b_long, n_long, keys, binary, 0.95)
    cells["better"] = cells["metric"].map(lambda metric: better.get(metric, ""))
    gated = cells["better"].isin(BETTER).to_numpy()
    m = int(gated.sum())
    # one-sided bounds at 1 - alpha/m are the ends of the two-sided 1 - 2 alpha/m interval
    per_cell = alpha / max(m, 1) if family_wise else alpha
    gate = cells_at(b_long, n_long, keys, binary, 1 - 2 * per_cell)
    low, high = gate["ci_low"].to_numpy(), gate["ci_high"].to_numpy()
    tol = cells["metric"].map(tolerance).fillna(0.0).to_numpy(float)
    higher = (cells["better"] == "higher").to_numpy()
    worse = np.where(higher, high < -tol, low > tol)
    improved = np.where(higher, low > 0, high < 0)
    differs = (cells["ci_low"] > 0) | (cells["ci_high"] < 0)
    cells["verdict"] = np.select(
        [gated & worse, gated & improved, gated, differs],
        ["regression", "improvement", "no significant change", "differs"],
        "no significant difference")
    columns = [*keys, "metric", "better", "n_base", "n_new", "base", "new", "diff", "ci_low",
               "ci_high", "p_value", "test", "verdict"]
    return Comparison(cells[columns].reset_index(drop=True), paired, m, alpha,
                      _left_out(b_long, cells, keys), _left_out(n_long, cells, keys))


def _left_out(long: pd.DataFrame, cells: pd.DataFrame, keys: list[str]) -> pd.DataFrame:
    """The cells (key columns and ``metric``) of one run's long rows that ``cells`` lacks."""
    names = [*keys, "metric"]
    present = long[names].drop_duplicates()
    found = present.merge(cells[names].drop_duplicates(), on=names, how="left",
                          indicator=True)
    return found.loc[found["_merge"] == "left_only", names].reset_index(drop=True)


def compare_runs(base: RunData, new: RunData, tolerance: Mapping[str, float] | None = None,
                 alpha: float = 0.05, family_wise: bool = True,
                 metrics: Sequence[str] | None = None,
                 algorithms: Sequence[str] | None = None) -> Comparison:
    """Compare two complete runs of the same experiment (see :func:`compare_trials`).

    Cells are keyed by the keys either run sweeps and the experiment's row keys: a key one
    run sweeps and the other fixes (``--set clutter.mean=5``) is compared at the fixed value
    (:func:`_with_fixed_keys`). 0/1 metrics and the direction of each metric come from
    ``Experiment.metrics``; a metric summarized as a root mean square is compared on its
    per-trial squares (``base``, ``new``, ``diff`` in the unit squared: the RMS is worse
    exactly when the mean square is). Trials are paired when both runs share the root seed, on the
    trial indices both have (:func:`_pairing`). ``metrics``, ``algorithms``: compare only
    these (default all); the gate's family is then the cells kept. Raises ``ValueError`` for
    runs of different experiments, a key one run sweeps that the other fixes to a list or a
    mapping, or a metric or algorithm neither run has."""
    if base.config["experiment"] != new.config["experiment"]:
        raise ValueError(f"different experiments: {base.config['experiment']!r} and "
                         f"{new.config['experiment']!r}")
    keys = [*dict.fromkeys([*base.sweep, *new.sweep])]
    if base.path.resolve() == new.path.resolve():
        raise ValueError(f"{base.path}: BASE and NEW are the same run; compare needs two runs")
    for run in (base, new):
        if succeeded_rows(run.trials).empty:
            raise ValueError(f"{run.path}: every trial of the run failed "
                             f"({run.manifest.get('trials_failed', '?')} of "
                             f"{run.manifest.get('trials_total', '?')}): nothing to compare")
        points = [repr([p[k] for k in run.sweep]) for p in run.points]
        if len(set(points)) < len(points):
            raise ValueError(f"{run.path}: a sweep point comes twice (a run of a version "
                             "that allowed it); compare needs distinct points")
    experiment = base.experiment
    names = [m.name for m in experiment.metrics if not m.categorical]
    for metric, value in (tolerance or {}).items():
        if metric not in names:
            raise ValueError(f"--tolerance: unknown metric {metric!r}"
                             f"{did_you_mean(metric, names)}; allowed: {', '.join(names)}")
        if not 0 <= value < math.inf:
            raise ValueError(f"--tolerance: got {metric}={value}; allowed: a finite number "
                             ">= 0 (in the metric's unit)")
    _check_chosen("--metric", metrics, names)
    frames = [_with_fixed_keys(run, keys, role) for run, role in ((base, "BASE"), (new, "NEW"))]
    if algorithms is not None:
        frames = _of_algorithms(frames, algorithms)
    if rms := [m for m in experiment.rms_metrics if m in names]:  # compared as mean squares
        frames = [frame.assign(**{m: frame[m] ** 2 for m in rms if m in frame})
                  for frame in frames]
    paired, pairing = _pairing(base.config, new.config)
    result = compare_trials(*frames, [*keys, *experiment.row_keys],
                            binary=experiment.binary_metrics, better=experiment.directions,
                            paired=paired, tolerance=tolerance, alpha=alpha, metrics=metrics,
                            family_wise=family_wise, skip=experiment.categorical_metrics)
    squared = result.cells["metric"].isin(rms)
    result.cells.loc[squared, "test"] = result.cells.loc[squared, "test"] + " on e^2"
    return dataclasses.replace(result, pairing=pairing, config_differences=tuple(
        config_differences(base.config, new.config)))


def _check_chosen(option: str, chosen: Sequence[str] | None, allowed: Sequence[str]) -> None:
    """Raise ``ValueError`` naming ``option`` for a chosen name not in ``allowed``."""
    for name in chosen or ():
        if name not in allowed:
            raise ValueError(f"{option}: unknown {option[2:]} {name!r}"
                             f"{did_you_mean(name, allowed)}; allowed: {', '.join(allowed)}")


def _of_algorithms(frames: list[pd.DataFrame], algorithms: Sequence[str]
                   ) -> list[pd.DataFrame]:
    """The rows of ``frames`` (both runs' trials) whose ``algorithm`` is one of
    ``algorithms``; ``ValueError`` for an algorithm neither run has."""
    if any("algorithm" not in frame for frame in frames):
        raise ValueError("--algorithm: the runs' rows have no algorithm column; allowed: "
                         "compare without --algorithm")
    present = sorted({str(a) for frame in frames for a in frame["algorithm"].dropna()})
    _check_chosen("--algorithm", algorithms, present)
    return [frame[frame["algorithm"].astype(str).isin(list(algorithms))] for frame in frames]


def _with_fixed_keys(run: RunData, keys: Sequence[str], role: str) -> pd.DataFrame:
    """``run``'s trials with a column for each of ``keys`` it does not sweep, holding the value
    its config fixes (one sweep point of the other run's axis)."""
    trials = run.trials
    for key in keys:
        if key in run.sweep:
            continue
        if key not in run.params:
            raise ValueError(f"the other run sweeps {key}, a parameter {role}'s experiment "
                             "does not have (a run of other code?); allowed: keys of both")
        value = run.params[key]
        if value is None or isinstance(value, (list, dict)):
            raise ValueError(f"the other run sweeps {key}, which {role} fixes to "
                             f"{value!r}; allowed: a key fixed to one number or word, or swept "
                             "by both (narrow an axis with --sweep KEY=V1,V2)")
        trials = trials.assign(**{key: value})
    return trials


def _pairing(base: Mapping, new: Mapping) -> tuple[bool, str]:
    """Whether trials of the resolved configs ``base`` and ``new`` pair by index, and how: with
    one root seed trial ``t`` has the same common draw in both runs (its point stream only where
    both give the point the same draw point); with two seeds no trial pairs
    (``docs/statistics.md``)."""
    seeds, trials = (base.get("seed"), new.get("seed")), (base.get("trials"), new.get("trials"))
    if seeds[0] != seeds[1]:
        return False, f"(the seeds differ, {seeds[0]} and {seeds[1]}: no trial is shared)"
    if trials[0] == trials[1]:
        return True, f"trial by trial (same seed {seeds[0]}, {trials[0]} trials per point)"
    return True, (f"on the trial indices both runs have (same seed {seeds[0]}; {trials[0]} "
                  f"trials per point in BASE, {trials[1]} in NEW: the others are left out)")


def _flat(config: Mapping, prefix: str = "") -> dict[str, object]:
    """A resolved config as ``{dotted path: value}`` (``params.clutter.mean``, ``trials``);
    an empty mapping (``sweep: {}``) has no values."""
    flat: dict[str, object] = {}
    for key, value in config.items():
        if isinstance(value, Mapping):
            flat.update(_flat(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def config_differences(base: Mapping, new: Mapping) -> list[tuple[str, object, object]]:
    """``(key, base value, new value)`` for every value of two resolved configs that differs
    (``None`` where a config lacks the key), in the order of ``base`` then ``new``. The
    ``params`` value of a swept key is no point's value: it reads :data:`SWEPT` (the
    ``sweep`` entries give the values), so a key both runs sweep is left out."""
    b, n = (_flat({**config, "params": {**(config.get("params") or {}), **dict.fromkeys(
        config.get("sweep") or {}, SWEPT)}}) for config in (base, new))
    return [(key, b.get(key), n.get(key)) for key in dict.fromkeys([*b, *n])
            if b.get(key) != n.get(key) or (key in b) != (key in n)]

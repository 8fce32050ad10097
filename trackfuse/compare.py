"""Compare two runs of one experiment cell by cell, and gate regressions for CI.

A cell is one sweep point, one value of the row keys and one metric: both means,
``new - base`` with its 95 % interval, a p-value and the test (paired by trial index with
one root seed, else unpaired). Tests, the Bonferroni-adjusted one-sided gate and the
verdicts: ``docs/statistics.md``; the files: ``docs/outputs.md``.
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

    ``cells``: one row per cell (keys, ``metric``, ``better``, counts, ``base``, ``new``,
    ``diff``, ``ci_low``, ``ci_high``, ``p_value``, ``test``, ``verdict``); ``paired``;
    ``gated`` cell count; ``alpha`` the gate's family-wise level; ``only_base_cells``,
    ``only_new_cells`` the cells one run lacks. Verdicts: ``regression``, ``improvement``,
    ``no significant change``; ungated, ``differs`` or ``no significant difference``.
    """

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
        """Why the gate fails, in one line, or ``None``: a regression, a base cell left out, no cell
        compared, or no compared cell gated.
        """
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
        """The gate's verdicts over the gated cells, then how many ungated cells differ, in one
        line."""
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
    """Finished trials melted to ``[*keys, trial, metric, value]`` (by position, so a metric may be
    called ``value`` or ``metric``).
    """
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
    """``cells`` where the ``flat`` ones (no spread, nonzero difference: t reads p 0) read the exact
    ``test`` with ``p_exact``; the difference is their interval only if that p reaches
    ``1 - level``.
    """
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
    """Compare the trial rows of two runs cell by cell: a :class:`Comparison`.

    ``keys`` identify a cell besides the metric (swept keys and row keys, not ``point``);
    ``better`` gives gated metrics' directions; ``tolerance`` the accepted worsening per metric
    (its unit); ``alpha`` the gate's family-wise level (``family_wise=False``: per cell);
    ``skip`` label columns never compared.
    """
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
    """Compare two complete runs of the same experiment (:func:`compare_trials`).

    A key one run sweeps and the other fixes is compared at the fixed value; RMS metrics are
    compared on their per-trial squares; trials pair when the root seeds match.
    ValueError for different experiments, a fixed list or mapping against a sweep, or a metric
    or algorithm neither run has.
    """
    if base.config["experiment"] != new.config["experiment"]:
        raise ValueError(f"different experiments: {base.config['experiment']!r} and "
                         f"{new.config['experiment']!r}")
    keys = [*dict.fromkeys([*base.sweep, *new.sweep])]
    if base.path.resolve() == new.path.resolve():
        raise ValueError(f"{base.path}: BASE and NEW are the same run; compare needs two runs")
    for run in (base, new):
        if succeeded_rows(run.trials).empty:
            raise ValueError(f"{run.path}: every trial of the run failed "
                             f"({_or_unknown(run.manifest.trials_failed)} of "
                             f"{_or_unknown(run.manifest.trials_total)}): nothing to compare")
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
    """Rows of ``frames`` of the chosen ``algorithms``; ValueError for one neither has."""
    if any("algorithm" not in frame for frame in frames):
        raise ValueError("--algorithm: the runs' rows have no algorithm column; allowed: "
                         "compare without --algorithm")
    present = sorted({str(a) for frame in frames for a in frame["algorithm"].dropna()})
    _check_chosen("--algorithm", algorithms, present)
    return [frame[frame["algorithm"].astype(str).isin(list(algorithms))] for frame in frames]


def _with_fixed_keys(run: RunData, keys: Sequence[str], role: str) -> pd.DataFrame:
    """``run``'s trials with a column holding its fixed value for each of ``keys`` it does not
    sweep."""
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
    """Whether trials of configs ``base`` and ``new`` pair by index, and why (one root seed: the
    same common draws; ``docs/statistics.md``).
    """
    seeds, trials = (base.get("seed"), new.get("seed")), (base.get("trials"), new.get("trials"))
    if seeds[0] != seeds[1]:
        return False, f"(the seeds differ, {seeds[0]} and {seeds[1]}: no trial is shared)"
    if trials[0] == trials[1]:
        return True, f"trial by trial (same seed {seeds[0]}, {trials[0]} trials per point)"
    return True, (f"on the trial indices both runs have (same seed {seeds[0]}; {trials[0]} "
                  f"trials per point in BASE, {trials[1]} in NEW: the others are left out)")


def _flat(config: Mapping, prefix: str = "") -> dict[str, object]:
    """A resolved config as ``{dotted path: value}``; an empty mapping has no values."""
    flat: dict[str, object] = {}
    for key, value in config.items():
        if isinstance(value, Mapping):
            flat.update(_flat(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def config_differences(base: Mapping, new: Mapping) -> list[tuple[str, object, object]]:
    """``(key, base value, new value)`` for every differing value (``None`` where absent), base
    order first; a key both runs sweep is left out (its ``params`` value reads :data:`SWEPT`).
    """
    b, n = (_flat({**config, "params": {**(config.get("params") or {}), **dict.fromkeys(
        config.get("sweep") or {}, SWEPT)}}) for config in (base, new))
    return [(key, b.get(key), n.get(key)) for key in dict.fromkeys([*b, *n])
            if b.get(key) != n.get(key) or (key in b) != (key in n)]


def _or_unknown(count: int | None) -> str:
    """A count a manifest records, or ``?`` where it does not."""
    return "?" if count is None else str(count)

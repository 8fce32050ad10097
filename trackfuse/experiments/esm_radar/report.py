"""Figures and report tables of ``esm_radar`` (paper 001, ESM-radar fuzzy track correlation),
from the saved ``trials.csv`` and ``summary.csv``. Rate figures are the declared plots of
:data:`~trackfuse.experiments.esm_radar.FIGURES`; ``trajectory`` and ``manoeuvre`` are drawn
here; the tables come from :mod:`.tables` and :mod:`.paper`."""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from trackfuse.association.esm_scenario import FACTORS
from trackfuse.association.track_history_tests import binomial_tail, counting_threshold
from trackfuse.experiments.esm_radar import EXPERIMENT, FIGURES, LOOKS
from trackfuse.experiments.esm_radar.model import (
    TRUE_TRACK,
    alpha_max,
    decode_series,
    esm_times,
    scenario,
    static_weights,
)
from trackfuse.experiments.esm_radar.paper import (
    PAPER_PAIR,
    PAPER_SCENARIO,
    at_paper_setting,
    paper_vs_reproduced,
    setting_words,
    value_words,
)
from trackfuse.experiments.esm_radar.tables import ablation, ahp_table, manoeuvre_table, table3
from trackfuse.reported import ESM_RADAR
from trackfuse.reportkit import axes as kit_axes
from trackfuse.reportkit import render
from trackfuse.reportkit.derived import Rate, with_rates
from trackfuse.reportkit.numberformat import sig3
from trackfuse.reportkit.series import MAX_KEYED, mean_band, setting_colours, settings_bar
from trackfuse.reportkit.spec import SLOTS, Reference
from trackfuse.reportkit.style import context, legend_below, legend_entries, panels
from trackfuse.rundata import RunData, swept_keys

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def tables(run: RunData) -> dict[str, pd.DataFrame]:
    """The Table 3 analogue, the ablation table, the AHP weights, the manoeuvre index per
    point and the headline table."""
    trials, config = run.trials, run.config
    out = {"paper_vs_reproduced": paper_vs_reproduced(run), "table3": table3(trials, config),
           "ahp": ahp_table(), "manoeuvre": manoeuvre_table(run.summary, config)}
    abl = ablation(trials, config)
    if not abl.empty:
        out["ablation"] = abl
    return out


# --------------------------------------------------------------------------- figures

#: The algorithms of each correct-rate figure: the paper's pair and ours, the ablations
#: (beside the paper's method), the chi-square references (beside the paper's pair).
GROUPS = {"correct_rate": ("improved", "traditional", "improved_gauss"),
          "correct_rate_ablations": ("improved", "traditional_5f", "improved_static",
                                     "improved_no_range", "improved_3f", "improved_l2"),
          "correct_rate_references": ("improved", "traditional", "chi2", "chi2_lrt", "chi2_5f")}
#: What each figure draws, in its title.
GROUP_TITLES = {"correct_rate": "the paper's methods and ours",
                "correct_rate_ablations": "ablations of the paper's method",
                "correct_rate_references": "chi-square ML references"}
#: Paper figure drawn by ``correct_rate`` for each numeric swept key.
PAPER_FIGURE = {"target.separation": "Fig. 3", "radar.sigma_range_coef": "Fig. 4"}
CHANCE = 0.5  # T1 or T2 at random: track 3 is never chosen
#: A numeric swept key with at most this many values is drawn as categories, not as a
#: curve: two settings ("no weave" and "weave") joined by a line would suggest a trend.
MAX_CATEGORIES = 2


def rate_axis(run: RunData) -> tuple[str, bool]:
    """``(x, categories)`` of a rate figure: the first numeric swept key of more than
    :data:`MAX_CATEGORIES` values as a curve, else the first swept key as categories, else
    (nothing swept) the radar-factor model every rate depends on, one category."""
    keys = [k for k in swept_keys(run.config) if k != "algorithms"]
    for key in keys:
        values = run.sweep[key]
        if all(isinstance(v, int | float) for v in values) and len(set(values)) > MAX_CATEGORIES:
            return key, False
    return (keys[0] if keys else "radar.factor_model"), True


def _paper_points(run: RunData) -> tuple[int, ...]:
    """The sweep points at the paper's Table 3 setting (:func:`at_paper_setting`)."""
    return tuple(i for i in range(len(run.points)) if at_paper_setting(run.point_params(i)))


def _rate_title(group: str, x: str, categories: bool, paper: bool) -> str:
    """The title: the paper item redrawn (Fig. axis or Table 3 setting), else what is drawn."""
    item = PAPER_FIGURE.get(x) if not categories else ("Table 3" if paper else "")
    if group == "correct_rate" and item:
        return f"Paper 001 {item} redrawn: correct association rate"
    return f"Correct association rate, {GROUP_TITLES[group]} (no paper figure)"


def _rate_figure(run: RunData, group: str) -> Figure | str:
    """One correct-rate figure of :data:`GROUPS`: chance dotted, paper Table 3 as open stars."""
    present = set(run.summary.loc[run.summary["metric"] == "correct", "algorithm"])
    names = tuple(n for n in GROUPS[group] if n in present)
    if group != "correct_rate" and not set(names) - set(PAPER_PAIR):
        names = ()
    if not names:
        return (f"none of {', '.join(GROUPS[group])} was run" if group == "correct_rate"
                else f"no algorithm of this group ({', '.join(GROUPS[group][1:])}) was run")
    x, categories = rate_axis(run)
    points = _paper_points(run) if group == "correct_rate" else ()
    stars = tuple((n, ESM_RADAR.result(f"{n}: correct rate").value) for n in PAPER_PAIR
                  if n in names)
    references = (Reference(y=CHANCE),) + ((Reference(values=stars, points=points,
                                                      label="paper's Table 3"),)
                                           if points and stars else ())
    plot = replace(FIGURES[group].plot, x=x, categories=categories, algorithms=names,
                   references=references)
    return render.draw(run, plot, _rate_title(group, x, categories, bool(points)))


#: The tests over the track history: the figure needs one of them.
HISTORY_TESTS = ("counting", "sprt")
#: A wrong radar track chosen, and no decision: the outcomes beside ``correct`` of a test
#: that may abstain (no decision is drawn only for the methods that may abstain).
HISTORY_RATES = (
    Rate("wrong", "false association rate", lambda t: (t["decided"] == 1) & (t["correct"] == 0)),
    Rate("missed", "missed association rate", lambda t: t["decided"] == 0,
         (*HISTORY_TESTS, "chi2_lrt")))
#: Params that set the counting test's design rate: a run sweeping one has no single rate.
DESIGN_KEYS = ("counting.window", "history.p_false", "history.alpha", "scan.count")


def counting_design_rate(params: Mapping[str, Any]) -> float:
    """The counting test's design false-association rate: ``P(Binomial(n, p_false) >= M)``
    for its window ``n`` (the configured one, at most the ESM's scans) and threshold ``M``."""
    n = min(int(params["counting.window"]), len(esm_times(params)))
    p_false = float(params["history.p_false"])
    return binomial_tail(n, p_false, counting_threshold(n, p_false, params["history.alpha"]))


def _history_figure(run: RunData) -> Figure | str:
    """Association rates of the track-history tests beside the single-scan and fuzzy methods."""
    if not set(HISTORY_TESTS) & set(run.summary["algorithm"]):
        return "neither of the tests over the track history (counting, sprt) was run"
    x, categories = rate_axis(run)
    fixed = not set(DESIGN_KEYS) & set(run.sweep)
    design = counting_design_rate(run.params)
    references = (Reference(y=design, label=f"design rate {sig3(100 * design)} %",
                            metrics=("wrong",)),) if fixed and "counting" in run.params[
                                "algorithms"] else ()
    plot = replace(FIGURES["history_rates"].plot, x=x, categories=categories,
                   references=references)
    return render.draw(with_rates(run, HISTORY_RATES), plot,
                       "Association over the track history (no paper figure)")


# --------------------------------------------------------------------------- per-scan figures

#: Colours of the true tracks T1, T2, T3 and of the ESM location (no algorithm's colour).
TARGET_COLOURS, ESM_COLOUR = ("#56B4E9", "#000000", "#888888"), "#CC79A7"
#: Swept keys that change the ESM track or its manoeuvre index (prefixes).
ESM_TRACK_KEYS = ("target.", "snake.", "crossing.", "esm.", "geometry.", "scan.", "alpha.",
                  "noise.")
NO_SERIES = ("trials.csv has no per-scan columns (alpha_per_scan, ...): the run predates "
             "them; run it again to draw this figure")


def _esm_rows(trials: pd.DataFrame) -> pd.DataFrame:
    """The first row of every trial, which carries the ESM track's per-scan series."""
    if "alpha_per_scan" not in trials:
        return trials.iloc[:0]
    return trials[trials["alpha_per_scan"].notna()].sort_values(["point", "trial"])


def _weight_series(trials: pd.DataFrame, point: int, trial_ids: Sequence[int]
                   ) -> tuple[str, np.ndarray] | None:
    """``(algorithm, (N, K) range weights)`` of ``improved`` (or a dynamic one), or None."""
    if "range_weight_per_scan" not in trials:
        return None
    rows = trials[(trials["point"] == point) & trials["range_weight_per_scan"].notna()
                  & trials["trial"].isin(trial_ids)]
    if rows.empty:
        return None
    names = list(dict.fromkeys(rows["algorithm"]))
    name = "improved" if "improved" in names else names[0]
    cells = rows[rows["algorithm"] == name].sort_values("trial")["range_weight_per_scan"]
    return name, decode_series(cells)


def _truth(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """ESM times (K,) in s and true positions (K, 3, 2) in m, from the config alone."""
    t = esm_times(params)
    return t, scenario(params).states(t)[0]


def _tracks_panel(ax: Axes, params: Mapping[str, Any], row: pd.Series) -> None:
    """True tracks (km) and the ESM TDOA-DF location of target 2 in one saved trial."""
    t, p = _truth(params)
    motion = "weaving" if params["snake.amplitude"] > 0 else "straight"
    for j, name in enumerate((f"T1 ({motion})", f"T2 ({motion}, the ESM's target)",
                              "T3 (crossing)")):
        ax.plot(p[:, j, 0] / 1e3, p[:, j, 1] / 1e3, color=TARGET_COLOURS[j],
                linestyle=("-", "-", "--")[j], label=name)
    truth = p[:, TRUE_TRACK]
    r = np.hypot(truth[:, 0], truth[:, 1]) + decode_series([row["esm_range_error_per_scan_m"]])[0]
    th = np.arctan2(truth[:, 1], truth[:, 0]) \
        + 1e-3 * decode_series([row["esm_bearing_error_per_scan_mrad"]])[0]
    ax.plot(r * np.cos(th) / 1e3, r * np.sin(th) / 1e3, ".", color=ESM_COLOUR,
            markersize=4, label=f"ESM TDOA-DF location (trial {int(row['trial'])})")
    ax.set_xlabel("x (km)")
    ax.set_ylabel("y (km)")
    ax.set_title(f"one trial, separation {params['target.separation']:g} m")
    ax.legend(loc="best", fontsize=7)


def _index_panel(ax: Axes, run: RunData, row: pd.Series, params: Mapping[str, Any]) -> None:
    """One trial's manoeuvre index (log) and, on a twin axis, its range weight per scan."""
    t = esm_times(params)
    ax.plot(t, decode_series([row["alpha_per_scan"]])[0], color="0.2",
            label=f"index α(k), "
            f"{render.quantity(EXPERIMENT, 'alpha.index').word(params['alpha.index'])}")
    a_max, mode = alpha_max(params)
    if mode == "fixed":
        ax.axhline(a_max, color="0.2", linestyle=":", linewidth=1.0, label="α_max")
    ax.set_yscale("log")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high * (high / low) ** 0.45)  # room for the legend
    ax.set_xlabel("time (s)")
    ax.set_ylabel("manoeuvre index α\n(log scale)")
    weights = _weight_series(run.trials, int(row["point"]), [int(row["trial"])])
    top = ax
    if weights is not None:
        name, a1 = weights
        top = ax.twinx()
        top.plot(t, a1[0], color=LOOKS[name].colour, linewidth=2.0, label="range weight a₁(k)")
        top.axhline(static_weights(FACTORS, params["weights"])[0], color=LOOKS[name].colour,
                    linestyle=":", linewidth=1.0, label="static AHP weight")
        top.set_ylim(0, 1.0)
        top.set_ylabel("range weight a₁")
        top.grid(False)
    ax.set_title("one trial: index" + (" and range weight" if weights else "") + " per scan")
    top.legend(*legend_entries([ax, top]), loc="upper center", ncols=2, fontsize=7)


def _range_error_panel(ax: Axes, esm: pd.DataFrame, params: Mapping[str, Any]) -> None:
    """RMS and median absolute ESM range error (m, log) per scan over the saved trials."""
    t = esm_times(params)
    err = decode_series(esm["esm_range_error_per_scan_m"])
    ax.plot(t, np.sqrt(np.nanmean(err**2, axis=0)), color=ESM_COLOUR,
            label="RMS ESM range error")
    ax.plot(t, np.nanmedian(np.abs(err), axis=0), color=ESM_COLOUR, linestyle="--",
            label="median |ESM range error|")
    ax.axhline(params["target.separation"], color="0.5", linewidth=1.0,
               label="T1–T2 separation")
    kit_axes.y_log(ax, "log")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high * (high / low) ** 0.35)  # room for the legend
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ESM range error\n(m, log scale)")
    ax.set_title(f"all {len(esm)} trials of this point")
    ax.legend(loc="upper center", ncols=2, fontsize=7)


TRAJECTORY_SIZE = (SLOTS["double"], 5.4)
"""Width and height (in) of the trajectory figure: a double-column slot."""


def _trajectory_figure(run: RunData) -> Figure | str:
    """Paper 001 Figs. 1-2: the first trial of the first point with the paper's weave, else any."""
    esm = _esm_rows(run.trials)
    if esm.empty:
        return NO_SERIES
    weave = [p for p in esm["point"].unique() if np.isclose(
        run.point_params(int(p))["snake.amplitude"], PAPER_SCENARIO["snake.amplitude"])]
    row = esm[esm["point"] == weave[0]].iloc[0] if weave else esm.iloc[0]
    point = int(row["point"])
    params = run.point_params(point)
    with context():
        fig = Figure(figsize=TRAJECTORY_SIZE, layout="constrained")
        axes = fig.subplot_mosaic([["tracks", "index"], ["tracks", "error"]],
                                  width_ratios=(1.0, 1.15))  # the map over two rows
        _tracks_panel(axes["tracks"], params, row)
        _index_panel(axes["index"], run, row, params)
        _range_error_panel(axes["error"], esm[esm["point"] == point], params)
        axes["tracks"].set_aspect("equal", adjustable="datalim")
        amplitude = params["snake.amplitude"]
        head = ("Paper 001 Figs. 1-2 redrawn" if np.isclose(
            amplitude, PAPER_SCENARIO["snake.amplitude"]) else
            f"Paper 001 Figs. 1-2 layout, snake amplitude {amplitude:g} m")
        fig.suptitle(f"{head}: true tracks and the ESM location of T2")
    return fig


def _esm_groups(run: RunData, esm: pd.DataFrame) -> list[tuple[str, int, pd.DataFrame]]:
    """``(words, point, first rows)`` per setting of :data:`ESM_TRACK_KEYS`, at its first point."""
    keys = [k for k in swept_keys(run.config) if k.startswith(ESM_TRACK_KEYS)]
    seen: dict[tuple, int] = {}
    for point, params in enumerate(run.points):
        seen.setdefault(tuple(params[k] for k in keys), point)
    return [(setting_words(run.point_params(p), keys)
             or value_words("snake.amplitude", run.point_params(p)["snake.amplitude"]), p,
             esm[esm["point"] == p]) for p in seen.values()]


def _manoeuvre_figure(run: RunData) -> Figure | str:
    """Mean manoeuvre index and range weight per scan (index alone without dynamic weights)."""
    esm = _esm_rows(run.trials)
    if esm.empty:
        return NO_SERIES
    groups = _esm_groups(run, esm)
    if len(groups) > 9:
        return f"{len(groups)} settings of the ESM track (more than 9 curves per panel)"
    weights = [_weight_series(run.trials, p, rows["trial"].tolist()) for _, p, rows in groups]
    weight_name = next((w[0] for w in weights if w is not None), "")
    fig, grid = panels(1, 2 if weight_name else 1, panel_height=2.4)
    axes = grid.ravel()
    ax = axes[0]
    colours = setting_colours(len(groups))
    keyed = len(groups) > MAX_KEYED  # the settings on a colour bar, not in the legend
    for (words, point, rows), colour, w in zip(groups, colours, weights, strict=True):
        t, shade = esm_times(run.point_params(point)), len(groups) <= 3
        words = f"_{words}" if keyed else words
        mean_band(ax, t, decode_series(rows["alpha_per_scan"]), words, colour, shade)
        if w is not None:
            mean_band(axes[1], t, w[1], words, colour, shade)
    indices = _index_references(ax, [run.point_params(p) for _, p, _ in groups])
    ax.set_yscale("log")
    labelled = [(ax, "manoeuvre index α\n(log scale)", "manoeuvre index")]
    if weight_name:
        static = static_weights(FACTORS, run.point_params(groups[0][1])["weights"])[0]
        axes[1].axhline(static, color=LOOKS[weight_name].colour, linestyle=":",
                        linewidth=1.0)  # the static AHP range weight (in the caption)
        axes[1].set_ylim(0, 0.7)
        labelled.append((axes[1], "range weight a₁", f"range weight, {LOOKS[weight_name].label}"))
    with context():
        if keyed:
            settings_bar(fig, axes, [words for words, _, _ in groups])
        for a, ylabel, title in labelled:
            a.set_xlabel("time (s)")
            a.set_ylabel(ylabel)
            a.set_title(title)
        legend_below(fig, axes)  # one legend for both panels, below them
        words = render.quantity(EXPERIMENT, "alpha.index")
        fig.suptitle(f"Manoeuvre index ({', '.join(words.word(i) for i in indices)})"
                     + (" and range weight" if weight_name else "") + " per scan")
    return fig


def _index_references(ax: Axes, settings: Sequence[Mapping[str, Any]]) -> list[str]:
    """Draw the NIS expectation and each fixed ``alpha_max``; return the indices used."""
    indices = list(dict.fromkeys(p["alpha.index"] for p in settings))
    if "nis_tdoa" in indices:
        ax.axhline(1.0, color="0.5", linestyle="--", linewidth=1.0,
                   label="no-manoeuvre expectation E[α] = 1")
    limits = dict.fromkeys(alpha_max(p) for p in settings)
    for (a_max, mode), style in zip(limits, (":", "-.", (0, (1, 3))) * 3, strict=False):
        if mode == "fixed":
            ax.axhline(a_max, color="k", linestyle=style, linewidth=1.0, label="α_max")
    return indices


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """The ``wanted`` figures among :data:`GROUPS`, ``trajectory`` and ``manoeuvre``; a one-line
    reason for one this run cannot draw."""
    drawers: dict[str, Callable[[], Figure | str]] = {
        **{g: (lambda g=g: _rate_figure(run, g)) for g in GROUPS},
        "history_rates": lambda: _history_figure(run),
        "trajectory": lambda: _trajectory_figure(run),
        "manoeuvre": lambda: _manoeuvre_figure(run)}
    with context():
        return {name: draw() for name, draw in drawers.items() if name in wanted}

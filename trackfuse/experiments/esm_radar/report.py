"""Figures and report tables of the ``esm_radar`` experiment (paper 001).

Zhang Xiaoqiang et al., "An ESM-radar track correlation algorithm based on improved fuzzy
comprehensive evaluation", J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49. The
experiment itself (scenario, algorithms, rows) is :mod:`trackfuse.experiments.esm_radar.model`.

Figures, returned by :func:`figures`:

=============  ============================================================================
correct_rate   correct-association rate per algorithm with 95 % Wilson bands, against the
               first numeric swept axis (paper Fig. 3: separation; Fig. 4: radar range
               error), one panel per value of the other swept keys; a bar chart per panel
               when nothing numeric is swept (Table 3 setting: one panel per radar-factor
               model). Drawn from ``summary.csv`` alone.
trajectory     paper Figs. 1-2: true tracks and the ESM TDOA-DF location track, and the
               per-scan manoeuvre index and range weight of ``improved``. *Recomputed* from
               the config and seed: trial 0 of point 0 is re-simulated with the runner's
               streams ``trial_streams(seed, 0, 0)`` (milliseconds); the title says
               whether the recomputed decision matches the saved row of ``trials.csv``.
manoeuvre      mean manoeuvre index against time with 95 % t bands, with the snake and
               without it (same noise), for the default detector and the paper's literal
               index. *Recomputed* for the first 200 trials of point 0 (W001-4).
=============  ============================================================================

Tables, returned by :func:`tables`:

===================  ======================================================================
table3               paper Table 3: counts per chosen radar track (and "no decision"),
                     correct rate with its Wilson interval and wrong-decision rate, per
                     point and algorithm. From ``trials.csv``.
ablation             every algorithm against ``improved`` on the same trials (paired, exact
                     McNemar test); only when ``improved`` was run. From ``trials.csv``.
ahp                  paper Table 1 AHP weights and consistency, computed from the judgement
                     matrix (no run data), beside the paper's printed numbers.
paper_vs_reproduced  what paper 001 reports (:data:`trackfuse.reported.ESM_RADAR`) against
                     this run: Table 3 at the paper's setting with our Wilson intervals, and
                     the AHP numbers; a verdict per number (paper value inside our interval
                     or not).
===================  ======================================================================

The science (simulation, algorithms, AHP weight subsets) is
:mod:`trackfuse.experiments.esm_radar.model`; this module imports it, never the reverse.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from trackfuse.association import ahp
from trackfuse.association.esm_scenario import FACTORS
from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    N_TRACKS,
    THREE,
    alpha_max,
    differences,
    evaluate,
    factor_names,
    manoeuvre_alpha,
    simulate,
    static_weights,
)
from trackfuse.plots.style import band, new_figure, reference_line
from trackfuse.reported import ESM_RADAR, ESM_RADAR_WEIGHTS
from trackfuse.rundata import RunData, swept_keys
from trackfuse.seeding import trial_streams
from trackfuse.stats import t_interval, wilson_interval

if TYPE_CHECKING:
    from matplotlib.figure import Figure


# --------------------------------------------------------------------------- tables

def table3(trials: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Counts per chosen radar track (and "no decision"), correct rate with its Wilson 95 %
    interval, and the rate of wrong decisions, per point and algorithm."""

    keys = swept_keys(config)
    out = []
    for group, g in trials.groupby(["point", *keys, "algorithm"], sort=False):
        n = len(g)
        k = int(g["correct"].sum())
        lo, hi = wilson_interval(k, n)
        row = dict(zip(["point", *keys, "algorithm"], group, strict=True))
        for track in range(1, N_TRACKS + 1):
            row[f"radar_track_{track}"] = int((g["chosen"] == track).sum())
        row["no_decision"] = int((g["chosen"] == 0).sum())
        wrong = int(((g["chosen"] != 0) & (g["correct"] == 0)).sum())
        row.update(n=n, correct_rate=k / n, ci_low=float(lo), ci_high=float(hi),
                   wrong_rate=wrong / n)
        out.append(row)
    return pd.DataFrame(out).sort_values(["point"], kind="stable").reset_index(drop=True)


def ablation(trials: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Each algorithm against ``improved`` on the same trials (paired, exact McNemar test).

    ``gain_vs_improved`` is the variant's correct rate minus improved's; ``n_variant_only``
    and ``n_improved_only`` count the discordant trials; ``mcnemar_p`` is the two-sided exact
    binomial test of those counts (Q. McNemar, Psychometrika 12, 1947, 153-157). Empty when
    ``improved`` was not run.
    """

    if "improved" not in set(trials["algorithm"]):
        return pd.DataFrame()
    keys = swept_keys(config)
    wide = trials.pivot_table(index=["point", *keys, "trial"], columns="algorithm",
                              values="correct", aggfunc="first")
    params = config["params"]
    order = list(dict.fromkeys(trials["algorithm"]))
    out = []
    for point_key, g in wide.groupby(level=["point", *keys], sort=True):
        point_key = point_key if isinstance(point_key, tuple) else (point_key,)
        ref = g["improved"].to_numpy()
        for name in order:
            x = g[name].to_numpy()
            n = len(x)
            lo, hi = wilson_interval(x.sum(), n)
            only_v = int(((x == 1) & (ref == 0)).sum())
            only_i = int(((x == 0) & (ref == 1)).sum())
            p = binomtest(only_v, only_v + only_i).pvalue if only_v + only_i else 1.0
            v = ALGORITHMS[name]
            member = params["membership_norm"] if v.membership == "param" else v.membership
            out.append({
                **dict(zip(["point", *keys], point_key, strict=True)),
                "algorithm": name, "description": v.summary,
                "factors": len(factor_names(v, params)), "membership": member,
                "weights": "-" if v.membership.startswith("chi2") else
                ("dynamic" if v.dynamic else "static"),
                "correct_rate": x.mean(), "ci_low": float(lo), "ci_high": float(hi),
                "gain_vs_improved": x.mean() - ref.mean(),
                "n_variant_only": only_v, "n_improved_only": only_i, "mcnemar_p": float(p),
            })
    return pd.DataFrame(out)


def ahp_table() -> pd.DataFrame:
    """Paper 001 Table 1 weights by the root and eigenvector methods, with consistency.

    One row per factor set (all five, and the traditional method's three) and method:
    weights by factor name, ``lambda_max``, ``CI`` and ``CR``, plus the paper's printed
    rounded weights and consistency numbers for comparison.
    """

    out = []
    for names in (FACTORS, THREE):
        idx = [FACTORS.index(f) for f in names]
        B = ahp.PAPER_001_JUDGEMENT[np.ix_(idx, idx)]
        lam = ahp.lambda_max(B)
        for method in ("root", "eigen"):
            w = dict(zip(names, ahp.weights(B, method), strict=True))
            out.append({"factors": len(names), "method": method,
                        **{f: w.get(f, np.nan) for f in FACTORS}, "lambda_max": lam,
                        "CI": ahp.consistency_index(lam, len(names)),
                        "CR": ahp.consistency_ratio(B)})
    paper = {q: ESM_RADAR.result(f"AHP {q}").value for q in ("lambda_max", "CI", "CR")}
    out.append({"factors": 5, "method": "paper_printed",
                **dict(zip(FACTORS, ESM_RADAR_WEIGHTS, strict=True)), **paper})
    return pd.DataFrame(out)


#: Paper 001's Table 3 setting, by param key: T1-T2 separation (m) and the radar range sd
#: coefficient of its Table 2. Points of a run at other values are not compared with it.
PAPER_TABLE3_SETTING = {"target.separation": 200.0, "radar.sigma_range_coef": 0.01}


def printed_half_unit(value: float) -> float:
    """Half a unit in the last printed digit of ``value`` (0.053 -> 0.0005; 130 -> 0.5)."""
    text = repr(float(value)).rstrip("0").rstrip(".")
    decimals = len(text.split(".")[1]) if "." in text else 0
    return 0.5 * 10.0 ** -decimals


def verdict(paper: float, low: float, high: float, tolerance: float = 0.0) -> str:
    """``inside`` if the paper's value lies in ``[low - tolerance, high + tolerance]``."""
    return "inside" if low - tolerance <= paper <= high + tolerance else "outside"


def _comparison(quantity: str, where: str, paper: float, ours: float, low: float,
                high: float, tolerance: float, note: str = "") -> dict[str, Any]:
    return {"where": where, "quantity": quantity, "paper": paper, "ours": ours,
            "ci_low": low, "ci_high": high, "tolerance": tolerance,
            "verdict": verdict(paper, low, high, tolerance), "note": note}


def _table3_comparisons(row: pd.Series) -> list[dict[str, Any]]:
    """Paper Table 3 against one ``table3`` row (one algorithm at one point)."""
    method, n = row["algorithm"], int(row["n"])
    rep = ESM_RADAR.result(f"{method}: correct rate")
    out = [_comparison(rep.quantity, rep.where, rep.value, row["correct_rate"],
                       row["ci_low"], row["ci_high"], 0.0,
                       "ours: 95 % Wilson interval")]
    for track in (1, 2, 3):
        rep = ESM_RADAR.result(f"{method}: runs to radar track {track}")
        count = int(row[f"radar_track_{track}"])
        lo, hi = (n * float(v) for v in wilson_interval(count, n))
        out.append(_comparison(rep.quantity, rep.where, rep.value, count, lo, hi, 0.0,
                               f"ours: n x 95 % Wilson interval, n = {n}"))
    return out


def _ahp_comparisons() -> list[dict[str, Any]]:
    """Paper Table 1 numbers against the exact root-method computation (no interval)."""
    B = ahp.PAPER_001_JUDGEMENT
    lam = ahp.lambda_max(B)
    ours = {"AHP lambda_max": lam, "AHP CI": ahp.consistency_index(lam, len(FACTORS)),
            "AHP CR": ahp.consistency_ratio(B)}
    out = []
    for quantity, value in ours.items():
        rep = ESM_RADAR.result(quantity)
        note = ("exact; tolerance = half a unit of the paper's last printed digit"
                + ("; the paper's CI is (5.2375 - 5)/4 from its rounded lambda_max"
                   if quantity == "AHP CI" else ""))
        out.append(_comparison(quantity, rep.where, rep.value, value, value, value,
                               printed_half_unit(rep.value), note))
    for f, w, printed in zip(FACTORS, ahp.weights(B, "root"), ESM_RADAR_WEIGHTS, strict=True):
        out.append(_comparison(f"AHP weight: {f}", "Table 1", printed, w, w, w,
                               printed_half_unit(printed), "root method, exact"))
    return out


def paper_vs_reproduced(trials: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """What paper 001 reports against what this run reproduces, with a verdict per number.

    Rows: Table 3 (correct rate and runs per radar track, improved and traditional) for
    every point of the run at the paper's setting (:data:`PAPER_TABLE3_SETTING`), with our
    95 % Wilson interval; and the AHP numbers of Table 1, computed exactly, with a
    tolerance of half a unit in the paper's last printed digit. ``verdict`` says whether the
    paper's value lies inside our interval (widened by the tolerance). Values come from
    :data:`trackfuse.reported.ESM_RADAR`.
    """
    keys = swept_keys(config)
    t3 = table3(trials, config)
    out = []
    for _, row in t3[t3["algorithm"].isin(["improved", "traditional"])].iterrows():
        setting = {k: (row[k] if k in keys else config["params"][k])
                   for k in PAPER_TABLE3_SETTING}
        if not all(np.isclose(float(setting[k]), v) for k, v in PAPER_TABLE3_SETTING.items()):
            continue
        point = {k: row[k] for k in ["point", *keys, "algorithm"]}
        out += [{**point, **c} for c in _table3_comparisons(row)]
    out += _ahp_comparisons()
    return pd.DataFrame(out)


def tables(run: RunData) -> dict[str, pd.DataFrame]:
    """The Table 3 analogue, the ablation table and the AHP weights (from ``trials.csv``)."""
    trials, config = run.trials, run.config
    out = {"table3": table3(trials, config), "ahp": ahp_table(),
           "paper_vs_reproduced": paper_vs_reproduced(trials, config)}
    abl = ablation(trials, config)
    if not abl.empty:
        out["ablation"] = abl
    return out


# --------------------------------------------------------------------------- figures

#: x-axis label of each numeric swept key (the key itself for any other).
AXIS_LABELS = {
    "target.separation": "T1-T2 separation (m)",
    "radar.sigma_range_coef": "radar range error sd (fraction of range R)",
    "phase.d_over_lambda": "interferometer spacing d/λ",
    "snake.amplitude": "snake amplitude (m)",
    "alpha.max": "α_max",
}

#: One colour per algorithm in every figure; the ML references are dashed (grey/black).
COLOURS = {
    "traditional": "tab:blue", "traditional_5f": "tab:cyan", "improved": "tab:orange",
    "improved_static": "tab:green", "improved_3f": "tab:red", "improved_l2": "tab:olive",
    "improved_gauss": "tab:purple", "chi2": "black", "chi2_lrt": "tab:brown",
    "chi2_5f": "tab:gray",
}


def _algorithm_line_style(name: str) -> dict[str, Any]:
    style = {"color": COLOURS[name]}
    if name.startswith("chi2"):
        style["linestyle"] = "--"
    return style


def _correct_rate_figure(summary: pd.DataFrame, config: Mapping[str, Any]) -> Figure:
    """Correct-association rate (fraction) with Wilson bands, from the ``correct`` rows of
    the summary: curves against the first numeric swept key, else bars per algorithm."""

    s = summary[summary["metric"] == "correct"]
    sweep = swept_keys(config)
    numeric = [k for k in sweep if pd.api.types.is_numeric_dtype(s[k])]
    x = numeric[0] if numeric else None
    panel_keys = [k for k in sweep if k != x]
    combos = (list(dict.fromkeys(map(tuple, s[panel_keys].to_numpy()))) if panel_keys
              else [()])
    algorithms = list(dict.fromkeys(s["algorithm"]))
    params = config["params"]
    ncols = min(len(combos), 3)
    fig, axes = new_figure(ncols=ncols, nrows=-(-len(combos) // ncols), width=5.0, height=3.6)
    axes = np.atleast_1d(axes)
    for ax in axes[len(combos):]:
        ax.set_visible(False)
    for ax, combo in zip(axes, combos, strict=False):
        mask = np.ones(len(s), dtype=bool)
        for key, value in zip(panel_keys, combo, strict=True):
            mask &= (s[key] == value).to_numpy()
        sp = s[mask]
        setting = (", ".join(f"{k} = {v}" for k, v in zip(panel_keys, combo, strict=True))
                   or f"radar factors: {params['radar.factor_model']}")
        if x is not None:
            for name in algorithms:
                g = sp[sp["algorithm"] == name].sort_values(x)
                band(ax, g[x], g["mean"], g["ci_low"], g["ci_high"], label=name,
                     **_algorithm_line_style(name))
            ax.set_xlabel(AXIS_LABELS.get(x, x))
            if x == "target.separation":
                ax.set_xscale("log")
        else:
            g = sp.set_index("algorithm").loc[algorithms]
            pos = np.arange(len(algorithms))
            ax.bar(pos, g["mean"], color=[COLOURS[a] for a in algorithms], alpha=0.75,
                   hatch=["//" if a.startswith("chi2") else "" for a in algorithms])
            ax.errorbar(pos, g["mean"], yerr=[g["mean"] - g["ci_low"], g["ci_high"] - g["mean"]],
                        fmt="none", color="k", capsize=3)
            ax.set_xticks(pos, algorithms, rotation=35, ha="right")
            ax.set_xlabel("algorithm")
        reference_line(ax, 1 / N_TRACKS, "chance (1/3)", color="0.5")
        ax.set_ylim(0, 1.02)
        ax.set_ylabel("correct association rate (fraction)")
        ax.set_title(f"{setting}; 95 % Wilson bands", fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 5),
               fontsize=7)
    timing = ""
    if params["esm.period"] != params["radar.period"] or params["esm.offset"]:
        timing = (f", ESM/radar periods {params['esm.period']:g}/{params['radar.period']:g} s"
                  f" ({'interpolated' if params['time_align'] else 'latest radar sample'})")
    fig.suptitle(f"ESM-radar association (paper 001), {config['trials']} trials/point"
                 + (f", separation {params['target.separation']:g} m"
                    if "target.separation" not in sweep else "")
                 + timing)
    return fig


def _trajectory_figure(run: RunData) -> Figure:
    """Paper 001 Figs. 1-2: re-simulate trial 0 of point 0 and draw its tracks (km) and the
    per-scan manoeuvre index and range weight of ``improved`` against time (s)."""

    trials, config, params = run.trials, run.config, run.point_params(0)
    sim = simulate(params, [trial_streams(int(config["seed"]), 0, 0)])
    fig, (ax, ax2) = new_figure(ncols=2, width=5.0, height=4.0)
    names = ("T1 (snake)", "T2 (snake, ESM target)", "T3 (crossing)")
    for j in range(N_TRACKS):
        ax.plot(sim.truth_p[:, j, 0] / 1e3, sim.truth_p[:, j, 1] / 1e3, label=names[j])
    r, th = sim.x_esm[0, :, 0], sim.x_esm[0, :, 2]
    ax.plot(r * np.cos(th) / 1e3, r * np.sin(th) / 1e3, ".", color="tab:red", ms=3,
            label="ESM TDOA-DF location")
    ax.plot([0, params["geometry.baseline"] / 1e3], [0, 0], "k^", label="A1, A2")
    ax.set_xlabel("x (km)")
    ax.set_ylabel("y (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(f"tracks, separation {params['target.separation']:g} m; mean ESM range sd "
                 f"{np.sqrt(sim.P_esm[0, :, 0, 0]).mean() / 1e3:.1f} km", fontsize=8)

    res = evaluate(ALGORITHMS["improved"], differences(sim), sim.alpha, params)
    ax2.plot(sim.t, sim.alpha[0], color="tab:purple",
             label=f"manoeuvre index α(k), {params['alpha.index']}")
    a_max, mode = alpha_max(params)
    if mode == "fixed":
        ax2.axhline(a_max, color="tab:purple", linestyle=":", linewidth=1.0, label="α_max")
    ax2.set_yscale("log")
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("manoeuvre index α (dimensionless, log)")
    ax3 = ax2.twinx()
    ax3.plot(sim.t, res["weights"][0, :, 0], color="tab:green", label="range weight a₁(k)")
    ax3.set_ylabel("range weight a₁ (fraction)")
    a1 = static_weights(FACTORS, params["weights"])[0]
    ax3.axhline(a1, color="tab:green", linestyle=":", linewidth=1.0, label="static AHP a₁")
    ax3.set_ylim(0, 0.6)
    h1, l1 = ax2.get_legend_handles_labels()
    h2, l2 = ax3.get_legend_handles_labels()
    ax2.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower left")
    saved = trials[(trials["point"] == 0) & (trials["trial"] == 0)
                   & (trials["algorithm"] == "improved")]
    chosen = int(res["chosen"][0]) + 1
    check = ("" if saved.empty else
             " (matches saved row)" if int(saved["chosen"].iloc[0]) == chosen
             else " (DIFFERS from saved row)")
    ax2.set_title(f"improved: chose radar track {chosen}{check}; per-scan diagnostics",
                  fontsize=8)
    fig.suptitle("Paper 001 Figs. 1-2 analogue: one trial (point 0, trial 0), recomputed "
                 "from config and seed")
    return fig


#: Trials re-simulated for the manoeuvre-index figure.
MANOEUVRE_TRIALS = 200


def _index_band(ax, t: np.ndarray, alpha: np.ndarray, label: str, **kw) -> None:
    """Mean of ``alpha`` (N, K) over trials against ``t`` with its 95 % t band, where
    defined (NaN marks start-up scans)."""
    ok = np.isfinite(alpha).all(axis=0)
    a = alpha[:, ok]
    n = a.shape[0]
    lo, hi = t_interval(a.mean(axis=0), a.std(axis=0, ddof=1), n)
    band(ax, t[ok], a.mean(axis=0), lo, hi, label=label, marker="", **kw)


def _manoeuvre_figure(run: RunData) -> Figure:
    """Mean manoeuvre index against time (s), with and without the snake, for the default
    detector and the paper's literal index. *Recomputed*: the first
    :data:`MANOEUVRE_TRIALS` trials of point 0 are re-simulated with the runner's streams at
    the point's snake amplitude (the schema default if it is 0) and at amplitude 0 (same
    noise)."""

    config, params = run.config, run.point_params(0)
    amplitude = params["snake.amplitude"] or run.experiment.defaults()["snake.amplitude"]
    n = min(int(config["trials"]), MANOEUVRE_TRIALS)
    streams = [trial_streams(int(config["seed"]), 0, t) for t in range(n)]
    sims = {a: simulate(dict(params, **{"snake.amplitude": a}), streams)
            for a in (amplitude, 0.0)}
    nis_params = dict(params, **{"alpha.index": "nis_tdoa", "alpha.max_mode": "chi2"})
    panels = (("nis_tdoa", "windowed NIS of the range difference c·Δt (default)",
               alpha_max(nis_params)[0],
               f"α_max (χ² quantile, 1 - {params['alpha.false_alarm']:g})"),
              ("literal", "paper eq. 8-13: V²/R on the TDOA-DF range", params["alpha.max"],
               "α_max ('fixed' mode value)"))
    fig, axes = new_figure(ncols=2, width=5.0, height=3.8)
    for ax, (index, title, a_max, a_label) in zip(axes, panels, strict=True):
        for a, colour in zip(sims, ("tab:red", "tab:blue"), strict=True):
            sim = sims[a]
            _index_band(ax, sim.t, manoeuvre_alpha(params, sim.x_esm, sim.P_esm, index),
                        f"snake amplitude {a:g} m", color=colour)
        if index == "nis_tdoa":
            reference_line(ax, 1.0, "no-manoeuvre expectation E[α] = 1", color="0.5")
        ax.axhline(a_max, color="k", linestyle=":", linewidth=1.0, label=a_label)
        ax.set_yscale("log")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("manoeuvre index α (dimensionless)")
        ax.set_title(title, fontsize=8)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Manoeuvre index, mean over {n} trials with 95 % t bands (seed "
                 f"{config['seed']}, point 0, separation {params['target.separation']:g} m), "
                 "recomputed")
    return fig


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure]:
    """The ``wanted`` figures among ``correct_rate`` (from the summary), ``trajectory`` and
    ``manoeuvre`` (recomputed)."""
    drawers = {"correct_rate": lambda: _correct_rate_figure(run.summary, run.config),
               "trajectory": lambda: _trajectory_figure(run),
               "manoeuvre": lambda: _manoeuvre_figure(run)}
    return {name: draw() for name, draw in drawers.items() if name in wanted}

"""Figures and report tables of the ``esm_radar`` experiment (paper 001).

Zhang Xiaoqiang et al., "An ESM-radar track correlation algorithm based on improved fuzzy
comprehensive evaluation", J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49. The
experiment itself (scenario, algorithms, rows) is :mod:`trackfuse.experiments.esm_radar.model`;
this module imports it, never the reverse, and reads saved runs only: every curve and table
entry comes from ``trials.csv`` or ``summary.csv``. Only the noise-free geometry (true
tracks, sensor positions) and the static AHP weights are recomputed, from the config alone.

Figures, returned by :func:`figures`:

========================  ==================================================================
correct_rate              the paper's main result: correct-association rate (%) of its
                          method (``improved``), its baseline (``traditional``) and our
                          improvement (``improved_gauss``), 95 % Wilson intervals, one panel
                          per value of the other swept keys. Table 3 layout (one row per
                          method, the paper's 74.0 % and 55.2 % beside ours) when nothing
                          numeric is swept; Fig. 3 (separation) or Fig. 4 (radar range
                          error) layout otherwise, the paper's Table 3 values marked just
                          right of every point at its setting (:func:`at_paper_setting`),
                          under our markers. Chance between T1 and T2 is 1/2 (track 3 is
                          never chosen).
correct_rate_ablations    the same for those ablations the run has (``traditional_5f``,
                          ``improved_static``, ``improved_no_range``, ``improved_3f``,
                          ``improved_l2``) beside ``improved``; on curves the thin ones with
                          Wilson error bars, shifted sideways (bands for the paper's).
correct_rate_references   the same for the chi-square ML references beside the paper's two.
trajectory                paper Figs. 1-2 (redrawn if point 0 has the paper's weave): true
                          tracks and the ESM TDOA-DF location track of one saved trial, its
                          per-scan manoeuvre index and range weight, and the RMS ESM range
                          error per scan over all trials.
manoeuvre                 mean manoeuvre index and mean range weight of ``improved`` per scan
                          with 95 % t bands, one curve per setting of the ESM track (the
                          index panel alone without a dynamic-weight algorithm).
========================  ==================================================================

A figure that a run cannot draw (e.g. no algorithm of its group was run) is returned as a
one-line reason string.

Tables, returned by :func:`tables`: ``table3`` (counts per chosen radar track, correct
rate with its Wilson interval), ``ablation`` (every algorithm against ``improved`` on the
same trials, exact McNemar test), ``ahp`` (paper Table 1), ``manoeuvre`` (mean manoeuvre
index and range weight of ``improved`` per point, 95 % t intervals) and ``paper_vs_reproduced``
(:data:`trackfuse.reports.HEADLINE_COLUMNS`, see :func:`paper_vs_reproduced`).
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
from matplotlib.transforms import offset_copy

from trackfuse.association import ahp
from trackfuse.association.esm_scenario import FACTORS
from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    N_TRACKS,
    THREE,
    TRUE_TRACK,
    alpha_max,
    decode_series,
    esm_times,
    factor_names,
    scenario,
    static_weights,
)
from trackfuse.plots.algorithms import line_kwargs, look
from trackfuse.plots.style import (
    PAGE_WIDTH_IN,
    band,
    legend_below,
    legend_entries,
    mosaic_figure,
    new_figure,
    reference_line,
    wants_log_axis,
)
from trackfuse.reported import ESM_RADAR, ESM_RADAR_WEIGHTS
from trackfuse.reportkit.verdicts import (
    AGREES,
    ALPHA,
    DIFFERS,
    against_paper_sample,
    as_printed_verdict,
    at_least,
    claim_verdict,
    exploration,
    points,
    printed_decimals,
    setting_text,
)
from trackfuse.reports import HEADLINE_COLUMNS, headline_row
from trackfuse.rundata import RunData, swept_keys
from trackfuse.stats import (
    PairedBinary,
    holm_adjusted,
    paired_binary,
    paired_t_p,
    t_interval,
    wilson_interval,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

DOCS = "docs/papers/esm_radar.md"

# --------------------------------------------------------------------------- tables


def table3(trials: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Counts per chosen radar track (and "no decision"), correct rate and rate of wrong
    decisions with their Wilson 95 % intervals (``<rate>_ci_low``/``_ci_high``), per point
    and algorithm."""

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
        wrong_lo, wrong_hi = wilson_interval(wrong, n)
        row.update(n=n, correct_rate=k / n, correct_rate_ci_low=float(lo),
                   correct_rate_ci_high=float(hi), wrong_rate=wrong / n,
                   wrong_rate_ci_low=float(wrong_lo), wrong_rate_ci_high=float(wrong_hi))
        out.append(row)
    return pd.DataFrame(out).sort_values(["point"], kind="stable").reset_index(drop=True)


def ablation(trials: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Each algorithm against ``improved`` on the same trials (paired, exact McNemar test).

    ``gain_vs_improved`` is the variant's correct rate minus improved's, with Newcombe's
    paired 95 % interval; ``n_variant_only`` and ``n_improved_only`` count the discordant
    trials; ``mcnemar_p`` is the two-sided exact binomial test of those counts (Q. McNemar,
    Psychometrika 12, 1947, 153-157), ``mcnemar_p_holm`` the same adjusted by Holm's method
    over the variants compared at that point, and ``mcnemar_p_holm_sweep`` adjusted over the
    points of the run for that variant (the family of a claim along the sweep, such as "leads
    from 100 m to 1 km"). ``improved``'s own row is no comparison: its gain is 0 with no
    interval and no p-value (NaN). Empty when ``improved`` was not run.
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
            lo, hi = wilson_interval(x.sum(), len(x))
            gain = paired_binary(ref, x)
            v = ALGORITHMS[name]
            member = params["membership_norm"] if v.membership == "param" else v.membership
            out.append({
                **dict(zip(["point", *keys], point_key, strict=True)),
                "algorithm": name, "description": v.summary,
                "factors": len(factor_names(v, params)), "membership": member,
                "weights": "-" if v.membership.startswith("chi2") else
                ("dynamic" if v.dynamic else "static"),
                "correct_rate": x.mean(), "correct_rate_ci_low": float(lo),
                "correct_rate_ci_high": float(hi), "gain_vs_improved": float(gain.diff),
                "gain_vs_improved_ci_low": float(gain.low),
                "gain_vs_improved_ci_high": float(gain.high),
                "n_variant_only": int(gain.y_only), "n_improved_only": int(gain.x_only),
                "mcnemar_p": float(gain.p),
            })
    table = pd.DataFrame(out)
    own = table["algorithm"] == "improved"
    table.loc[own, ["gain_vs_improved_ci_low", "gain_vs_improved_ci_high", "mcnemar_p"]] = np.nan
    table["mcnemar_p_holm"] = np.nan
    table["mcnemar_p_holm_sweep"] = np.nan
    for _, rows in table[~own].groupby(["point", *keys], sort=False):
        table.loc[rows.index, "mcnemar_p_holm"] = holm_adjusted(rows["mcnemar_p"])
    for _, rows in table[~own].groupby("algorithm", sort=False):
        table.loc[rows.index, "mcnemar_p_holm_sweep"] = holm_adjusted(rows["mcnemar_p"])
    return table


def manoeuvre_table(summary: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Per point: the ESM track's manoeuvre index (``alpha_mean``, its mean over the scans
    where it is defined, then over the trials) and the mean range weight of ``improved``
    (``improved_range_weight``), each with its 95 % Student-t interval from ``summary.csv``
    (columns ``<q>_ci_low``/``<q>_ci_high``). The index is the same for every algorithm of a
    trial; it is read from the first algorithm's rows."""
    keys = swept_keys(config)
    first = summary["algorithm"].iloc[0]
    wanted = {("alpha_mean", first): "alpha_mean",
              ("range_weight_mean", "improved"): "improved_range_weight"}
    out = []
    for point, g in summary.groupby("point", sort=True):
        row = {"point": point, **{k: g[k].iloc[0] for k in keys}}
        for (metric, name), column in wanted.items():
            hit = g[(g["metric"] == metric) & (g["algorithm"] == name)]
            if len(hit):
                row.update({column: hit["mean"].iloc[0],
                            f"{column}_ci_low": hit["ci_low"].iloc[0],
                            f"{column}_ci_high": hit["ci_high"].iloc[0]})
        out.append(row)
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


# --------------------------------------------------------------------------- headline

#: Paper 001's Table 3 setting, by param key: T1-T2 separation (m) and the radar range sd
#: coefficient of its Table 2. Points of a run at other values are not compared with it.
PAPER_TABLE3_SETTING = {"target.separation": 200.0, "radar.sigma_range_coef": 0.01}
#: The paper's scenario beyond :data:`PAPER_TABLE3_SETTING`: its 1 km weave (a run's points
#: in straight flight are not compared with the paper's Table 3).
PAPER_SCENARIO = {"snake.amplitude": 1000.0}
#: The paper's method and its baseline, compared in every claim.
PAPER_PAIR = ("improved", "traditional")


def at_paper_setting(params: Mapping[str, Any]) -> bool:
    """Whether a point's params are the paper's Table 3 setting and scene
    (:data:`PAPER_TABLE3_SETTING`, :data:`PAPER_SCENARIO`): where its 74.0 % / 55.2 % apply."""
    setting = {**PAPER_TABLE3_SETTING, **PAPER_SCENARIO}
    return all(np.isclose(float(params[k]), v) for k, v in setting.items())


def _setting_words(point: Mapping[str, Any], keys: Sequence[str]) -> str:
    """The swept settings of a point in words (``radar TDOA/phase derived``, ...)."""
    return "; ".join(_value_words(k, point[k]) for k in keys)


def _headline_words(point: Mapping[str, Any], keys: Sequence[str]) -> str:
    """The swept settings of a point for the headline table: as :func:`_setting_words`, but
    the radar-factor model named by its value (``radar factors 'derived': ...``), so a row
    says which model it judges."""
    return "; ".join(f"radar factors '{point[k]}': "
                     + _value_words(k, point[k]).removeprefix("radar ")
                     if k == "radar.factor_model" else _value_words(k, point[k]) for k in keys)


def _table3_rows(run: RunData) -> list[dict[str, Any]]:
    """Paper Table 3 correct rates against every point of the run at the paper's setting:
    ours against the paper's count of its 500 runs as two samples
    (:func:`~trackfuse.reportkit.verdicts.against_paper_sample`); ``reproduced`` is our rate
    with its Wilson interval."""
    trials, out = run.trials, []
    swept = swept_keys(run.config)
    keys = [k for k in swept if k not in PAPER_TABLE3_SETTING]
    for point, params in enumerate(run.points):
        if not at_paper_setting(params):
            continue
        at = trials[trials["point"] == point]
        for name in (n for n in PAPER_PAIR if n in set(at["algorithm"])):
            x = at.loc[at["algorithm"] == name, "correct"].to_numpy()
            lo, hi = (float(v) for v in wilson_interval(x.sum(), len(x)))
            item = ESM_RADAR.result(f"{name}: correct rate")
            verdict = against_paper_sample(int(x.sum()), len(x),
                                           round(item.value * item.runs), item.runs)
            why = ("; the radar's own TDOA decides the choice (see the notes on the radar's "
                   "TDOA and phase)" if verdict.estimate > 0 and verdict.word == DIFFERS
                   and params["radar.factor_model"] == "table" else "")
            out.append(headline_row(
                "Table 3", "correct association rate at 200 m separation, radar range sd 1 %"
                + (f" ({_headline_words(params, keys)})" if keys else ""), name, item.value,
                x.mean(), lo, hi, "fraction", len(x), verdict.word, verdict.reason + why,
                f"{DOCS}#w001-2-radar-tdoa-and-phase" if why else f"{DOCS}#table-3",
                claim=item.quantity, setting=setting_text({k: params[k] for k in swept})))
    return out


def _ahp_rows() -> list[dict[str, Any]]:
    """Paper Table 1 numbers against the exact root-method computation, compared as printed
    (:func:`~trackfuse.reportkit.verdicts.as_printed_verdict`; an exact value has no
    interval: ``ci_low``, ``ci_high`` NaN). The paper's CI is computed from its printed
    lambda_max, so ours is too: from our lambda_max rounded as the paper prints it."""
    B = ahp.PAPER_001_JUDGEMENT
    lam = ahp.lambda_max(B)
    lam_printed = round(lam, printed_decimals(ESM_RADAR.result("AHP lambda_max").value))
    ours = {"AHP lambda_max": lam, "AHP CI": ahp.consistency_index(lam_printed, len(FACTORS)),
            "AHP CR": ahp.consistency_ratio(B)}
    ours.update({f"AHP weight: {f}": w for f, w in zip(FACTORS, ahp.weights(B, "root"),
                                                       strict=True)})
    printed = dict(zip([f"AHP weight: {f}" for f in FACTORS], ESM_RADAR_WEIGHTS, strict=True))
    out = []
    for quantity, value in ours.items():
        paper = printed[quantity] if quantity in printed else ESM_RADAR.result(quantity).value
        verdict = as_printed_verdict(value, paper)
        note = (f" (ours from our lambda_max as printed, {lam_printed:g})"
                if quantity == "AHP CI" else "; the printed set looks adjusted to sum to 1"
                if verdict.word == DIFFERS and quantity in printed else "")
        out.append(headline_row("Table 1", quantity.removeprefix("AHP "), "", paper, value,
                                np.nan, np.nan, "1", None, verdict.word, verdict.reason + note,
                                f"{DOCS}#table-1-ahp-weights",
                                claim="AHP weights" if quantity in printed else quantity))
    return out


def _correct_by_point(trials: pd.DataFrame, name: str) -> pd.DataFrame:
    """``correct`` of ``name`` as a (trial x point) frame: trials share their common random
    numbers across points, so columns are paired."""
    rows = trials[trials["algorithm"] == name]
    return rows.pivot(index="trial", columns="point", values="correct").sort_index()


def _sweep_groups(run: RunData, x: str) -> list[tuple[str, str, list[tuple[float, int]]]]:
    """Points of the run grouped by the swept keys other than ``x``: ``(words, setting,
    [(x value, point), ...] sorted by x)`` per group, ``setting`` in the machine form of
    :func:`~trackfuse.reportkit.verdicts.setting_text`."""
    others = [k for k in swept_keys(run.config) if k != x]
    groups: dict[tuple, list[tuple[float, int]]] = {}
    for point, params in enumerate(run.points):
        groups.setdefault(tuple(params[k] for k in others), []).append((float(params[x]), point))
    return [(_headline_words(values, others), setting_text(values), sorted(members))
            for key, members in groups.items()
            for values in [dict(zip(others, key, strict=True))]]


def _fmt_x(x: str, value: float) -> str:
    """A swept value in words with its unit (``200 m``, ``1 %``)."""
    return f"{100 * value:g} %" if x == "radar.sigma_range_coef" else f"{value:g} m"


def _gap_rows(item: str, anchor: str, x: str, setting: str, imp: pd.DataFrame,
              trad: pd.DataFrame, xs: list[tuple[float, int]], at: str = ""
              ) -> list[dict[str, Any]]:
    """Claims on the gap improved - traditional along ``x`` (``at``: the group's setting,
    machine form): clearly higher at the first value and narrowing (Fig. 3 only,
    :func:`_narrowing_row`), higher at every value (:func:`_always_higher_row`)."""
    gaps = [(xv, paired_binary(trad[p].to_numpy(), imp[p].to_numpy())) for xv, p in xs]
    n, where = len(imp), f" ({setting})" if setting else ""
    out = []
    if x == "target.separation":
        x0, gap = gaps[0]
        claim = ESM_RADAR.result("clearly higher when close")
        verdict = at_least(float(gap.diff), float(gap.low), float(gap.high), claim.margin,
                           "a lead of improved over traditional")
        out.append(headline_row(
            item, f"improved - traditional at the closest separation, {_fmt_x(x, x0)}{where}",
            "improved", "clearly higher", verdict.estimate, verdict.low, verdict.high,
            "fraction difference", n, verdict.word,
            verdict.reason + " (same runs, Newcombe's paired interval)", f"{DOCS}#{anchor}",
            claim=claim.quantity, setting=at))
        out.append(_narrowing_row(item, anchor, x, where, imp, trad, xs, at))
    out.append(_always_higher_row(item, anchor, x, where, n, gaps, at))
    return out


def _narrowing_row(item: str, anchor: str, x: str, where: str, imp: pd.DataFrame,
                   trad: pd.DataFrame, xs: list[tuple[float, int]], at: str = ""
                   ) -> dict[str, Any]:
    """"The gap narrows as separation grows", decided by the one comparison fixed in
    advance: the gap at the closest separation minus the gap at the widest, over the same
    trials (per trial, improved's 0/1 outcome minus traditional's), with its 95 % paired t
    interval, judged against the declared margin
    (:func:`~trackfuse.reportkit.verdicts.at_least`). Every other pair of separations is
    searched too (paired t, Holm over all pairs); a pair found widening goes into the reason
    as exploration, never into the verdict."""
    gap = {xv: imp[p].to_numpy() - trad[p].to_numpy() for xv, p in xs}
    tests = []
    for i, (xa, _) in enumerate(xs):
        for xb, _ in xs[i + 1:]:
            d = gap[xa] - gap[xb]
            d = d[np.isfinite(d)]
            mean, sd = float(d.mean()), float(d.std(ddof=1))
            lo, hi = t_interval(mean, sd, len(d))
            tests.append((xa, xb, mean, float(lo), float(hi),
                          float(paired_t_p(mean, sd, len(d)))))
    holm = holm_adjusted([t[-1] for t in tests])
    x0, x1 = xs[0][0], xs[-1][0]
    _, _, d_end, lo_end, hi_end, _ = next(t for t in tests if t[:2] == (x0, x1))
    claim = ESM_RADAR.result("gap narrows")
    verdict = at_least(d_end, lo_end, hi_end, claim.margin, "a narrowing")
    means = {xv: float(np.nanmean(g)) for xv, g in gap.items()}
    reason = (f"gap {points(means[x0])} points at {_fmt_x(x, x0)}, {points(means[x1])} at "
              f"{_fmt_x(x, x1)}, the comparison fixed in advance: {verdict.reason}")
    widening = sorted((q, i) for i, (t, q) in enumerate(zip(tests, holm, strict=True))
                      if t[2] < 0 and q < ALPHA and t[:2] != (x0, x1))
    if widening:
        q, i = widening[0]
        xa, xb = tests[i][:2]
        reason += "; " + exploration(len(tests), (
            f"the gap widens from {_fmt_x(x, xa)} to {_fmt_x(x, xb)}, Holm p = {q:.2g}"))
    return headline_row(item, f"gap at {_fmt_x(x, x0)} minus gap at {_fmt_x(x, x1)}, same "
                        f"trials{where}", "improved", "gap narrows as separation grows",
                        d_end, lo_end, hi_end, "fraction difference", len(imp), verdict.word,
                        reason, f"{DOCS}#{anchor}", claim=claim.quantity, setting=at)


def _always_higher_row(item: str, anchor: str, x: str, where: str, n: int,
                       gaps: list[tuple[float, PairedBinary]], at: str = "") -> dict[str, Any]:
    """"Always higher" (abstract, over separation) / "higher throughout" (Fig. 4):
    ``agrees`` when the paired interval lies above 0 at every value (each must be shown, so
    no adjustment is needed); ``differs`` when improved is shown *lower* somewhere (exact
    McNemar, Holm over the values); else ``inconclusive``. ``gaps``: ``(x value,
    improved against traditional)`` per value; ``reproduced`` is the smallest gap, for
    display."""
    not_shown = [(xv, g) for xv, g in gaps if not g.low > 0]
    holm = holm_adjusted([g.p for _, g in gaps])
    lower = [xv for (xv, g), q in zip(gaps, holm, strict=True)
             if g.x_only > g.y_only and q < ALPHA]
    word = claim_verdict(not not_shown, bool(lower))
    listed = ", ".join(_fmt_x(x, xv) + (" (the same outcome in every trial)"
                                        if g.x_only == g.y_only == 0 else f" ({points(g.diff)} "
                                        f"points, {points(g.low)} to {points(g.high)})")
                       for xv, g in not_shown)
    reason = ("paired interval above 0 at every value" if word == AGREES else
              "shown lower at " + ", ".join(_fmt_x(x, v) for v in lower) + " (exact McNemar, "
              f"Holm over the {len(gaps)} values)" if word == DIFFERS else
              f"not shown higher at {listed}; shown lower nowhere (exact McNemar, Holm over "
              f"the {len(gaps)} values)")
    xm, gm = min(gaps, key=lambda xg: xg[1].diff)
    separation = x == "target.separation"
    claim = ESM_RADAR.result("always higher" if separation else "higher throughout")
    return headline_row("Abstract" if separation else item,
                        f"smallest improved - traditional over the {len(gaps)} values, at "
                        f"{_fmt_x(x, xm)}{where}", "improved", claim.claim, float(gm.diff),
                        float(gm.low), float(gm.high), "fraction difference", n, word, reason,
                        f"{DOCS}#{anchor}", claim=claim.quantity, setting=at)


def _trend_rows(item: str, anchor: str, x: str, setting: str, rates: dict[str, pd.DataFrame],
                xs: list[tuple[float, int]], at: str = "") -> list[dict[str, Any]]:
    """"Both degrade" claims: rate at the hardest end minus rate at the easiest end of
    ``x`` per algorithm (paired over the trials, one pre-specified comparison), judged
    against the declared margin (:func:`~trackfuse.reportkit.verdicts.at_least`)."""
    hard, easy = (xs[0], xs[-1]) if x == "target.separation" else (xs[-1], xs[0])
    claim = ESM_RADAR.result("both degrade when close" if x == "target.separation"
                             else "both decline with range error")
    out = []
    for name, r in rates.items():
        change = paired_binary(r[easy[1]].to_numpy(), r[hard[1]].to_numpy())
        verdict = at_least(float(change.diff), float(change.low), float(change.high),
                           claim.margin, "a decline")
        out.append(headline_row(item, f"rate at {_fmt_x(x, hard[0])} minus at "
                                f"{_fmt_x(x, easy[0])}" + (f" ({setting})" if setting else ""),
                                name, "declines", verdict.estimate, verdict.low, verdict.high,
                                "fraction difference", len(r), verdict.word,
                                verdict.reason + " (same runs, Newcombe's paired interval)",
                                f"{DOCS}#{anchor}", claim=claim.quantity, setting=at))
    return out


#: Swept key -> (paper figure, docs anchor) of the paper's curves against it.
PAPER_CURVES = {"target.separation": ("Fig. 3", "fig-3-separation"),
                "radar.sigma_range_coef": ("Fig. 4", "fig-4-radar-range-error")}


def _curve_rows(run: RunData) -> list[dict[str, Any]]:
    """Fig. 3 / Fig. 4 / abstract claims, for each such axis swept over at least 2 values
    with both of the paper's methods run."""
    trials, out = run.trials, []
    if not set(PAPER_PAIR) <= set(trials["algorithm"]):
        return out
    rates = {name: _correct_by_point(trials, name) for name in PAPER_PAIR}
    for x, (item, anchor) in PAPER_CURVES.items():
        if len(run.sweep.get(x, [])) < 2:
            continue
        for setting, at, xs in _sweep_groups(run, x):
            out += _trend_rows(item, anchor, x, setting, rates, xs, at)
            out += _gap_rows(item, anchor, x, setting, rates["improved"],
                             rates["traditional"], xs, at)
    return out


def paper_vs_reproduced(run: RunData) -> pd.DataFrame:
    """What paper 001 reports against this run, in :data:`HEADLINE_COLUMNS`.

    * Table 3: correct rate of ``improved`` and ``traditional`` at every point at the paper's
      setting (:data:`PAPER_TABLE3_SETTING`), 95 % Wilson interval; judged against the
      paper's 370 / 276 of 500 runs as two samples (:func:`_table3_rows`).
    * Table 1: lambda_max, CI, CR and the five AHP weights, computed exactly; compared as
      printed (:func:`_ahp_rows`).
    * Fig. 3 / Fig. 4 / abstract, when separation or radar range error is swept: the claims
      as paired differences over the same trials (trials share their random numbers across
      sweep points), judged against the margins declared on the paper's items
      (:data:`trackfuse.reported.ESM_RADAR`; :func:`_trend_rows`, :func:`_gap_rows`,
      :func:`_narrowing_row`, :func:`_always_higher_row`).
    """
    rows = _table3_rows(run) + _ahp_rows() + _curve_rows(run)
    table = pd.DataFrame(rows, columns=list(HEADLINE_COLUMNS))
    return table.astype({"trials": "Int64"})


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

#: Axis label of each numeric swept key (unit included) and how its values are scaled.
AXES = {
    "target.separation": ("T1-T2 separation (m)", 1.0),
    "radar.sigma_range_coef": ("radar range error sd (% of range)", 100.0),
    "phase.d_over_lambda": ("interferometer spacing d/λ (1)", 1.0),
    "snake.amplitude": ("snake amplitude (m)", 1.0),
    "alpha.max": ("α_max (1)", 1.0),
}
#: Words for the values of categorical keys.
WORDS = {("radar.factor_model", "table"): "radar TDOA/phase with their own noise",
         ("radar.factor_model", "derived"): "radar TDOA/phase derived from its position",
         ("alpha.index", "nis_tdoa"): "NIS index", ("alpha.index", "literal"): "literal index",
         ("alpha.max_mode", "chi2"): "α_max chi-square", ("alpha.max_mode", "fixed"): "α_max fixed",
         ("alpha.max_mode", "running_max"): "α_max running maximum"}
#: Words of the figures' panel titles and category labels for categorical keys (the tables
#: keep :data:`WORDS`): the radar-factor model named by its config value, what it means below.
TITLE_WORDS = {("radar.factor_model", "table"):
               "radar factors 'table'\n(own TDOA/phase noise)",
               ("radar.factor_model", "derived"):
               "radar factors 'derived'\n(TDOA/phase from position)",
               ("baseline.spread", "nominal"): "spread static, nominal geometry",
               ("baseline.spread", "trial_mean"): "spread static, trial mean",
               ("baseline.spread", "per_sample"): "spread recomputed per sample"}
#: Swept keys whose value the paper does not give, by their symbol: the paper's Table 3
#: values drawn at every value of such a key say so.
PAPER_GIVES_NO = {"phase.d_over_lambda": "d/λ"}
#: Paper figure drawn by ``correct_rate`` for each numeric swept key.
PAPER_FIGURE = {"target.separation": "Fig. 3", "radar.sigma_range_coef": "Fig. 4"}
#: The algorithms of each correct-rate figure: the paper's pair and ours, the ablations
#: (beside the paper's method), the chi-square references (beside the paper's pair).
GROUPS = {"correct_rate": ("improved", "traditional", "improved_gauss"),
          "correct_rate_ablations": ("improved", "traditional_5f", "improved_static",
                                     "improved_no_range", "improved_3f", "improved_l2"),
          "correct_rate_references": ("improved", "traditional", "chi2", "chi2_lrt", "chi2_5f")}
#: What the other groups draw, in their titles (``correct_rate``: :func:`_methods_words`).
GROUP_TITLES = {"correct_rate_ablations": "ablations",
                "correct_rate_references": "chi-square ML references"}
CHANCE = 0.5  # T1 or T2 at random: track 3 is never chosen
#: How chance is drawn: dotted grey, apart from the dashed chi-square references.
CHANCE_STYLE = {"color": "0.5", "linestyle": ":", "linewidth": 1.2}
#: Marker and line style of each chi-square reference (their looks have no marker), in both
#: layouts, so that the references stay apart from each other and from chance.
REFERENCE_STYLES = {"chi2": ("o", "--"), "chi2_lrt": ("X", "-."),
                    "chi2_5f": ("d", (0, (4, 1, 1, 1, 1, 1)))}
#: End of the rate axis (%): a line at 100 % stays clear of the spine (markers there are
#: drawn unclipped, whole, however short the axes).
RATE_TOP = 104.0


def _value_words(key: str, value: Any) -> str:
    """A swept value in words (``separation 200 m``, ``radar range sd 1 %``)."""
    if (key, value) in WORDS:
        return WORDS[key, value]
    if key in AXES:
        label, scale = AXES[key]
        name, _, unit = label.rpartition(" (")
        unit = unit.rstrip(")")
        return f"{name} {scale * float(value):g}" + ("" if unit == "1" else
                                                      f" {unit.replace('% of range', '%')}")
    return f"{key} = {value}"


def _numeric_axis(config: Mapping[str, Any], summary: pd.DataFrame) -> str | None:
    """The first numeric swept key with at least two values, else None."""
    for key in swept_keys(config):
        if pd.api.types.is_numeric_dtype(summary[key]) and len(config["sweep"][key]) > 1:
            return key
    return None


#: Grids up to this many values get a labelled tick at every value.
MAX_LABELLED = 9


def _set_x_axis(ax: Axes, key: str, values: np.ndarray) -> None:
    """Label the x axis; a log axis (its label says so) only for a wide grid
    (:func:`~trackfuse.plots.style.wants_log_axis`), ticked with plain numbers, else
    linear. Up to :data:`MAX_LABELLED` values every grid value is ticked and labelled; a
    longer log grid is ticked at 1, 2, 5 x 10^k."""
    label, _ = AXES.get(key, (key, 1.0))
    values = np.unique(values)
    log = wants_log_axis(values)
    if log:
        label = f"{label[:-1]}, log scale)" if label.endswith(")") else f"{label} (log scale)"
    ax.set_xlabel(label)
    if log:
        ax.set_xscale("log")
        ticks = values if len(values) <= MAX_LABELLED else [
            v for m in (1, 2, 5) for v in m * 10.0 ** np.arange(-3, 7)
            if values.min() <= v <= values.max()]
        ax.set_xticks(sorted(ticks))
        ax.xaxis.set_minor_formatter(NullFormatter())
    elif len(values) <= MAX_LABELLED:
        ax.set_xticks(values)
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))


def _title_words(key: str, value: Any) -> str:
    """A swept value in a panel title (:data:`TITLE_WORDS`, else :func:`_value_words`)."""
    return TITLE_WORDS.get((key, value)) or _value_words(key, value)


def _panels(summary: pd.DataFrame, keys: Sequence[str]) -> list[tuple[str, pd.DataFrame]]:
    """(title, rows) per combination of ``keys`` in the summary (one panel each)."""
    if not keys:
        return [("", summary)]
    return [("; ".join(_title_words(k, v) for k, v in zip(keys, np.atleast_1d(key),
                                                          strict=True)), g)
            for key, g in summary.groupby(list(keys), sort=False)]


def _paper_xs(run: RunData, rows: pd.DataFrame, x: str | None) -> list[float]:
    """The x values (scaled; 0 with no x) of the points in ``rows`` at the paper's setting
    (:func:`at_paper_setting`): where its Table 3 values belong."""
    scale = AXES.get(x, (x, 1.0))[1]
    points = (run.point_params(int(p)) for p in rows["point"].unique())
    return sorted({scale * float(p[x]) if x else 0.0 for p in points if at_paper_setting(p)})


#: How far right of their setting the paper's values are drawn on a curve panel (points),
#: so that our marker at that setting stays in sight beside the paper's.
PAPER_DODGE_PT = 9.0
#: Drawing order of the paper's values: above our bands (1), below our curves, markers and
#: error bars (2 and 3, :func:`trackfuse.plots.algorithms.line_kwargs`).
PAPER_ZORDER = 1.5
#: Sideways offsets (points) of the curves drawn with error bars (variants, references), by
#: their order in the figure: beside the banded curves' markers and each other's, so that
#: equal rates stay in sight; their data stay at the grid values. Constant on the page:
#: 3 points is about 6 % of x on the separation axis (50 m to 2 km in a panel 2.8 in wide),
#: so that a cluster stays at its setting, well apart from 750 m and 1000 m.
BAR_DODGE_PT = (-3.0, 3.0, -6.0, 6.0, -9.0, 9.0)
#: Drawing order of the curves with error bars: thin, above the thick banded ones (3).
BAR_ZORDER = 3.5
#: Room (fraction of the data range) each side of a curve panel's x data, for the markers
#: drawn aside (:data:`PAPER_DODGE_PT`, :data:`BAR_DODGE_PT`).
X_MARGIN = 0.08
#: A numeric swept key with at most this many values is drawn as categories, not as a
#: curve: two settings ("no weave" and "weave") joined by a line would suggest a trend.
MAX_CATEGORIES = 2
#: Sideways step (in categories) between the methods drawn side by side in one category.
CATEGORY_STEP = 0.13
#: Marker size (points) of a rate drawn with its error bar alone (categories, rows).
DOT_MARKER = 6.0


def _paper_markers(ax: Axes, names: Sequence[str],
                   place: Callable[[float, str], tuple[list[float], list[float]]],
                   where: str = "", dodge_pt: float = 0.0) -> None:
    """The paper's Table 3 rates (%) as open stars in each method's colour, under our
    markers, where ``place(value, name)`` puts them (data ``(xs, ys)``), drawn ``dodge_pt``
    points to the right; ``where`` ends the legend label."""
    transform = offset_copy(ax.transData, fig=ax.figure, x=dodge_pt, units="points")
    for name in (n for n in PAPER_PAIR if n in names):
        value = 100 * ESM_RADAR.result(f"{name}: correct rate").value
        xs, ys = place(value, name)
        if not xs:
            continue
        ax.plot(xs, ys, linestyle="none", marker="*", markersize=11, markerfacecolor="white",
                markeredgecolor=look(name).colour, markeredgewidth=1.4, zorder=PAPER_ZORDER,
                transform=transform, label=f"paper's Table 3: {name} {value:.1f} %{where}")


def _rate_arrays(rows: pd.DataFrame, name: str, x: str) -> tuple[pd.DataFrame, np.ndarray,
                                                                  np.ndarray, np.ndarray]:
    """The rows of ``name`` sorted by ``x`` and its rate, interval low and high (%)."""
    g = rows[rows["algorithm"] == name].sort_values(x)
    return g, *(100 * g[c].to_numpy(float) for c in ("mean", "ci_low", "ci_high"))


def _curve_panel(ax: Axes, rows: pd.DataFrame, x: str, names: Sequence[str],
                 paper_xs: Sequence[float]) -> None:
    """Correct rate (%) of ``names`` against ``x`` with 95 % Wilson intervals: bands for
    the emphasised methods, error bars for the others (:data:`BAR_DODGE_PT` aside); the
    paper's values at ``paper_xs``."""
    scale = AXES.get(x, (x, 1.0))[1]
    barred = [n for n in names if not look(n).emphasised]
    for name in names:
        g, mean, lo, hi = _rate_arrays(rows, name, x)
        xs = scale * g[x].to_numpy(float)
        kw = {**line_kwargs(name), "clip_on": False}  # a marker at 100 % is drawn whole
        if look(name).role == "paper":  # on top of ours where both reach 100 %
            kw["zorder"] += 0.1
        if name not in barred:
            band(ax, xs, mean, lo, hi, **kw)
            continue
        marker, style = REFERENCE_STYLES.get(name, (kw["marker"], kw["linestyle"]))
        aside = offset_copy(ax.transData, fig=ax.figure,
                            x=BAR_DODGE_PT[barred.index(name)], units="points")
        ax.errorbar(xs, mean, yerr=[mean - lo, hi - mean], transform=aside, capsize=1.5,
                    elinewidth=0.8, **{**kw, "marker": marker, "linestyle": style,
                                       "zorder": BAR_ZORDER})
    _paper_markers(ax, names, lambda v, _: (list(paper_xs), [v] * len(paper_xs)),
                   ", drawn just right of its setting", PAPER_DODGE_PT)
    _set_x_axis(ax, x, scale * rows[x].to_numpy(float))
    ax.margins(x=X_MARGIN)
    _rate_axis_lines(ax)


def _rate_axis_lines(ax: Axes) -> None:
    """Chance (dotted) and the y label of a panel with the rate on y."""
    reference_line(ax, 100 * CHANCE, "chance between T1 and T2 (50 %)", **CHANCE_STYLE)
    ax.set_ylabel("correct association\nrate (%)")


def _category_words(x: str, value: float) -> str:
    """A category's tick label: ``no weave (0 m)`` / ``weave (1000 m)`` for the snake
    amplitude, else the axis symbol and value (``d/λ = 0.5``, ``separation = 200 m``)."""
    if x == "snake.amplitude":
        return f"{'weave' if value > 0 else 'no weave'} ({value:g} m)"
    label, scale = AXES.get(x, (x, 1.0))
    name, _, unit = label.rpartition(" (")
    unit = unit.rstrip(")")
    return f"{name.split()[-1]} = {scale * value:g}" + ("" if unit == "1" else f" {unit}")


def _category_panel(ax: Axes, rows: pd.DataFrame, x: str, names: Sequence[str],
                    paper_xs: Sequence[float]) -> None:
    """Correct rate (%) of ``names`` at each value of ``x`` drawn as a category: markers
    with 95 % Wilson error bars side by side (:data:`CATEGORY_STEP`), no line joining the
    categories; the paper's values right of the methods at ``paper_xs`` (scaled x)."""
    scale = AXES.get(x, (x, 1.0))[1]
    values = sorted(rows[x].unique())
    shifts = CATEGORY_STEP * (np.arange(len(names)) - (len(names) - 1) / 2)
    for name, shift in zip(names, shifts, strict=True):
        g, mean, lo, hi = _rate_arrays(rows, name, x)
        kw = {**line_kwargs(name), "clip_on": False}
        slots = [values.index(v) + shift for v in g[x]]
        ax.errorbar(slots, mean, yerr=[mean - lo, hi - mean], capsize=2, **{
            **kw, "marker": REFERENCE_STYLES.get(name, (kw["marker"],))[0],
            "linestyle": "none", "markersize": DOT_MARKER})
    at = [i + shifts[-1] + CATEGORY_STEP for i, v in enumerate(values)
          if any(np.isclose(scale * v, p) for p in paper_xs)]
    _paper_markers(ax, names, lambda v, _: (at, [v] * len(at)), ", drawn right of our rates")
    ax.set_xticks(range(len(values)), [_category_words(x, v) for v in values])
    ax.set_xlim(-0.5, len(values) - 0.5)
    ax.grid(False, axis="x")
    ax.set_xlabel(AXES.get(x, (x,))[0])
    _rate_axis_lines(ax)


def _interval_entries(names: Sequence[str], layout: str) -> tuple[list, list[str]]:
    """Legend entries saying what the intervals of a curve or category figure of ``names``
    are: the emphasised methods' shaded bands and the others' error bars on curves, every
    method's error bars in categories."""
    handles, labels = [], []
    if layout == "curves" and any(look(n).emphasised for n in names):
        handles.append(Patch(facecolor="0.5", alpha=0.3))
        labels.append("shaded band: 95 % Wilson interval")
    if layout == "categories" or not all(look(n).emphasised for n in names):
        handles.append(Line2D([], [], color="0.3", marker="|", markersize=10, linestyle="none"))
        labels.append("error bar: 95 % Wilson interval"
                      + (", shifted sideways" if layout == "curves" else ""))
    return handles, labels


def _place(i: int, n: int, ncols: int) -> str:
    """Panel ``i`` of ``n`` (``ncols`` a row, row-major) in words."""
    if n <= ncols:
        return (("left", "right") if n == 2 else ("left", "middle", "right"))[i] + " panel"
    return f"panel in row {i // ncols + 1}, column {i % ncols + 1}"


def _coincidences(panels: Sequence[tuple[str, pd.DataFrame]], x: str, names: Sequence[str],
                  ncols: int) -> list[str]:
    """A sentence for each curve of ``names`` equal to an earlier one at every x of a panel
    (their lines lie on each other there), naming the panels unless it is all of them."""
    found: dict[tuple[str, str], list[int]] = {}
    for i, (_, rows) in enumerate(panels):
        means = {n: rows[rows["algorithm"] == n].sort_values(x)["mean"].to_numpy()
                 for n in names}
        for j, b in enumerate(names):
            same = [a for a in names[:j] if len(means[b]) and np.array_equal(means[a],
                                                                             means[b])]
            if same:
                found.setdefault((b, same[0]), []).append(i)
    return [("" if len(at) == len(panels) else
             " and ".join(_place(i, len(panels), ncols) for i in at) + ": ")
            + f"{look(b).label} coincides with {look(a).label}" for (b, a), at in found.items()]


def _star_rows(entries: Sequence[tuple[str, str, pd.Series, bool]], ys: Sequence[float]
               ) -> dict[str, list[float]]:
    """Per algorithm, the y of the paper's value (0.3 below the row) in every row of
    ``entries`` at the paper's setting (:func:`_dot_rows`)."""
    out: dict[str, list[float]] = {}
    for (_, name, _, at), y in zip(entries, ys, strict=True):
        if at:
            out.setdefault(name, []).append(y - 0.3)
    return out


def _dot_rows(ax: Axes, entries: Sequence[tuple[str, str, pd.Series, bool]]) -> None:
    """Table 3 layout: one row per entry ``(tick label, algorithm, its summary row, at the
    paper's setting)``, top down, our rate (%) with its Wilson interval and, at the paper's
    setting, the paper's value (open star) just below it."""
    ys = np.arange(len(entries), dtype=float)[::-1]
    for (_, name, g, _), y in zip(entries, ys, strict=True):
        lk = look(name)
        ax.errorbar(100 * g["mean"], y, xerr=[[100 * (g["mean"] - g["ci_low"])],
                                              [100 * (g["ci_high"] - g["mean"])]],
                    fmt=REFERENCE_STYLES.get(name, (lk.marker or "o",))[0], color=lk.colour,
                    markersize=DOT_MARKER + 1, capsize=4, clip_on=False,
                    linewidth=2.0 if lk.emphasised else 1.0)
    ax.plot([], [], marker="o", color="k", label="this run: rate, 95 % Wilson interval")
    stars = _star_rows(entries, ys)
    _paper_markers(ax, list(stars), lambda v, name: ([v] * len(stars[name]), stars[name]))
    ax.axvline(100 * CHANCE, label="chance between T1 and T2 (50 %)", **CHANCE_STYLE)
    ax.set_yticks(list(ys), [label for label, *_ in entries])
    ax.set_ylim(-0.8, len(entries) - 0.4)
    ax.set_xlabel("correct association rate (%)")


def _rate_legend(axes: Sequence[Axes], names: Sequence[str], layout: str
                 ) -> tuple[list, list[str]]:
    """Legend entries of a rate figure: the methods in the order of ``names``, then (curves,
    categories) what the intervals are, then the rest (the paper's values, chance)."""
    handles, labels = legend_entries(axes)
    order = [look(n).label for n in names]
    if layout in ("curves", "categories"):
        extra = _interval_entries(names, layout)
        handles, labels, order = handles + extra[0], labels + extra[1], order + extra[1]
    ranked = sorted(zip(handles, labels, strict=True),
                    key=lambda e: order.index(e[1]) if e[1] in order else len(order))
    return [h for h, _ in ranked], [lab for _, lab in ranked]


def _methods_words(names: Collection[str]) -> str:
    """The ``correct_rate`` methods among ``names`` in words ("the paper's methods and
    ours", "the paper's baseline", ...)."""
    pair = tuple(n for n in PAPER_PAIR if n in names)
    words = {PAPER_PAIR: "the paper's methods", ("improved",): "the paper's method",
             ("traditional",): "the paper's baseline", (): ""}[pair]
    if "improved_gauss" in names:
        words = f"{words} and ours" if words else "ours"
    return words


def _rate_title(run: RunData, group: str, x: str | None, names: Sequence[str],
                at_setting: bool) -> str:
    """Two-line suptitle: the paper item redrawn (both of the paper's methods drawn, Table 3
    only at its setting) or in its layout with what is drawn, else what is drawn; the trials
    and fixed settings."""
    what = "correct association rate" + (f" vs {AXES.get(x, (x,))[0].split(' (')[0]}"
                                         if x else "")
    item = PAPER_FIGURE.get(x, "Table 3" if x is None else "")
    paper = group == "correct_rate" and item and (x is not None or at_setting)
    drawn = _methods_words(names) if group == "correct_rate" else GROUP_TITLES[group]
    if paper and set(PAPER_PAIR) <= set(names):
        head, tail = f"Paper 001 {item} redrawn: {what}", ""
    elif paper:
        head, tail = f"Paper 001 {item} layout: {what}", f"{drawn.capitalize()} only; "
    else:
        head, tail = f"Paper 001, {drawn}: {what}", ""
    fixed = [_value_words(k, run.params[k]) for k in PAPER_TABLE3_SETTING if k not in run.sweep]
    if "radar.factor_model" not in run.sweep:  # the setting every rate here depends on
        fixed.append(f"radar factors '{run.params['radar.factor_model']}'")
    return (f"{head}\n{tail}{run.config['trials']} trials per point; " + "; ".join(fixed)
            + ("" if paper else "; not a figure of the paper"))


#: Width (in) of a figure printed across a two-column page: a rate figure of several panels
#: is drawn at it, so that its text prints at its own size.
#: wide a character of it is (in ems), to wrap a suptitle to the figure's width.
SUPTITLE_PT, CHAR_EM = 10.8, 0.53


def _layout(x: str | None, summary: pd.DataFrame, names: Sequence[str], n_panels: int
            ) -> str:
    """How a rate figure is laid out: ``curves`` against a numeric ``x`` of more than
    :data:`MAX_CATEGORIES` values, ``categories`` for fewer; without ``x`` one row per
    method in each panel (``rows``), or for one method one panel with a row per setting of
    the other swept keys (``settings``: three panels of one dot each filled a 2 x 2 grid)."""
    if x is not None:
        return "categories" if summary[x].nunique() <= MAX_CATEGORIES else "curves"
    return "settings" if len(names) == 1 and n_panels > 1 else "rows"


def _rate_columns(layout: str, n_panels: int) -> int:
    """Panels a row: up to 3 on x (curves, categories), up to 2 in the rows layout."""
    return 1 if layout == "settings" else min(n_panels, 3 if layout in (
        "curves", "categories") else 2)


def _rate_axes(layout: str, n_panels: int, n_rows: int) -> tuple[Figure, np.ndarray]:
    """The figure and one axes per panel (row-major) of a rate figure: several panels at
    :data:`PAGE_WIDTH_IN` wide, one narrower; a rows layout ``n_rows`` rows tall."""
    ncols = _rate_columns(layout, n_panels)
    n_axes = 1 if layout == "settings" else n_panels
    across = layout in ("curves", "categories")
    width = PAGE_WIDTH_IN / ncols if ncols > 1 else (4.8 if across else 6.0)
    fig, axes = new_figure(ncols=ncols, nrows=-(-n_axes // ncols), width=width,
                           height=CURVE_ROW_IN if across else 0.55 * n_rows + 2.0)
    axes = np.atleast_1d(axes)
    for ax in axes[n_axes:]:
        ax.set_visible(False)
    return fig, axes[:n_axes]


def _algorithm_row(rows: pd.DataFrame, name: str) -> pd.Series:
    """The summary row of ``name`` in a one-point ``rows``."""
    return rows[rows["algorithm"] == name].iloc[0]


def _draw_rate_panels(axes: Sequence[Axes], layout: str,
                      panels: Sequence[tuple[str, pd.DataFrame]], names: Sequence[str],
                      x: str | None, paper_xs: Sequence[Sequence[float]]) -> None:
    """Draw every panel of a rate figure in its ``layout`` (:func:`_layout`), titled."""
    row = _algorithm_row
    if layout == "settings":
        (name,) = names
        _dot_rows(axes[0], [(title, name, row(rows, name), bool(at))
                            for (title, rows), at in zip(panels, paper_xs, strict=True)])
        axes[0].set_title(look(name).label)
        return
    for ax, (title, rows), at in zip(axes, panels, paper_xs, strict=True):
        if layout == "rows":
            _dot_rows(ax, [(look(n).label, n, row(rows, n), bool(at)) for n in names])
        else:
            (_curve_panel if layout == "curves" else _category_panel)(ax, rows, x, names, at)
        ax.set_title(title)


def _star_notes(run: RunData, drawn: bool) -> list[str]:
    """When the paper's Table 3 values are drawn: a sentence for each swept key the paper
    gives no value of (:data:`PAPER_GIVES_NO`), at every value of which they are drawn."""
    return [f"paper's Table 3 values drawn at every {symbol}: the paper gives no {symbol}"
            for key, symbol in PAPER_GIVES_NO.items() if drawn and key in run.sweep]


def _balanced(text: str, chars: int) -> int:
    """A line width for wrapping ``text`` into as few lines of at most ``chars`` as
    :func:`textwrap.wrap` needs, about equally long (not a last line of one word)."""
    lines = len(textwrap.wrap(text, chars))
    return min(chars, -(-len(text) // lines) + 12) if lines > 1 else chars


def _wrap_suptitle(fig: Figure, title: str) -> None:
    """``title`` as ``fig``'s suptitle, each line wrapped to the figure's width between its
    ``; ``-separated parts, a part longer than a line between its words."""
    chars = int(fig.get_figwidth() * 72 / (SUPTITLE_PT * CHAR_EM))
    lines: list[str] = []
    for line in title.split("\n"):
        lines.append("")
        pieces = [(k == 0, piece) for whole in line.split("; ")
                  for k, piece in enumerate(textwrap.wrap(whole, _balanced(whole, chars)))]
        for first, piece in pieces:
            sep = ";" if first else ""
            joined = f"{lines[-1]}{sep} {piece}" if lines[-1] else piece
            if len(joined) > chars and lines[-1]:
                lines[-1] += sep
                lines.append(piece)
            else:
                lines[-1] = joined
    fig.suptitle("\n".join(lines))


def _rate_figure(run: RunData, group: str) -> Figure | str:
    """One correct-rate figure (``group`` of :data:`GROUPS`), from ``summary.csv``."""
    s = run.summary[run.summary["metric"] == "correct"]
    names = [n for n in GROUPS[group] if n in set(s["algorithm"])]
    if group != "correct_rate":
        names = names if set(names) - set(PAPER_PAIR) else []
    if not names:
        return (f"none of {', '.join(GROUPS[group])} was run"
                if group == "correct_rate" else
                f"no algorithm of this group ({', '.join(GROUPS[group][1:])}) was run")
    x = _numeric_axis(run.config, s)
    panels = _panels(s, [k for k in swept_keys(run.config) if k != x])
    if len(panels) > 9:
        return f"{len(panels)} panels (more than 9 combinations of the other swept keys)"
    layout = _layout(x, s, names, len(panels))
    fig, axes = _rate_axes(layout, len(panels),
                           len(panels) if layout == "settings" else len(names))
    paper_xs = [_paper_xs(run, rows, x) if group == "correct_rate" else [] for _, rows in panels]
    _draw_rate_panels(axes, layout, panels, names, x, paper_xs)
    _share_rate_axis(axes, "y" if x else "x", s)
    legend_below(fig, *_rate_legend(axes, names, layout))
    notes = _star_notes(run, any(paper_xs)) + (  # said above the legend's entries
        _coincidences(panels, x, names, _rate_columns(layout, len(panels)))
        if layout == "curves" else [])
    if notes:
        fig.legends[-1].set_title("\n".join(notes))
    _wrap_suptitle(fig, _rate_title(run, group, x, names, any(paper_xs)))
    if x:
        _grow_for_legend(fig)
        _upright_crowded_ticks(fig, axes)
    return fig


#: Height (inches) of a row of curve panels with their titles and tick labels; the figure
#: gets its legend's height on top (:func:`_grow_for_legend`).
CURVE_ROW_IN = 3.0


def _grow_for_legend(fig: Figure) -> None:
    """Make ``fig`` taller by its legend's height (inches), so that a long legend (many
    entries, a note on coinciding curves) leaves its panels the height of a short one's,
    taller than their y labels."""
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    legend = fig.legends[-1].get_window_extent(fig.canvas.get_renderer())
    fig.set_figheight(fig.get_figheight() + legend.height / fig.dpi)


def _upright_crowded_ticks(fig: Figure, axes: Sequence[Axes]) -> None:
    """Turn the x tick labels of ``axes`` upright when two neighbours would touch
    (every grid value is labelled: 750 / 1000 / 1500 / 2000 m on a log axis).

    Only the layout is computed to measure them (the panels placed where drawing places
    them), not a full draw: saving lays the figure out again from there, as after a draw.
    """
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    renderer = fig.canvas.get_renderer()
    if (engine := fig.get_layout_engine()) is not None:
        engine.execute(fig)
    for ax in axes:
        boxes = sorted((t.get_window_extent(renderer) for t in ax.get_xticklabels()
                        if t.get_visible() and t.get_text()), key=lambda b: b.x0)
        if any(a.x1 + 2 > b.x0 for a, b in zip(boxes, boxes[1:], strict=False)):
            ax.tick_params(axis="x", labelrotation=90)


def _share_rate_axis(axes: Sequence[Axes], which: str, summary: pd.DataFrame) -> None:
    """One rate range (%) for every panel, from just below the lowest interval (and below
    chance) to :data:`RATE_TOP`; with shared y the inner panels drop their tick labels."""
    low = min(40.0, 10 * np.floor((100 * summary["ci_low"].min() - 2) / 10))
    for i, ax in enumerate(axes):
        (ax.set_ylim if which == "y" else ax.set_xlim)(low, RATE_TOP)
        if which == "x" and i % 2:
            ax.tick_params(labelleft=False)


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
    """``(algorithm, (N, K) range weights)`` of ``improved`` (else the first dynamic-weight
    algorithm) at ``point`` for ``trial_ids``, or None if no such rows."""
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
    ax.set_title(f"one trial; separation {params['target.separation']:g} m;\nsensors at "
                 f"(0, 0) and ({params['geometry.baseline'] / 1e3:g} km, 0)")


def _index_panel(ax: Axes, run: RunData, row: pd.Series, params: Mapping[str, Any]) -> None:
    """One trial's manoeuvre index (log) and, on a twin axis, its range weight per scan."""
    t = esm_times(params)
    ax.plot(t, decode_series([row["alpha_per_scan"]])[0], color="0.2",
            label=f"manoeuvre index α(k) ({params['alpha.index']})")
    a_max, mode = alpha_max(params)
    if mode == "fixed":
        ax.axhline(a_max, color="0.2", linestyle=":", linewidth=1.0, label="α_max")
    ax.set_yscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("manoeuvre index α\n(1, log scale)")
    weights = _weight_series(run.trials, int(row["point"]), [int(row["trial"])])
    if weights is not None:
        name, a1 = weights
        twin = ax.twinx()
        twin.plot(t, a1[0], color=look(name).colour, linewidth=2.0,
                  label=f"range weight a₁(k), {name}")
        twin.axhline(static_weights(FACTORS, params["weights"])[0], color=look(name).colour,
                     linestyle=":", linewidth=1.0, label="static AHP range weight")
        twin.set_ylim(0, 0.7)
        twin.set_ylabel("range weight a₁ (1)")
        twin.grid(False)
    ax.set_title("one trial: index" + (" and range weight" if weights else "") + " per scan"
                 + ("" if weights else "\n(no dynamic-weight algorithm run)"))


def _range_error_panel(ax: Axes, esm: pd.DataFrame, params: Mapping[str, Any]) -> None:
    """RMS and median absolute ESM range error (m, log) per scan over the saved trials."""
    t = esm_times(params)
    err = decode_series(esm["esm_range_error_per_scan_m"])
    ax.plot(t, np.sqrt(np.nanmean(err**2, axis=0)), color=ESM_COLOUR,
            label="RMS ESM range error")
    ax.plot(t, np.nanmedian(np.abs(err), axis=0), color=ESM_COLOUR, linestyle="--",
            label="median |ESM range error|")
    ax.axhline(params["target.separation"], color="0.5", linewidth=1.0,
               label="T1-T2 separation")
    ax.set_yscale("log")
    ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ESM range error\n(m, log scale)")
    ax.set_title(f"all {len(esm)} trials of this point")


#: Characters per line of a panel title at the house title size in a panel of half the
#: page's width (about 3 in).
PANEL_TITLE_CHARS = 36

TRAJECTORY_SIZE = (8.6, 6.4)
"""Width and height (in) of the trajectory figure: readable at a page's 7 in (it was 12.9 in
wide, its tick labels under 5 pt there)."""

TRAJECTORY_TITLE_CHARS = 88
"""Characters per title line of the trajectory figure (about 10 per inch at the title's
size)."""


def _trajectory_figure(run: RunData) -> Figure | str:
    """Paper 001 Figs. 1-2 from ``trials.csv``: the first saved trial of the first point
    with the paper's weave (:data:`PAPER_SCENARIO`; the paper's figures redrawn), else of
    the first point."""
    esm = _esm_rows(run.trials)
    if esm.empty:
        return NO_SERIES
    weave = [p for p in esm["point"].unique() if np.isclose(
        run.point_params(int(p))["snake.amplitude"], PAPER_SCENARIO["snake.amplitude"])]
    row = esm[esm["point"] == weave[0]].iloc[0] if weave else esm.iloc[0]
    point = int(row["point"])
    params = run.point_params(point)
    fig, axes = mosaic_figure([["tracks", "index"], ["tracks", "error"]], *TRAJECTORY_SIZE,
                              width_ratios=(1.0, 1.15))  # the map over two rows
    _tracks_panel(axes["tracks"], params, row)
    _index_panel(axes["index"], run, row, params)
    _range_error_panel(axes["error"], esm[esm["point"] == point], params)
    axes["tracks"].set_aspect("equal", adjustable="datalim")
    legend_below(fig, *legend_entries(fig.axes))
    where = _setting_words(params, swept_keys(run.config))
    amplitude = params["snake.amplitude"]
    head = ("Paper 001 Figs. 1-2 redrawn" if np.isclose(amplitude, PAPER_SCENARIO[
        "snake.amplitude"]) else f"Paper 001 Figs. 1-2 layout, snake amplitude {amplitude:g} m"
            f" (not the paper's {PAPER_SCENARIO['snake.amplitude']:g} m weave)")
    fig.suptitle(textwrap.fill(f"{head}: true tracks and the ESM TDOA-DF location of target 2",
                               TRAJECTORY_TITLE_CHARS) + (f"\n{where}" if where else ""))
    return fig


def _series_band(ax: Axes, t: np.ndarray, values: np.ndarray, label: str, colour: str,
                 shade: bool) -> None:
    """Mean over trials of ``values`` (N, K) against ``t`` with its 95 % t band (scans
    where every trial is defined)."""
    ok = np.isfinite(values).all(axis=0)
    v = values[:, ok]
    mean = v.mean(axis=0)
    if shade and len(v) > 1:
        lo, hi = t_interval(mean, v.std(axis=0, ddof=1), len(v))
        band(ax, t[ok], mean, lo, hi, label=label, marker="", color=colour)
    else:
        ax.plot(t[ok], mean, label=label, color=colour)


def _esm_groups(run: RunData, esm: pd.DataFrame) -> list[tuple[str, int, pd.DataFrame]]:
    """``(words, point, first rows)`` per setting of the swept keys that change the ESM
    track (:data:`ESM_TRACK_KEYS`), at its first point."""
    keys = [k for k in swept_keys(run.config) if k.startswith(ESM_TRACK_KEYS)]
    seen: dict[tuple, int] = {}
    for point, params in enumerate(run.points):
        seen.setdefault(tuple(params[k] for k in keys), point)
    return [(_setting_words(run.point_params(p), keys)
             or _value_words("snake.amplitude", run.point_params(p)["snake.amplitude"]), p,
             esm[esm["point"] == p]) for p in seen.values()]


def _manoeuvre_figure(run: RunData) -> Figure | str:
    """Mean manoeuvre index and mean range weight per scan, from ``trials.csv``; the index
    panel alone when no dynamic-weight algorithm was run."""
    esm = _esm_rows(run.trials)
    if esm.empty:
        return NO_SERIES
    groups = _esm_groups(run, esm)
    if len(groups) > 9:
        return f"{len(groups)} settings of the ESM track (more than 9 curves per panel)"
    weights = [_weight_series(run.trials, p, rows["trial"].tolist()) for _, p, rows in groups]
    weight_name = next((w[0] for w in weights if w is not None), "")
    fig, axes = new_figure(ncols=2 if weight_name else 1,
                           width=PAGE_WIDTH_IN / 2 if weight_name else 4.8,
                           height=CURVE_ROW_IN + 0.3)
    axes = np.atleast_1d(axes)
    ax = axes[0]
    colours = ["0.2"] if len(groups) == 1 else [
        matplotlib.colormaps["viridis"](i / (len(groups) - 1) * 0.9) for i in range(len(groups))]
    for (words, point, rows), colour, w in zip(groups, colours, weights, strict=True):
        t, shade = esm_times(run.point_params(point)), len(groups) <= 3
        _series_band(ax, t, decode_series(rows["alpha_per_scan"]), words, colour, shade)
        if w is not None:
            _series_band(axes[1], t, w[1], words, colour, shade)
    indices = _index_references(ax, [run.point_params(p) for _, p, _ in groups])
    ax.set_yscale("log")
    panels = [(ax, "manoeuvre index α\n(1, log scale)", "manoeuvre index" + (
        "" if weight_name else " (no range weight: no dynamic-weight algorithm was run)"))]
    if weight_name:
        static = static_weights(FACTORS, run.point_params(groups[0][1])["weights"])[0]
        axes[1].axhline(static, color=look(weight_name).colour, linestyle=":",
                        linewidth=1.0, label="static AHP range weight")  # not α_max's black
        axes[1].set_ylim(0, 0.7)
        panels.append((axes[1], "range weight a₁ (1)",
                       f"range weight of {look(weight_name).label}"))
    for a, ylabel, title in panels:
        a.set_xlabel("time (s)")
        a.set_ylabel(ylabel)
        a.set_title(textwrap.fill(title, PANEL_TITLE_CHARS))
    legend_below(fig, *legend_entries(axes))  # one legend for both panels, below them
    _grow_for_legend(fig)
    fig.suptitle(f"Manoeuvre index ({' and '.join(indices)})"
                 + (" and range weight" if weight_name else "") + " per scan (no paper figure)"
                 f"\nmean over {len(groups[0][2])} trials with 95 % t bands")
    return fig


def _index_references(ax: Axes, settings: Sequence[Mapping[str, Any]]) -> list[str]:
    """Draw the no-manoeuvre expectation (NIS index) and each fixed ``alpha_max`` of the
    ``settings`` (point params); return the indices used, in order of appearance."""
    indices = list(dict.fromkeys(p["alpha.index"] for p in settings))
    if "nis_tdoa" in indices:
        ax.axhline(1.0, color="0.5", linestyle="--", linewidth=1.0,
                   label="no-manoeuvre expectation E[α] = 1")
    limits = dict.fromkeys((*alpha_max(p), p["alpha.index"]) for p in settings)
    for (a_max, mode, index), style in zip(limits, (":", "-.", (0, (1, 3))) * 3,
                                           strict=False):
        if mode == "fixed":
            ax.axhline(a_max, color="k", linestyle=style, linewidth=1.0,
                       label="α_max" if len(indices) == 1 else
                       f"α_max, {_value_words('alpha.index', index)}")
    return indices


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """The ``wanted`` figures among :data:`GROUPS` (from ``summary.csv``), ``trajectory``
    and ``manoeuvre`` (from the per-scan columns of ``trials.csv``); a one-line reason
    string for a wanted figure this run cannot draw."""
    drawers: dict[str, Callable[[], Figure | str]] = {
        **{g: (lambda g=g: _rate_figure(run, g)) for g in GROUPS},
        "trajectory": lambda: _trajectory_figure(run),
        "manoeuvre": lambda: _manoeuvre_figure(run)}
    return {name: draw() for name, draw in drawers.items() if name in wanted}

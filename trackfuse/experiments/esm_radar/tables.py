"""The ``esm_radar`` report's tables, from a saved run: ``table3`` (paper 001's Table 3
layout), ``ablation`` (every algorithm against ``improved`` on the same trials), ``ahp``
(paper Table 1) and ``manoeuvre`` (index and range weight per point)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from trackfuse.association import ahp
from trackfuse.association.esm_scenario import FACTORS
from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    N_TRACKS,
    THREE,
    factor_names,
)
from trackfuse.reported import ESM_RADAR, ESM_RADAR_WEIGHTS
from trackfuse.reportkit.paired import against_reference
from trackfuse.reportkit.summarytable import per_point
from trackfuse.rundata import swept_keys
from trackfuse.stats import (
    wilson_interval,
)


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
    """Each algorithm against ``improved`` on the same trials (paired gain in ``correct``, exact
    McNemar, Holm over a point's variants and the sweep), described by factors, membership and
    weights; empty when ``improved`` was not run."""
    table = against_reference(trials, swept_keys(config), "correct", "improved")
    if table.empty:
        return table
    described = pd.DataFrame([_described(n, config["params"]) for n in table["algorithm"]])
    at = table.columns.get_loc("algorithm") + 1
    return pd.concat([table.iloc[:, :at], described, table.iloc[:, at:]], axis=1)


def _described(name: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """An algorithm's summary, factor count, membership and weights (ablation columns)."""
    v = ALGORITHMS[name]
    return {"description": v.summary, "factors": len(factor_names(v, params)),
            "membership": params["membership_norm"] if v.membership == "param" else v.membership,
            "weights": "-" if v.membership.startswith("chi2") else
            ("dynamic" if v.dynamic else "static")}


def manoeuvre_table(summary: pd.DataFrame, config: Mapping[str, Any]) -> pd.DataFrame:
    """Per point: the ESM track's mean manoeuvre index ``alpha_mean`` (over defined scans, then
    trials) and ``improved``'s mean range weight, each with its 95 % Student-t interval from
    ``summary.csv``."""
    first = summary["algorithm"].iloc[0]
    return per_point(summary, swept_keys(config),
                     {("alpha_mean", first): "alpha_mean",
                      ("range_weight_mean", "improved"): "improved_range_weight"})


def ahp_table() -> pd.DataFrame:
    """Paper 001 Table 1 weights by the root and eigenvector methods, per factor set (all five, the
    traditional three): weights, ``lambda_max``, ``CI``, ``CR`` and the paper's printed values."""

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

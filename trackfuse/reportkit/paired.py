"""Every algorithm against a reference algorithm on the same trials: the ablation table of a
0/1 metric (each change to a method against the method itself).

Trials share their random numbers across algorithms, so each comparison is paired: the gain
``rate(algorithm) - rate(reference)`` with Newcombe's paired 95 % interval, the discordant
trials and the exact McNemar test (Q. McNemar, Psychometrika 12, 1947, 153-157), adjusted by
Holm's method over the algorithms compared at a point and over the points of the run for one
algorithm (the family of a claim along a sweep).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from trackfuse.stats import holm_adjusted, paired_binary, wilson_interval


def against_reference(trials: pd.DataFrame, keys: Sequence[str], metric: str,
                      reference: str) -> pd.DataFrame:
    """One row per point (``point`` and ``keys``) and algorithm, in the trials' algorithm
    order: ``<metric>_rate`` with its Wilson interval (``_ci_low``/``_ci_high``),
    ``gain_vs_<reference>`` with Newcombe's paired interval, ``n_variant_only`` and
    ``n_<reference>_only`` discordant trials, ``mcnemar_p``, ``mcnemar_p_holm`` (over the
    algorithms of a point) and ``mcnemar_p_holm_sweep`` (over the points of an algorithm).
    The reference's own row is no comparison: gain 0, NaN interval and p-values. Empty when
    the reference was not run."""
    if reference not in set(trials["algorithm"]):
        return pd.DataFrame()
    group = ["point", *keys]
    wide = trials.pivot_table(index=[*group, "trial"], columns="algorithm", values=metric,
                              aggfunc="first")
    order = list(dict.fromkeys(trials["algorithm"]))
    gain, rows = f"gain_vs_{reference}", []
    for at, g in wide.groupby(level=group, sort=True):
        at = at if isinstance(at, tuple) else (at,)
        ref = g[reference].to_numpy()
        for name in order:
            x = g[name].to_numpy()
            low, high = wilson_interval(x.sum(), len(x))
            pair = paired_binary(ref, x)
            rows.append({**dict(zip(group, at, strict=True)), "algorithm": name,
                         f"{metric}_rate": x.mean(), f"{metric}_rate_ci_low": float(low),
                         f"{metric}_rate_ci_high": float(high), gain: float(pair.diff),
                         f"{gain}_ci_low": float(pair.low), f"{gain}_ci_high": float(pair.high),
                         "n_variant_only": int(pair.y_only),
                         f"n_{reference}_only": int(pair.x_only), "mcnemar_p": float(pair.p)})
    table = pd.DataFrame(rows)
    own = table["algorithm"] == reference
    table.loc[own, [f"{gain}_ci_low", f"{gain}_ci_high", "mcnemar_p"]] = np.nan
    table["mcnemar_p_holm"] = np.nan
    table["mcnemar_p_holm_sweep"] = np.nan
    for column, by in (("mcnemar_p_holm", group), ("mcnemar_p_holm_sweep", "algorithm")):
        for _, rows_ in table[~own].groupby(by, sort=False):
            table.loc[rows_.index, column] = holm_adjusted(rows_["mcnemar_p"])
    return table

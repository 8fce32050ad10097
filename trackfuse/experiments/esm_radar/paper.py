"""Paper 001's claims against an ``esm_radar`` run (:func:`paper_vs_reproduced`); numbers and
margins are in :data:`trackfuse.reported.ESM_RADAR`, rules in ``docs/statistics.md``."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from trackfuse.association import ahp
from trackfuse.association.esm_scenario import FACTORS
from trackfuse.experiments.esm_radar import EXPERIMENT
from trackfuse.reported import ESM_RADAR, ESM_RADAR_WEIGHTS
from trackfuse.reportkit import render
from trackfuse.reportkit.sweepclaims import higher_everywhere, narrows
from trackfuse.reportkit.verdicts import (
    DIFFERS,
    against_paper_sample,
    as_printed_verdict,
    at_least,
    printed_decimals,
    setting_text,
)
from trackfuse.reports import HEADLINE_COLUMNS, headline_row
from trackfuse.rundata import RunData, swept_keys
from trackfuse.stats import (
    PairedBinary,
    paired_binary,
    wilson_interval,
)

DOCS = "docs/papers/esm_radar.md"


#: Paper 001's Table 3 setting, by param key: T1-T2 separation (m) and the radar range sd
#: coefficient of its Table 2. Points of a run at other values are not compared with it.
PAPER_TABLE3_SETTING = {"target.separation": 200.0, "radar.sigma_range_coef": 0.01}
#: The paper's scenario beyond :data:`PAPER_TABLE3_SETTING`: its 1 km weave (a run's points
#: in straight flight are not compared with the paper's Table 3).
PAPER_SCENARIO = {"snake.amplitude": 1000.0}
#: The paper's method and its baseline, compared in every claim.
PAPER_PAIR = ("improved", "traditional")


def at_paper_setting(params: Mapping[str, Any]) -> bool:
    """Whether a point is at the paper's Table 3 setting and scene (its 74.0 % / 55.2 %)."""
    setting = {**PAPER_TABLE3_SETTING, **PAPER_SCENARIO}
    return all(np.isclose(float(params[k]), v) for k, v in setting.items())


def setting_words(point: Mapping[str, Any], keys: Sequence[str]) -> str:
    """A point's swept settings in words, so a headline row says which setting it judges."""
    return "; ".join(value_words(k, point[k]) for k in keys)


def _table3_rows(run: RunData) -> list[dict[str, Any]]:
    """Paper Table 3 correct rates against every point at its setting, as two samples."""
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
                + (f" ({setting_words(params, keys)})" if keys else ""), name, item.value,
                x.mean(), lo, hi, "fraction", len(x), verdict.word, verdict.reason + why,
                f"{DOCS}#w001-2-radar-tdoa-and-phase" if why else f"{DOCS}#table-3",
                claim=item.quantity, setting=setting_text({k: params[k] for k in swept})))
    return out


def _ahp_rows() -> list[dict[str, Any]]:
    """Paper Table 1 against the exact AHP computation, compared as printed."""
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
    """``correct`` of ``name`` as a (trial x point) frame, paired across points."""
    rows = trials[trials["algorithm"] == name]
    return rows.pivot(index="trial", columns="point", values="correct").sort_index()


def _sweep_groups(run: RunData, x: str) -> list[tuple[str, str, list[tuple[float, int]]]]:
    """Points grouped by the swept keys other than ``x``:
    ``(words, setting, [(x, point), ...])``."""
    others = [k for k in swept_keys(run.config) if k != x]
    groups: dict[tuple, list[tuple[float, int]]] = {}
    for point, params in enumerate(run.points):
        groups.setdefault(tuple(params[k] for k in others), []).append((float(params[x]), point))
    return [(setting_words(values, others), setting_text(values), sorted(members))
            for key, members in groups.items()
            for values in [dict(zip(others, key, strict=True))]]


def _fmt_x(x: str, value: float) -> str:
    """A swept value in words with its unit (``200 m``, ``1 %``)."""
    return f"{100 * value:g} %" if x == "radar.sigma_range_coef" else f"{value:g} m"


def _gap_rows(item: str, anchor: str, x: str, setting: str, imp: pd.DataFrame,
              trad: pd.DataFrame, xs: list[tuple[float, int]], at: str = ""
              ) -> list[dict[str, Any]]:
    """Claims on the gap improved - traditional along ``x``: narrowing (Fig. 3), always higher."""
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
    """"The gap narrows as separation grows": closest minus widest gap against the margin."""
    gap = {xv: imp[p].to_numpy() - trad[p].to_numpy() for xv, p in xs}
    claim = ESM_RADAR.result("gap narrows")
    v = narrows(gap, claim.margin, lambda value: _fmt_x(x, value))
    x0, x1 = xs[0][0], xs[-1][0]
    return headline_row(item, f"gap at {_fmt_x(x, x0)} minus gap at {_fmt_x(x, x1)}, same "
                        f"trials{where}", "improved", "gap narrows as separation grows",
                        v.estimate, v.low, v.high, "fraction difference", len(imp), v.word,
                        v.reason, f"{DOCS}#{anchor}", claim=claim.quantity, setting=at)


def _always_higher_row(item: str, anchor: str, x: str, where: str, n: int,
                       gaps: list[tuple[float, PairedBinary]], at: str = "") -> dict[str, Any]:
    """"Always higher" / "higher throughout": improved against traditional at every x;
    ``reproduced`` is the smallest gap."""
    v = higher_everywhere(gaps, lambda value: _fmt_x(x, value))
    xm, _ = min(gaps, key=lambda xg: xg[1].diff)
    separation = x == "target.separation"
    claim = ESM_RADAR.result("always higher" if separation else "higher throughout")
    return headline_row("Abstract" if separation else item,
                        f"smallest improved - traditional over the {len(gaps)} values, at "
                        f"{_fmt_x(x, xm)}{where}", "improved", claim.claim, v.estimate, v.low,
                        v.high, "fraction difference", n, v.word, v.reason, f"{DOCS}#{anchor}",
                        claim=claim.quantity, setting=at)


def _trend_rows(item: str, anchor: str, x: str, setting: str, rates: dict[str, pd.DataFrame],
                xs: list[tuple[float, int]], at: str = "") -> list[dict[str, Any]]:
    """"Both degrade": hardest-end rate minus easiest-end rate, paired, against the margin."""
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
    """Fig. 3 / Fig. 4 / abstract claims per such axis swept over 2+ values, both methods run."""
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
    """Paper 001's Table 3, Table 1 and (when separation or radar range error is swept) Fig. 3,
    Fig. 4 and abstract claims against this run, in :data:`HEADLINE_COLUMNS`."""
    rows = _table3_rows(run) + _ahp_rows() + _curve_rows(run)
    table = pd.DataFrame(rows, columns=list(HEADLINE_COLUMNS))
    return table.astype({"trials": "Int64"})


def value_words(key: str, value: Any) -> str:
    """A swept value in the experiment's declared words (``T1–T2 separation 200 m``)."""
    shown = render.quantity(EXPERIMENT, key)
    word = dict(shown.words).get(value)
    if word:
        return f"{shown.label} {word}" if word.startswith("'") else word
    return f"{shown.label} {shown.value(value)}"

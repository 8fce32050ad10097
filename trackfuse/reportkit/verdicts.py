"""How a reproduced number or a claim becomes a :class:`Verdict`: one set of rules for every
paper, ``docs/statistics.md``, "Verdicts against a paper"."""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from decimal import ROUND_HALF_UP, Decimal

import pandas as pd

from trackfuse.reported import Reported
from trackfuse.reportkit.numberformat import sig3
from trackfuse.stats import proportion_difference_interval, two_proportion_p

#: ``agrees``: the data are consistent with the paper's number (its sample and ours), or show
#: its claim (at least its declared margin in the interval, the effect's direction shown);
#: ``differs``: the paper's number lies outside what both samples allow, or the claim's
#: declared margin is excluded; ``inconclusive``: the run can neither show nor exclude the
#: claim (too few runs): absence of evidence is never ``differs``; ``not comparable``: the
#: run's config cannot answer it, or the paper gives no number.
VERDICTS = ("agrees", "differs", "inconclusive", "not comparable")
#: The verdicts by name: report modules use these, never the words, so a typo is an error.
AGREES, DIFFERS, INCONCLUSIVE, NOT_COMPARABLE = VERDICTS
#: Significance level of every two-sided test behind a verdict (95 % intervals).
ALPHA = 0.05


@dataclass(frozen=True)
class Verdict:
    """One verdict: ``word`` of :data:`VERDICTS`; ``estimate`` the number it reads with its
    95 % interval ``low``/``high`` (NaN for none); ``reason`` one line in plain words."""

    word: str
    estimate: float
    low: float
    high: float
    reason: str


def points(value: float) -> str:
    """A difference of two rates in signed percentage points, 3 significant figures (``+1.60``)."""
    return sig3(100 * value, signed=True) if math.isfinite(value) else "n/a"


def against_paper_sample(k: int, n: int, paper_k: int, paper_n: int) -> Verdict:
    """Our ``k`` of ``n`` against the paper's ``paper_k`` of ``paper_n`` (rule 1):
    Newcombe interval of ours - paper; "agrees" when it holds 0."""
    diff = k / n - paper_k / paper_n
    low, high = (float(v) for v in proportion_difference_interval(paper_k, paper_n, k, n))
    p = float(two_proportion_p(k, n, paper_k, paper_n))
    span = f"{points(diff)} points ({points(low)} to {points(high)}), p = {p:.2g}"
    paper = f"the paper's {paper_k} of {paper_n} ({sig3(100 * paper_k / paper_n)} %)"
    if low <= 0 <= high:
        return Verdict(AGREES, diff, low, high, f"consistent with {paper}: ours minus "
                       f"the paper's {span}")
    return Verdict(DIFFERS, diff, low, high, f"differs from {paper} by {span}")


def below_paper_bound(k: int, n: int, bound: float, paper_n: int) -> Verdict:
    """A claimed bound ("below ``bound`` in ``paper_n`` runs") against our ``k`` of ``n`` (rule 1):
    "differs" only when our rate lies above the largest count under the bound."""
    most = math.ceil(bound * paper_n) - 1
    diff = k / n - most / paper_n
    low, high = (float(v) for v in proportion_difference_interval(most, paper_n, k, n))
    span = f"{points(diff)} points ({points(low)} to {points(high)})"
    paper = f"the paper's at most {most} of {paper_n} runs ({sig3(100 * most / paper_n)} %)"
    if low > 0:
        return Verdict(DIFFERS, diff, low, high, f"above {paper} by {span}")
    return Verdict(AGREES, diff, low, high, f"consistent with {paper}: ours minus that {span}")


def at_least(estimate: float, low: float, high: float, margin: float, claim: str) -> Verdict:
    """A claim that a difference of two rates is at least ``margin`` (negative for a decline),
    judged by ``estimate`` and its 95 % interval (rule 2)."""
    sign = 1.0 if margin > 0 else -1.0
    near, far = sorted((sign * low, sign * high))
    shown = f"{points(estimate)} points ({points(low)} to {points(high)})"
    size = f"{100 * abs(margin):g} points"  # declared, exact: not an estimate
    if far < abs(margin):
        return Verdict(DIFFERS, estimate, low, high, f"{shown}: {claim} of {size} or more, "
                       "the smallest that counts, is excluded")
    if near > 0:
        return Verdict(AGREES, estimate, low, high, f"{shown}: {claim} shown")
    return Verdict(INCONCLUSIVE, estimate, low, high, f"{shown}: {claim} neither shown nor "
                   f"excluded ({size} or more counts)")


def within(estimate: float, low: float, high: float, margin: float, claim: str) -> Verdict:
    """A claim that a difference of two rates is at most ``margin`` (rule 2, other side)."""
    shown = f"{points(estimate)} points ({points(low)} to {points(high)})"
    if high <= margin:
        return Verdict(AGREES, estimate, low, high, f"{shown}: {claim}")
    if low > margin:
        return Verdict(DIFFERS, estimate, low, high, f"{shown}: not {claim}")
    return Verdict(INCONCLUSIVE, estimate, low, high,
                   f"{shown}: neither shown {claim} nor further off")


def exploration(pairs: int, found: str) -> str:
    """Words for a comparison found by searching ``pairs`` pairs (rule 3): never deciding."""
    return f"exploration only, not the verdict (searched {pairs} pairs): {found}"


def printed_decimals(printed: float) -> int:
    """Decimals of the shortest form of ``printed`` (0.053 -> 3, 5.2375 -> 4, 130 -> 0)."""
    text = repr(float(printed)).rstrip("0").rstrip(".")
    return len(text.split(".")[1]) if "." in text else 0


def as_printed_verdict(ours: float, printed: float) -> Verdict:
    """Our exact ``ours`` against the paper's ``printed`` (rule 4): rounded half up as printed."""
    decimals = printed_decimals(printed)
    step = Decimal(1).scaleb(-decimals)
    rounded = float(Decimal(repr(float(ours))).quantize(step, rounding=ROUND_HALF_UP))
    word = AGREES if math.isclose(rounded, printed, abs_tol=0.1 ** (decimals + 3)) else DIFFERS
    reason = (f"ours {ours:.6g} prints as {rounded:.{decimals}f} at the paper's "
              f"{decimals} decimals: " + ("the same" if word == AGREES else "not the same"))
    return Verdict(word, ours, math.nan, math.nan, reason)


def claim_verdict(shown: bool, opposite_shown: bool) -> str:
    """:data:`AGREES` when the data show a claim, :data:`DIFFERS` when they show its opposite,
    else :data:`INCONCLUSIVE`."""
    return AGREES if shown else DIFFERS if opposite_shown else INCONCLUSIVE


#: How several rows of the answering config combine into one verdict for an item that
#: claims something of each (every target count, say): the first of these present wins.
COMBINED = (DIFFERS, INCONCLUSIVE, AGREES, NOT_COMPARABLE)


def combined(words: Sequence[str]) -> str:
    """One verdict over several rows: ``differs`` if any is, else ``inconclusive``, else
    ``agrees``, else ``not comparable``."""
    return next((w for w in COMBINED if w in words), NOT_COMPARABLE)


def setting_text(values: Mapping[str, object]) -> str:
    """A row's setting as :func:`bottom_line` matches it: ``key=value; key=value``."""
    return "; ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in values.items())


def matches(setting: str, wanted: Mapping[str, object]) -> bool:
    """Whether a row's ``setting`` holds every ``key=value`` of ``wanted``."""
    parts = set(str(setting).split("; ")) if setting else set()
    return set(setting_text(dict(wanted)).split("; ")) <= parts if wanted else True


@dataclass(frozen=True)
class Line:
    """One paper item's bottom line: its ``verdict`` and ``reason`` from the ``answering`` headline
    rows, and the ``supporting`` rows of every other config or setting."""

    item: Reported
    verdict: str
    reason: str
    answering: pd.DataFrame
    supporting: pd.DataFrame


def _answers(item: Reported, rows: pd.DataFrame) -> pd.Series:
    """The ``rows`` that the item's declared :class:`~trackfuse.reported.Answer` names."""
    answer = item.answer
    assert answer is not None
    config = rows["config"].map(lambda c: answer.config in str(c).split(", "))
    def text(value: object) -> str:
        return "" if pd.isna(value) else str(value)

    named = (rows["algorithm"].map(text) == answer.algorithm if answer.algorithm else True)
    setting = rows["setting"].map(lambda s: matches(text(s), answer.setting))
    return config & named & setting


def bottom_line(results: Sequence[Reported], rows: pd.DataFrame,
                ran: Collection[str] | None = None) -> list[Line]:
    """One :class:`Line` per item of ``results`` that declares an answer (rule 5); "not comparable"
    when the answering config gave no row or did not run."""
    out = []
    for item in (r for r in results if r.answer is not None):
        about = rows[rows["claim"] == item.quantity] if len(rows) else rows
        answering = about[_answers(item, about)] if len(about) else about
        supporting = about.drop(index=answering.index)
        if answering.empty:
            config = item.answer.config
            why = (f"{config} was not run" if ran is not None and config not in ran
                   else f"{config} gave no row for it")
            out.append(Line(item, NOT_COMPARABLE, why, answering, supporting))
            continue
        word = combined(list(answering["verdict"]))
        first = answering[answering["verdict"] == word].iloc[0]
        reason = str(first["reason"])
        if len(answering) > 1:
            count = int((answering["verdict"] == word).sum())
            reason = f"{count} of {len(answering)} {word}; {first['quantity']}: {reason}"
        out.append(Line(item, word, reason, answering, supporting))
    return out

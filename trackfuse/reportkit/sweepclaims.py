"""Claims along a sweep judged on paired trials (shared random numbers across points): "higher
at every value" and "the gap narrows", each a
:class:`~trackfuse.reportkit.verdicts.Verdict` with a one-line reason."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from trackfuse.reportkit.verdicts import (
    AGREES,
    ALPHA,
    DIFFERS,
    Verdict,
    at_least,
    claim_verdict,
    exploration,
    points,
)
from trackfuse.stats import PairedBinary, holm_adjusted, paired_t_p, t_interval

Words = Callable[[float], str]


def higher_everywhere(gaps: Sequence[tuple[float, PairedBinary]], words: Words) -> Verdict:
    """``agrees`` when the paired interval of the gap is above 0 at every value, ``differs`` when
    the method is shown lower somewhere (exact McNemar, Holm); else ``inconclusive``. ``gaps``:
    ``(x, comparison)`` per value; the estimate is the smallest gap."""
    not_shown = [(xv, g) for xv, g in gaps if not g.low > 0]
    holm = holm_adjusted([g.p for _, g in gaps])
    lower = [xv for (xv, g), q in zip(gaps, holm, strict=True)
             if g.x_only > g.y_only and q < ALPHA]
    word = claim_verdict(not not_shown, bool(lower))
    listed = ", ".join(words(xv) + (" (the same outcome in every trial)"
                                    if g.x_only == g.y_only == 0 else f" ({points(g.diff)} "
                                    f"points, {points(g.low)} to {points(g.high)})")
                       for xv, g in not_shown)
    family = f"(exact McNemar, Holm over the {len(gaps)} values)"
    reason = ("paired interval above 0 at every value" if word == AGREES else
              f"shown lower at {', '.join(words(v) for v in lower)} {family}"
              if word == DIFFERS else f"not shown higher at {listed}; shown lower nowhere "
              + family)
    _, smallest = min(gaps, key=lambda xg: xg[1].diff)
    return Verdict(word, float(smallest.diff), float(smallest.low), float(smallest.high),
                   reason)


def _pair_tests(gap: Mapping[float, np.ndarray]) -> list[tuple[float, float, float, float,
                                                                float, float]]:
    """``(x_a, x_b, mean, low, high, p)``: gap at ``x_a`` minus at ``x_b``, each pair, paired t."""
    xs, tests = list(gap), []
    for i, xa in enumerate(xs):
        for xb in xs[i + 1:]:
            d = gap[xa] - gap[xb]
            d = d[np.isfinite(d)]
            mean, sd = float(d.mean()), float(d.std(ddof=1))
            lo, hi = t_interval(mean, sd, len(d))
            tests.append((xa, xb, mean, float(lo), float(hi),
                          float(paired_t_p(mean, sd, len(d)))))
    return tests


def narrows(gap: Mapping[float, np.ndarray], margin: float, words: Words) -> Verdict:
    """"The gap narrows from the first value to the last": first-value gap minus last-value gap
    (paired t) against ``margin``; ``gap`` maps x to per-trial gaps in sweep order. Other pairs
    found widening (paired t, Holm) are reported as exploration only."""
    tests = _pair_tests(gap)
    holm = holm_adjusted([t[-1] for t in tests])
    x0, x1 = next(iter(gap)), list(gap)[-1]
    _, _, d_end, lo_end, hi_end, _ = next(t for t in tests if t[:2] == (x0, x1))
    verdict = at_least(d_end, lo_end, hi_end, margin, "a narrowing")
    means = {xv: float(np.nanmean(g)) for xv, g in gap.items()}
    reason = (f"gap {points(means[x0])} points at {words(x0)}, {points(means[x1])} at "
              f"{words(x1)}, the comparison fixed in advance: {verdict.reason}")
    widening = sorted((q, i) for i, (t, q) in enumerate(zip(tests, holm, strict=True))
                      if t[2] < 0 and q < ALPHA and t[:2] != (x0, x1))
    if widening:
        q, i = widening[0]
        xa, xb = tests[i][:2]
        reason += "; " + exploration(len(tests), (
            f"the gap widens from {words(xa)} to {words(xb)}, Holm p = {q:.2g}"))
    return Verdict(verdict.word, d_end, lo_end, hi_end, reason)

"""The shared verdict rules (trackfuse.reportkit.verdicts), checked against an independent
computation of Newcombe's interval and against published worked examples."""

import math

import pandas as pd
import pytest

from trackfuse.reported import ESM_RADAR, Answer, Reported
from trackfuse.reportkit import verdicts as v

Z = 1.959963984540054  # the normal 97.5 % quantile


def _wilson_by_roots(k: int, n: int) -> tuple[float, float]:
    """Wilson's interval as the two roots in p of (k/n - p)^2 = z^2 p (1 - p) / n, solved as a
    quadratic (an independent route from the closed form in trackfuse.stats)."""
    a = 1 + Z * Z / n
    b = -(2 * k / n + Z * Z / n)
    c = (k / n) ** 2
    root = math.sqrt(max(b * b - 4 * a * c, 0.0))
    return (-b - root) / (2 * a), (-b + root) / (2 * a)


def _newcombe_by_hand(k1: int, n1: int, k2: int, n2: int) -> tuple[float, float]:
    """Newcombe's method 10 for k1/n1 - k2/n2 (Stat. Med. 17, 873-890, 1998, eq. for
    delta - sqrt((p1 - l1)^2 + (u2 - p2)^2), delta + sqrt((u1 - p1)^2 + (p2 - l2)^2))."""
    p1, p2 = k1 / n1, k2 / n2
    l1, u1 = _wilson_by_roots(k1, n1)
    l2, u2 = _wilson_by_roots(k2, n2)
    d = p1 - p2
    return d - math.hypot(p1 - l1, u2 - p2), d + math.hypot(u1 - p1, p2 - l2)


# Newcombe (1998), Table II, method 10: (k1, n1, k2, n2) -> interval for p1 - p2
PUBLISHED = [((56, 70, 48, 80), (0.0524, 0.3339)), ((9, 10, 3, 10), (0.1705, 0.8090)),
             ((5, 56, 0, 29), (-0.0381, 0.1926)), ((0, 10, 0, 20), (-0.1611, 0.2775)),
             ((10, 10, 0, 20), (0.6791, 1.0000))]


@pytest.mark.parametrize(("counts", "interval"), PUBLISHED)
def test_the_two_sample_verdict_uses_newcombes_published_interval(counts, interval):
    k1, n1, k2, n2 = counts
    verdict = v.against_paper_sample(k1, n1, k2, n2)
    assert (round(verdict.low, 4), round(verdict.high, 4)) == pytest.approx(interval, abs=1e-4)
    assert (verdict.low, verdict.high) == pytest.approx(_newcombe_by_hand(k1, n1, k2, n2),
                                                        abs=1e-12)
    assert verdict.word == ("agrees" if verdict.low <= 0 <= verdict.high else "differs")


@pytest.mark.parametrize("k", [0, 1, 137, 276, 300, 499, 500])
def test_the_interval_matches_the_independent_computation_at_the_papers_count(k):
    verdict = v.against_paper_sample(k, 500, 276, 500)
    assert (verdict.low, verdict.high) == pytest.approx(_newcombe_by_hand(k, 500, 276, 500),
                                                        abs=1e-12)


def test_the_verdict_against_the_papers_sample_does_not_flip_with_more_trials():
    """The traditional baseline: 0.540 at 500 trials and 0.5275 at 4,000 against the paper's
    276 of 500 (0.552). Our Wilson interval at 4,000 excludes 0.552, but the two samples
    differ by z ~ 1.0, p ~ 0.3: consistent at both sizes."""
    small = v.against_paper_sample(270, 500, 276, 500)
    large = v.against_paper_sample(2110, 4000, 276, 500)
    assert small.word == large.word == "agrees"
    assert large.reason.startswith("consistent with the paper's 276 of 500 (55.2 %)")
    assert "p = 0.3" in large.reason
    far = v.against_paper_sample(3000, 4000, 276, 500)
    assert far.word == "differs" and far.reason.startswith("differs from the paper's 276 of 500")
    assert far.low > 0


@pytest.mark.parametrize(("estimate", "low", "high", "word"), [
    (0.0, -0.019, 0.019, "differs"),     # a rise of at most 1.9 points excludes 2 points
    (0.06, 0.02, 0.10, "agrees"),        # shown, and 2 points or more within reach
    (0.01, 0.001, 0.019, "differs"),     # shown, but too small to count
    (0.04, -0.02, 0.10, "inconclusive"),
    (-0.3, -0.43, -0.16, "differs"),     # a fall
])
def test_a_shape_claim_is_judged_against_its_declared_margin(estimate, low, high, word):
    assert v.at_least(estimate, low, high, 0.02, "a rise").word == word
    # the mirror claim (a decline of at least 2 points) on the mirrored data
    assert v.at_least(-estimate, -high, -low, -0.02, "a decline").word == word


def test_within_a_margin():
    assert v.within(0.01, -0.01, 0.04, 0.05, "close").word == "agrees"
    assert v.within(0.08, 0.06, 0.10, 0.05, "close").word == "differs"
    assert v.within(0.05, 0.02, 0.08, 0.05, "close").word == "inconclusive"


def test_a_bound_from_the_papers_runs_is_the_largest_count_under_it():
    """Below 5 % in 50 runs: at most 2 of 50. 3 % of ours, at any number of runs, is
    consistent; 20 % of 50 is above it."""
    for n in (100, 10_000):
        assert v.below_paper_bound(3 * n // 100, n, 0.05, 50).word == "agrees"
    high = v.below_paper_bound(10, 50, 0.05, 50)
    assert high.word == "differs" and high.low > 0
    assert "at most 2 of 50 runs (4.00 %)" in high.reason


@pytest.mark.parametrize(("ours", "printed", "word"), [
    (0.059375, 0.059375, "agrees"), (0.0593690, 0.059375, "differs"),
    (5.237476, 5.2375, "agrees"), (0.2638, 0.26, "agrees"), (0.0636, 0.07, "differs"),
    (129.6, 130, "agrees"), (0.0525, 0.053, "agrees"),
])
def test_printed_values_are_compared_at_the_printed_digits(ours, printed, word):
    assert v.as_printed_verdict(ours, printed).word == word


def test_printed_decimals():
    assert [v.printed_decimals(x) for x in (0.053, 5.2375, 130, 0.74)] == [3, 4, 0, 2]


def _rows(*rows: tuple[str, str, str, str, str]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["config", "claim", "algorithm", "setting", "verdict"]
                        ).assign(quantity="q", reason="why")


def test_the_bottom_line_takes_the_declared_config_and_setting():
    item = ESM_RADAR.result("improved: correct rate")
    rows = _rows(("esm_radar_snake_cross", item.quantity, "improved",
                  "radar.factor_model=table", "differs"),
                 ("esm_radar_snake_cross", item.quantity, "improved",
                  "radar.factor_model=derived", "agrees"),
                 ("esm_radar_phase", item.quantity, "improved", "radar.factor_model=table",
                  "agrees"),
                 ("esm_radar_snake_cross", item.quantity, "traditional",
                  "radar.factor_model=table", "agrees"))
    (line,) = [x for x in v.bottom_line([item], rows)]
    assert line.verdict == "differs"
    assert list(line.answering.index) == [0] and list(line.supporting.index) == [1, 2, 3]


def test_the_bottom_line_of_a_claim_about_every_setting_combines_its_rows():
    item = Reported("Fig. 2", "high", None, "fraction", 50, "all high",
                    answer=Answer("cfg", "pga"))
    rows = _rows(("cfg", "high", "pga", "targets.n=5", "agrees"),
                 ("cfg", "high", "pga", "targets.n=7", "inconclusive"),
                 ("cfg", "high", "other", "targets.n=7", "differs"),
                 ("other_cfg, cfg", "high", "pga", "targets.n=10", "agrees"))
    (line,) = v.bottom_line([item], rows)
    assert line.verdict == "inconclusive" and len(line.answering) == 3
    assert line.reason.startswith("1 of 3 inconclusive")
    missing = v.bottom_line([Reported("Fig. 2", "high", None, "", None, "",
                                      answer=Answer("not_run"))], rows)[0]
    assert missing.verdict == "not comparable" and len(missing.supporting) == 4


def test_setting_text_round_trips_through_matches():
    text = v.setting_text({"radar.factor_model": "table", "target.separation": 200.0})
    assert text == "radar.factor_model=table; target.separation=200"
    assert v.matches(text, {"radar.factor_model": "table"})
    assert not v.matches(text, {"radar.factor_model": "derived"})
    assert v.matches("", {})

"""Interval estimates against independent references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from trackfuse.stats import (
    PairedBinary,
    _bootstrap_t,
    _resample_counts,
    binomial_above_p,
    bootstrap_t_mean_intervals,
    holm_adjusted,
    mcnemar_p,
    median_interval,
    nees_band,
    no_spread_p,
    paired_binary,
    paired_t_p,
    percentile_mean_intervals,
    proportion_difference_interval,
    rmse_intervals,
    t_interval,
    welch_interval,
    wilson_interval,
)


def test_wilson_matches_scipy_binomtest():
    for k, n in [(0, 10), (3, 10), (10, 10), (17, 50), (499, 500)]:
        ref = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        low, high = wilson_interval(k, n)
        assert np.isclose(low, ref.low, atol=1e-12) and np.isclose(high, ref.high, atol=1e-12)


def test_wilson_bounds_at_zero_and_all_successes_are_exact():
    low, high = wilson_interval(np.array([0, 500]), np.array([500, 500]))
    assert low[0] == 0.0 and high[1] == 1.0


def test_wilson_empty_is_nan_and_bounds_ordered():
    low, high = wilson_interval(np.array([0, 2]), np.array([0, 4]))
    assert np.isnan(low[0]) and np.isnan(high[0]) and 0 < low[1] < 0.5 < high[1] < 1


def test_t_interval_matches_scipy():
    x = np.random.default_rng(1).normal(size=12)
    low, high = t_interval(x.mean(), x.std(ddof=1), len(x))
    ref = stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    assert np.allclose([low, high], ref)


def test_nees_band_brackets_the_dimension_and_narrows():
    low, high = nees_band(3, 50)
    assert low < 3 < high
    alpha = 1 - 0.95
    # bit for bit what scipy.stats gives, without importing it
    assert (low, high) == tuple(stats.chi2.ppf([alpha / 2, 1 - alpha / 2], 150) / 50)
    assert nees_band(3, 500)[1] - nees_band(3, 500)[0] < high - low


def test_newcombe_independent_matches_the_published_example():
    # Newcombe (1998), Stat. Med. 17, 873-890: 56/70 - 48/80, method 10: 0.0524 to 0.3339
    low, high = proportion_difference_interval(48, 80, 56, 70)
    assert np.isclose(low, 0.0524, atol=5e-5) and np.isclose(high, 0.3339, atol=5e-5)


def test_newcombe_paired_covers_at_about_the_nominal_level():
    """Monte Carlo coverage of the paired interval for correlated 0/1 outcomes (n = 40)."""
    rng = np.random.default_rng(3)
    reps, n = 4000, 40
    for p_base, p_new in ((0.7, 0.7), (0.85, 0.7), (0.5, 0.6)):
        u = rng.random((reps, n))
        noise = rng.random((reps, n))
        base = (u < p_base).astype(float)
        new = np.where(noise < 0.7, u < p_new, rng.random((reps, n)) < p_new).astype(float)
        truth = p_new - p_base
        k1, k2, both = base.sum(1), new.sum(1), (base * new).sum(1)
        low, high = proportion_difference_interval(k1, n, k2, n, both)
        coverage = np.mean((low <= truth) & (truth <= high))
        assert 0.93 <= coverage <= 0.985, (p_base, p_new, coverage)


def test_newcombe_paired_without_discordant_pairs_contains_zero():
    low, high = proportion_difference_interval(30, 40, 30, 40, both=30)
    assert low < 0 < high


def test_welch_and_mcnemar_match_scipy():
    rng = np.random.default_rng(5)
    x, y = rng.normal(0, 1, 15), rng.normal(0.4, 2, 22)
    low, high, p = welch_interval(x.mean(), x.std(ddof=1), 15, y.mean(), y.std(ddof=1), 22)
    ref = stats.ttest_ind(y, x, equal_var=False)
    ci = ref.confidence_interval(0.95)
    assert np.isclose(p, ref.pvalue) and np.isclose(low, ci.low) and np.isclose(high, ci.high)
    assert np.isclose(mcnemar_p(2, 9), stats.binomtest(2, 11).pvalue)
    assert mcnemar_p(0, 0) == 1.0


@pytest.mark.parametrize("level", [0.9, 0.95, 0.99])
def test_quantiles_equal_scipy_stats_bit_for_bit(level):
    """The summary uses scipy.special's quantiles (fast to import); they must be the very
    numbers scipy.stats gives, or every summary.csv would change in its last digits."""
    n = np.arange(0, 3000, dtype=float)
    low, high = t_interval(np.zeros_like(n), np.ones_like(n), n, level)
    t = stats.t.ppf(0.5 + level / 2, np.maximum(n - 1, 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        np.testing.assert_array_equal(high, np.where(n >= 2, t / np.sqrt(n), np.nan))
    k = np.arange(0, 51)
    z = stats.norm.ppf(0.5 + level / 2)
    p = k / 50
    centre = (p + z**2 / 100) / (1 + z**2 / 50)
    half = z * np.sqrt(p * (1 - p) / 50 + z**2 / (4 * 50**2)) / (1 + z**2 / 50)
    low, high = wilson_interval(k, 50, level)
    np.testing.assert_array_equal(low[1:], np.clip(centre - half, 0, 1)[1:])
    np.testing.assert_array_equal(high[:-1], np.clip(centre + half, 0, 1)[:-1])


def test_p_values_are_nan_when_the_spread_is_undefined():
    """One value or an infinite one leaves the t tests nothing to go on: NaN, never 0."""
    assert np.isnan(paired_t_p(1.0, np.nan, 1))
    assert np.isnan(paired_t_p(np.inf, np.nan, 3))
    assert paired_t_p(0.5, 0.0, 4) == 0.0 and paired_t_p(0.0, 0.0, 4) == 1.0
    d = np.random.default_rng(2).normal(0.3, 1, 12)
    assert np.isclose(paired_t_p(d.mean(), d.std(ddof=1), 12), stats.ttest_1samp(d, 0).pvalue)
    assert np.isnan(welch_interval(1.0, 1.0, 3, np.inf, np.nan, 3)[2])
    assert welch_interval(1.0, 0.0, 3, 2.0, 0.0, 3)[2] == 0.0


def _percentile_rmse_intervals(squared: np.ndarray, resamples: int, seed: int) -> np.ndarray:
    """The percentile bootstrap that :func:`rmse_intervals` replaced, ``(R, n) -> (R, 2)``."""
    return np.sqrt(percentile_mean_intervals(squared, resamples, seed))


def test_rmse_interval_covers_95_percent_of_gaussian_errors_where_the_percentile_did_not():
    n, replications, resamples = 50, 1000, 1000
    errors = np.random.default_rng(1).normal(0.0, 1.0, (replications, n))  # true RMSE 1
    new = rmse_intervals(list(errors**2), resamples=resamples)
    old = _percentile_rmse_intervals(errors**2, resamples, seed=0)

    def coverage(iv):
        return np.mean((iv[:, 0] <= 1.0) & (iv[:, 1] >= 1.0))

    # Monte Carlo s.e. of a coverage near 0.95 over 1000 replications: 0.007
    assert 0.935 <= coverage(new) <= 0.975
    assert coverage(old) < 0.935  # measured 0.92: the old interval fails the same tolerance


def test_bootstrap_t_intervals_are_deterministic_and_independent_of_grouping():
    rng = np.random.default_rng(4)
    groups = [rng.exponential(size=n) for n in (5, 7, 5, 30)] + [np.array([1.0, np.inf, 2.0])]
    many = bootstrap_t_mean_intervals(groups)
    alone = np.vstack([bootstrap_t_mean_intervals([g]) for g in groups])
    np.testing.assert_array_equal(many, alone)
    np.testing.assert_array_equal(many, bootstrap_t_mean_intervals(groups))
    assert not np.array_equal(many[0], many[2])  # same size, different data
    assert (many[:, 0] < [g[np.isfinite(g)].mean() for g in groups]).all()
    assert (many[:, 1] > [g[np.isfinite(g)].mean() for g in groups]).all()


def test_bootstrap_t_interval_edge_cases():
    constant, single = np.full(6, 2.5), np.array([3.0])
    ci = bootstrap_t_mean_intervals([constant, single])
    np.testing.assert_array_equal(ci[0], [2.5, 2.5])
    assert np.isnan(ci[1]).all()
    # one run of 50 off zero: resamples without it have no spread, the mean is not bounded
    one = np.r_[np.zeros(49), 4.0]
    low, high = bootstrap_t_mean_intervals([one])[0]
    assert low < one.mean() and high == np.inf
    # equivariance: shifting and scaling the data shifts and scales the interval
    x = np.random.default_rng(2).gamma(2.0, size=40)
    np.testing.assert_allclose(bootstrap_t_mean_intervals([3 * x + 7])[0],
                               3 * bootstrap_t_mean_intervals([x])[0] + 7)
    # RMSE: square root of the mean-square interval, lower bound clipped at 0
    sq = np.random.default_rng(3).normal(0, 1, 8) ** 2
    mse = bootstrap_t_mean_intervals([sq])[0]
    np.testing.assert_allclose(rmse_intervals([sq])[0], np.sqrt(np.clip(mse, 0, None)))


def test_a_resample_of_one_repeated_value_has_an_infinite_t_not_a_huge_one():
    # 46 equal values: many resamples draw only them; rounding must not give them a spread
    x = np.array([[1.7] * 46 + [3.1, 0.2, 5.9, 2.2]])
    t = _bootstrap_t(x, _resample_counts(50, 4000, 0))
    assert (~np.isfinite(t)).sum() > 0
    assert np.abs(t[np.isfinite(t)]).max() < 100


def test_holm_adjusts_step_down_and_keeps_the_input_order():
    # sorted: 0.005 x 4 = 0.02, 0.01 x 3 = 0.03, 0.03 x 2 = 0.06, 0.04 x 1 -> max(0.06, 0.04)
    np.testing.assert_allclose(holm_adjusted([0.01, 0.04, 0.03, 0.005]),
                               [0.03, 0.06, 0.06, 0.02])
    np.testing.assert_allclose(holm_adjusted([0.5, 0.9]), [1.0, 1.0])  # capped at 1
    assert holm_adjusted([0.2]).tolist() == [0.2] and holm_adjusted([]).size == 0


def test_binomial_above_p_is_scipys_one_sided_binomial_test():
    for k, n, p0 in [(0, 50, 0.05), (3, 50, 0.05), (8, 50, 0.05), (50, 50, 0.05), (1, 1, 0.5),
                     (12, 200, 0.02)]:
        ref = stats.binomtest(k, n, p0, alternative="greater").pvalue
        assert binomial_above_p(k, n, p0) == pytest.approx(ref, rel=1e-12)
    assert binomial_above_p(0, 0, 0.05) == 1.0
    np.testing.assert_allclose(binomial_above_p([3, 8], [50, 50], 0.05),
                               [stats.binomtest(k, 50, 0.05, alternative="greater").pvalue
                                for k in (3, 8)], rtol=1e-12)


def test_mcnemar_p_is_the_exact_two_sided_binomial_test():
    for b, c in [(2, 9), (12, 1), (15, 3), (0, 7), (50, 50), (100, 120)]:
        assert mcnemar_p(b, c) == pytest.approx(stats.binomtest(b, b + c).pvalue, rel=1e-12)


def test_paired_binary_counts_like_a_loop_over_the_trials_both_have():
    """(trials, 3, 2) against (trials, 1, 2), NaN where a trial has no row: every field
    equals a count by hand, and the interval and p-value those of the counts."""
    rng = np.random.default_rng(11)
    x = np.where(rng.random((40, 3, 2)) < 0.1, np.nan, rng.random((40, 3, 2)) < 0.6)
    y = np.where(rng.random((40, 1, 2)) < 0.1, np.nan, rng.random((40, 1, 2)) < 0.4)
    x[:, 2, 1] = np.nan  # no trial at all
    c = paired_binary(x, y)
    assert all(getattr(c, f).shape == (3, 2) for f in PairedBinary.__dataclass_fields__)
    for i, j in np.ndindex(3, 2):
        pairs = [(a, b) for a, b in zip(x[:, i, j], y[:, 0, j], strict=True)
                 if not (np.isnan(a) or np.isnan(b))]
        n = len(pairs)
        k_x, k_y = sum(a for a, _ in pairs), sum(b for _, b in pairs)
        both = sum(a == b == 1 for a, b in pairs)
        x_only, y_only = sum(a > b for a, b in pairs), sum(a < b for a, b in pairs)
        got = (c.n, c.k_x, c.k_y, c.both, c.x_only, c.y_only)
        assert tuple(v[i, j] for v in got) == (n, k_x, k_y, both, x_only, y_only)
        assert c.p[i, j] == mcnemar_p(x_only, y_only)
        if n == 0:
            assert np.isnan([c.diff[i, j], c.low[i, j], c.high[i, j]]).all()
            assert c.p[i, j] == 1.0
            continue
        assert (c.rate_x[i, j], c.rate_y[i, j]) == (k_x / n, k_y / n)
        assert c.diff[i, j] == k_y / n - k_x / n
        low, high = proportion_difference_interval(k_x, n, k_y, n, both)
        assert (c.low[i, j], c.high[i, j]) == (low, high)
    assert (c.n[2, 1], c.p[2, 1]) == (0, 1.0)


def test_paired_binary_drops_a_trial_either_side_lacks_and_mirrors():
    x = np.array([1, 1, 0, np.nan, 1, 0])
    y = np.array([1, 0, 1, 1, np.nan, 1])
    c = paired_binary(x, y)
    assert (c.n, c.k_x, c.k_y, c.both, c.x_only, c.y_only) == (4, 2, 3, 1, 1, 2)
    assert c.diff == pytest.approx(0.25)
    back = paired_binary(y, x)
    assert (back.x_only, back.y_only, back.p) == (c.y_only, c.x_only, c.p)
    assert (back.low, back.high) == pytest.approx((-c.high, -c.low), abs=1e-15)


def test_paired_binary_from_counts_passes_the_level_on():
    c = PairedBinary.from_counts([50, 50], [30, 12], [38, 12], [27, 12], level=0.99)
    low, high = proportion_difference_interval([30, 12], 50, [38, 12], 50, [27, 12], 0.99)
    np.testing.assert_array_equal(c.low, low)
    np.testing.assert_array_equal(c.high, high)
    np.testing.assert_array_equal(c.p, mcnemar_p([3, 0], [11, 0]))


def test_median_interval_takes_order_statistics():
    """n = 50: the 18th and 33rd of the sorted values (coverage 0.967 >= 0.95); 6 values:
    min and max; 5 values: no 95 % interval of the median."""
    assert median_interval(np.arange(50.0, 0, -1)) == (25.5, 18.0, 33.0)
    assert median_interval([3.0, 1, 2, 6, 5, 4]) == (3.5, 1.0, 6.0)
    median, low, high = median_interval([1.0, 2, 3, 4, 5])
    assert median == 3.0 and np.isnan(low) and np.isnan(high)


def test_no_spread_p_is_the_exact_sign_and_permutation_p():
    """All n paired differences of one sign: the exact binomial test's p; two samples of one
    value each: twice the chance, 1 / C(n1 + n2, n1), of the observed, most extreme split."""
    from scipy.stats import binomtest
    for n in (1, 2, 6, 10):
        assert no_spread_p(n) == pytest.approx(binomtest(n, n, 0.5).pvalue)
    assert no_spread_p(2, 2) == pytest.approx(1 / 3) and no_spread_p(5, 5) == 2 / 252
    assert no_spread_p(1, 1) == 1.0

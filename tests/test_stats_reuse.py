"""The report's tables reuse bootstrap draws and take their p-values from scipy.special
(scipy.stats' own functions) without importing scipy.stats: the same numbers, less work."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from scipy import stats as scipy_stats

from trackfuse import stats


def test_resample_counts_are_drawn_once_and_read_only():
    first = stats._resample_counts(37, 500, 11)
    assert stats._resample_counts(37, 500, 11) is first
    assert not first.flags.writeable
    assert first.shape == (500, 37) and (first.sum(axis=1) == 37).all()
    again = stats.bootstrap_t_mean_intervals([np.arange(37.0) ** 1.5], resamples=500, seed=11)
    stats._kept_resample_counts.cache_clear()
    fresh = stats.bootstrap_t_mean_intervals([np.arange(37.0) ** 1.5], resamples=500, seed=11)
    np.testing.assert_array_equal(again, fresh)


def test_large_resample_counts_are_not_kept(monkeypatch):
    monkeypatch.setattr(stats, "KEPT_COUNTS", 500 * 36)
    large = stats._resample_counts(37, 500, 11)
    assert stats._resample_counts(37, 500, 11) is not large
    np.testing.assert_array_equal(stats._resample_counts(37, 500, 11), large)


def test_p_values_equal_scipy_stats_bit_for_bit():
    rng = np.random.default_rng(3)
    n1, n2 = rng.integers(0, 60, 400).astype(float), rng.integers(0, 60, 400).astype(float)
    k1, k2 = np.floor(rng.random(400) * (n1 + 1)), np.floor(rng.random(400) * (n2 + 1))
    a, b, c, d, n = k1, n1 - k1, k2, n2 - k2, n1 + n2
    with np.errstate(invalid="ignore", divide="ignore"):
        chi2 = (a * d - b * c) ** 2 * (n - 1) / (n1 * n2 * (a + c) * (b + d))
    expected = np.where(np.isfinite(chi2), scipy_stats.chi2.sf(chi2, 1), 1.0)
    np.testing.assert_array_equal(stats.two_proportion_p(k1, n1, k2, n2), expected)

    diff = np.r_[rng.normal(size=300), 0.0, 1.0, -2.0, np.nan]
    sd = np.r_[rng.random(300) * 2, 0.0, 0.0, 1.0, 1.0]
    count = np.r_[rng.integers(1, 80, 300), 5, 5, 1, 7].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        se = sd / np.sqrt(count)
        old = stats._p_value(2 * scipy_stats.t.sf(np.abs(diff / se), count - 1), se, diff)
    np.testing.assert_array_equal(stats.paired_t_p(diff, sd, count), old)


def test_tables_p_values_do_not_import_scipy_stats():
    code = ("import sys; from trackfuse.stats import two_proportion_p, paired_t_p; "
            "two_proportion_p(3, 10, 5, 10); paired_t_p(0.5, 1.0, 10); "
            "sys.exit('scipy.stats' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0

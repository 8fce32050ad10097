"""Interval estimates against independent references."""

from __future__ import annotations

import numpy as np
from scipy import stats

from trackfuse.stats import nees_band, t_interval, wilson_interval


def test_wilson_matches_scipy_binomtest():
    for k, n in [(0, 10), (3, 10), (10, 10), (17, 50), (499, 500)]:
        ref = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        low, high = wilson_interval(k, n)
        assert np.isclose(low, ref.low, atol=1e-12) and np.isclose(high, ref.high, atol=1e-12)


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
    assert np.isclose(low, stats.chi2.ppf(0.025, 150) / 50)
    assert nees_band(3, 500)[1] - nees_band(3, 500)[0] < high - low

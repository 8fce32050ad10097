"""Interval estimates used by summaries and figures.

* Proportions: Wilson score interval (Wilson 1927; Agresti & Coull 1998).
* Means: Student-t interval on the sample mean.
* NEES: two-sided chi-square band for the average NEES over ``n_runs`` runs of an
  ``dim``-dimensional state (Bar-Shalom, Li & Kirubarajan 2001, sec. 5.4).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

Z95 = float(stats.norm.ppf(0.975))


def wilson_interval(successes, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval for a binomial proportion.

    ``successes`` and ``n`` broadcast; returns ``(low, high)`` arrays in [0, 1]. Where
    ``n == 0`` both bounds are NaN.
    """
    k = np.asarray(successes, dtype=float)
    n = np.asarray(n, dtype=float)
    z = float(stats.norm.ppf(0.5 + level / 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        denom = 1 + z**2 / n
        centre = (p + z**2 / (2 * n)) / denom
        half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    low = np.where(n > 0, np.clip(centre - half, 0.0, 1.0), np.nan)
    high = np.where(n > 0, np.clip(centre + half, 0.0, 1.0), np.nan)
    return low, high


def t_interval(mean, std, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Student-t interval ``mean +- t_{n-1} std / sqrt(n)``; NaN where ``n < 2``."""
    mean = np.asarray(mean, dtype=float)
    std = np.asarray(std, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = stats.t.ppf(0.5 + level / 2, np.maximum(n - 1, 1))
        half = np.where(n >= 2, t * std / np.sqrt(n), np.nan)
    return mean - half, mean + half


def nees_band(dim: int, n_runs: int, level: float = 0.95) -> tuple[float, float]:
    """Band for the average NEES of ``n_runs`` independent runs of a ``dim``-state filter.

    ``n_runs * ANEES ~ chi2(n_runs * dim)`` for a consistent filter, so the band is
    ``chi2.ppf([a/2, 1-a/2], n_runs*dim) / n_runs``.
    """
    dof = dim * n_runs
    alpha = 1 - level
    low, high = stats.chi2.ppf([alpha / 2, 1 - alpha / 2], dof) / n_runs
    return float(low), float(high)

"""Interval estimates and tests for summaries, figures and ``compare``; which serves where and
its coverage: ``docs/statistics.md``. scipy is imported on first use. Array arguments
broadcast to one shape ``S``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from trackfuse.chi2 import chi2_quantile


def wilson_interval(successes: ArrayLike, n: ArrayLike,
                    level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval ``(low, high)`` of ``successes / n``; NaN where ``n == 0``."""
    from scipy.special import ndtri  # on first use: see the module docstring

    k = np.asarray(successes, dtype=float)
    n = np.asarray(n, dtype=float)
    z = float(ndtri(0.5 + level / 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        denom = 1 + z**2 / n
        centre = (p + z**2 / (2 * n)) / denom
        half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    # the bounds at k = 0 and k = n are exactly 0 and 1; round off floating-point residue
    low = np.where(n > 0, np.where(k == 0, 0.0, np.clip(centre - half, 0.0, 1.0)), np.nan)
    high = np.where(n > 0, np.where(k == n, 1.0, np.clip(centre + half, 0.0, 1.0)), np.nan)
    return low, high


def t_interval(mean: ArrayLike, std: ArrayLike, n: ArrayLike,
               level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Student-t interval ``mean +- t_{n-1} std / sqrt(n)``; NaN where ``n < 2``."""
    from scipy.special import stdtrit  # on first use: see the module docstring

    mean = np.asarray(mean, dtype=float)
    std = np.asarray(std, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = stdtrit(np.maximum(n - 1, 1), 0.5 + level / 2)
        half = np.where(n >= 2, t * std / np.sqrt(n), np.nan)
    return mean - half, mean + half


def nees_band(dim: int, n_runs: int, level: float = 0.95) -> tuple[float, float]:
    """Band of the average NEES of ``n_runs`` runs of a ``dim``-state filter:
    ``n_runs * ANEES ~ chi2(n_runs * dim)`` when consistent."""
    dof = dim * n_runs
    alpha = 1 - level
    return chi2_quantile(alpha / 2, dof) / n_runs, chi2_quantile(1 - alpha / 2, dof) / n_runs



def welch_interval(m1: ArrayLike, s1: ArrayLike, n1: ArrayLike, m2: ArrayLike,
                   s2: ArrayLike, n2: ArrayLike,
                   level: float = 0.95) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Welch interval of ``m2 - m1`` and its two-sided p, ``(low, high, p_value)``; NaN where a
    sample has fewer than two values."""
    from scipy import stats  # on first use: see the module docstring

    m1, s1, n1, m2, s2, n2 = (np.asarray(v, dtype=float) for v in (m1, s1, n1, m2, s2, n2))
    with np.errstate(invalid="ignore", divide="ignore"):
        v1, v2 = s1**2 / n1, s2**2 / n2
        se = np.sqrt(v1 + v2)
        dof = (v1 + v2) ** 2 / (v1**2 / (n1 - 1) + v2**2 / (n2 - 1))
        dof = np.where(se > 0, dof, np.inf)
        half = stats.t.ppf(0.5 + level / 2, dof) * se
        t = (m2 - m1) / se
        p = _p_value(2 * stats.t.sf(np.abs(t), dof), se, m2 - m1)
    ok = (n1 >= 2) & (n2 >= 2)
    diff = m2 - m1
    nan = np.full(np.broadcast(diff, ok).shape, np.nan)
    return (np.where(ok, diff - half, nan), np.where(ok, diff + half, nan),
            np.where(ok, p, nan))


def _p_value(p_test: ArrayLike, se: ArrayLike, diff: ArrayLike) -> np.ndarray:
    """``p_test`` where ``se > 0``; at ``se == 0`` 1 if ``diff == 0`` else 0; NaN if ``se`` NaN."""
    se, diff = np.asarray(se, dtype=float), np.asarray(diff, dtype=float)
    return np.where(se > 0, p_test, np.where(se == 0, np.where(diff == 0, 1.0, 0.0), np.nan))


def no_spread_p(n1: ArrayLike, n2: ArrayLike | None = None) -> np.ndarray:
    """Exact two-sided p of a difference with no spread (where a t test reads 0): sign test
    ``2 * 0.5**n1`` if paired, else ``2 / C(n1 + n2, n1)``; at most 1."""
    from scipy.special import comb  # on first use: see the module docstring

    n1 = np.asarray(n1, dtype=float)
    arrangements = 2.0**n1 if n2 is None else comb(n1 + np.asarray(n2, dtype=float), n1)
    return np.minimum(1.0, 2.0 / arrangements)


def paired_t_p(diff: ArrayLike, sd: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Two-sided paired t p-value from the mean, sd and count of the differences."""
    from scipy.special import stdtr  # scipy.stats.t.sf's own function, without its import

    diff, sd, n = (np.asarray(v, dtype=float) for v in (diff, sd, n))
    with np.errstate(invalid="ignore", divide="ignore"):
        se = sd / np.sqrt(n)
        p = 2 * stdtr(n - 1, -np.abs(diff / se))
    return _p_value(p, se, diff)


def proportion_difference_interval(k1: ArrayLike, n1: ArrayLike, k2: ArrayLike,
                                   n2: ArrayLike, both: ArrayLike | None = None,
                                   level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Newcombe's hybrid score interval of ``k2/n2 - k1/n1`` (Newcombe 1998,
    Stat. Med. 17, 873-890, method 10; paired, 2635-2650, when ``both`` counts trials 1 in
    both); NaN if a sample is empty."""
    k1, n1, k2, n2 = (np.asarray(v, dtype=float) for v in (k1, n1, k2, n2))
    with np.errstate(invalid="ignore", divide="ignore"):
        p1, p2 = k1 / n1, k2 / n2
    l1, u1 = wilson_interval(k1, n1, level)
    l2, u2 = wilson_interval(k2, n2, level)
    phi = 0.0 if both is None else _paired_phi(np.asarray(both, dtype=float), k1, k2, n1)
    delta = p2 - p1
    low = delta - np.sqrt(np.maximum((p2 - l2) ** 2 - 2 * phi * (p2 - l2) * (u1 - p1)
                                     + (u1 - p1) ** 2, 0.0))
    high = delta + np.sqrt(np.maximum((u2 - p2) ** 2 - 2 * phi * (u2 - p2) * (p1 - l1)
                                      + (p1 - l1) ** 2, 0.0))
    return np.clip(low, -1.0, 1.0), np.clip(high, -1.0, 1.0)


def _paired_phi(a: np.ndarray, k1: np.ndarray, k2: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Newcombe's continuity-corrected phi of the paired 2x2 table."""
    b, c = k1 - a, k2 - a
    d = n - a - b - c
    num = a * d - b * c
    num = np.where(num > 0, np.maximum(num - n / 2, 0.0), num)
    with np.errstate(invalid="ignore", divide="ignore"):
        denom = np.sqrt((a + b) * (c + d) * (a + c) * (b + d))
        return np.where(denom > 0, num / denom, 0.0)


def holm_adjusted(p_values: ArrayLike) -> np.ndarray:
    """Holm's step-down adjusted p-values (m,) in input order
    (Holm 1979, Scand. J. Stat. 6, 65-70)."""
    p = np.asarray(p_values, dtype=float)
    order = np.argsort(p, kind="stable")
    m = len(p)
    stepped = np.maximum.accumulate(np.minimum(1.0, (m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = stepped
    return out


def mcnemar_p(b: ArrayLike, c: ArrayLike) -> np.ndarray:
    """Exact two-sided McNemar p from discordant counts ``b``, ``c``; 1 when ``b + c = 0``."""
    from scipy.special import bdtr  # on first use: see the module docstring

    b, c = np.asarray(b, dtype=float), np.asarray(c, dtype=float)
    with np.errstate(invalid="ignore"):
        p = 2 * bdtr(np.minimum(b, c), (b + c).astype(np.int64), 0.5)
    return np.where(b + c > 0, np.minimum(p, 1.0), 1.0)


def median_interval(values: ArrayLike, level: float = 0.95) -> tuple[float, float, float]:
    """``(median, low, high)`` with ``[x_(j), x_(n+1-j)]``, ``j`` the largest with
    ``1 - 2 P(B < j) >= level``, ``B ~ Binomial(n, 1/2)``; NaN bounds when ``n`` is too small."""
    from scipy.special import bdtr  # on first use: see the module docstring

    x = np.sort(np.asarray(values, dtype=float))
    n, tail = len(x), (1 - level) / 2
    # j = how many k in 0..n-1 have P(B <= k) <= tail (the CDF rises, so they come first)
    j = int(np.sum(bdtr(np.arange(n), n, 0.5) <= tail))
    if j < 1:
        return float(np.median(x)), np.nan, np.nan
    return float(np.median(x)), float(x[j - 1]), float(x[n - j])


@dataclass(frozen=True)
class PairedBinary:
    """Two 0/1 outcomes of the same trials, fields of shape ``S``: counts, rates,
    ``diff = rate_y - rate_x`` with Newcombe's paired ``(low, high)`` and exact McNemar ``p``."""

    n: np.ndarray
    k_x: np.ndarray
    k_y: np.ndarray
    both: np.ndarray
    x_only: np.ndarray
    y_only: np.ndarray
    rate_x: np.ndarray
    rate_y: np.ndarray
    diff: np.ndarray
    low: np.ndarray
    high: np.ndarray
    p: np.ndarray

    @classmethod
    def from_counts(cls, n: ArrayLike, k_x: ArrayLike, k_y: ArrayLike, both: ArrayLike,
                    level: float = 0.95) -> PairedBinary:
        """From counts; rates and ``diff`` NaN and ``p`` 1 where ``n`` is 0."""
        n, k_x, k_y, both = (np.asarray(v, dtype=float) for v in (n, k_x, k_y, both))
        x_only, y_only = k_x - both, k_y - both
        with np.errstate(invalid="ignore", divide="ignore"):
            rate_x, rate_y = k_x / n, k_y / n
        low, high = proportion_difference_interval(k_x, n, k_y, n, both, level)
        return cls(n, k_x, k_y, both, x_only, y_only, rate_x, rate_y, rate_y - rate_x, low,
                   high, mcnemar_p(x_only, y_only))


def paired_binary(x: ArrayLike, y: ArrayLike, level: float = 0.95) -> PairedBinary:
    """:class:`PairedBinary` of ``y`` against ``x``, 0/1 arrays (trials, *S), NaN = no row; each
    comparison counts only trials where both have a row."""
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    ok = ~(np.isnan(x) | np.isnan(y))
    x, y = np.where(ok, x, 0.0), np.where(ok, y, 0.0)
    return PairedBinary.from_counts(ok.sum(axis=0), x.sum(axis=0), y.sum(axis=0),
                                    (x * y).sum(axis=0), level)


def binomial_above_p(k: ArrayLike, n: ArrayLike, p0: ArrayLike) -> np.ndarray:
    """One-sided exact p ``P(X >= k)``, ``X ~ Binomial(n, p0)``; 1 when ``k = 0`` or ``n = 0``."""
    from scipy.special import bdtrc  # on first use: see the module docstring

    k, n = np.asarray(k, dtype=float), np.asarray(n, dtype=float)
    with np.errstate(invalid="ignore"):
        p = bdtrc(np.maximum(k - 1, 0), n.astype(np.int64), p0)
    return np.where((k > 0) & (n > 0), p, 1.0)


def two_proportion_p(k1: ArrayLike, n1: ArrayLike, k2: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Two-sided p of the 'N-1' chi-square test of equal proportions (Campbell 2007)."""
    from scipy.special import chdtrc  # scipy.stats.chi2.sf's own function, without its import

    k1, n1, k2, n2 = (np.asarray(v, dtype=float) for v in (k1, n1, k2, n2))
    a, b, c, d = k1, n1 - k1, k2, n2 - k2
    n = n1 + n2
    with np.errstate(invalid="ignore", divide="ignore"):
        chi2 = (a * d - b * c) ** 2 * (n - 1) / (n1 * n2 * (a + c) * (b + d))
    return np.where(np.isfinite(chi2), chdtrc(1, chi2), 1.0)


def bootstrap_t_mean_intervals(groups: Sequence[ArrayLike], level: float = 0.95,
                               resamples: int = 2000, seed: int = 0) -> np.ndarray:
    """Expanded bootstrap-t interval (len(groups), 2) of each group's mean
    (``docs/statistics.md``); non-finite values dropped, equal-size groups share one draw
    from ``seed``; NaN below 2 values."""
    from scipy.special import ndtr, stdtrit  # on first use: see the module docstring

    clean = [np.asarray(g, dtype=float)[np.isfinite(np.asarray(g, dtype=float))]
             for g in groups]
    out = np.full((len(clean), 2), np.nan)
    for n in sorted({len(c) for c in clean if len(c) >= 2}):
        which = [i for i, c in enumerate(clean) if len(c) == n]
        x = np.stack([clean[i] for i in which])
        alpha = float(ndtr(np.sqrt(n / (n - 1)) * stdtrit(n - 1, (1 - level) / 2)))
        t = _bootstrap_t(x, _resample_counts(n, resamples, seed))
        q_lo = np.quantile(t, alpha, axis=1, method="lower")
        q_hi = np.quantile(t, 1 - alpha, axis=1, method="higher")
        mean, se = x.mean(axis=1), x.std(axis=1, ddof=1) / np.sqrt(n)
        with np.errstate(invalid="ignore"):
            low, high = mean - q_hi * se, mean - q_lo * se
        flat = se == 0
        out[which] = np.column_stack([np.where(flat, mean, low), np.where(flat, mean, high)])
    return out


def percentile_mean_intervals(samples: np.ndarray, resamples: int = 2000,
                              seed: int = 0) -> np.ndarray:
    """95 % percentile-bootstrap interval (R, 2) of each row's mean of ``samples`` (R, n), the
    baseline of ``examples/interval_coverage.py``."""
    n = samples.shape[1]
    means = samples @ _resample_counts(n, resamples, seed).T / n  # (R, resamples)
    return np.quantile(means, [0.025, 0.975], axis=1).T


#: Largest table of resample counts kept for reuse (entries: 16 MB of int64; at most
#: four kept), so a large group's bootstrap does not hold gigabytes after it is done.
KEPT_COUNTS = 2_000_000


def _resample_counts(n: int, resamples: int, seed: int) -> np.ndarray:
    """(resamples, n) counts of each value in each resample with replacement, read-only;
    kept for the next group of ``n`` values when small enough (a report's tables draw the
    same few hundred times)."""
    if n * resamples <= KEPT_COUNTS:
        return _kept_resample_counts(n, resamples, seed)
    return _draw_resample_counts(n, resamples, seed)


@lru_cache(maxsize=4)
def _kept_resample_counts(n: int, resamples: int, seed: int) -> np.ndarray:
    return _draw_resample_counts(n, resamples, seed)


def _draw_resample_counts(n: int, resamples: int, seed: int) -> np.ndarray:
    idx = np.random.default_rng(seed).integers(0, n, (resamples, n))
    counts = np.bincount((np.arange(resamples)[:, None] * n + idx).ravel(),
                         minlength=resamples * n).reshape(resamples, n)
    counts.flags.writeable = False
    return counts


def _bootstrap_t(x: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``(mean* - mean) / (s* / sqrt(n))`` (groups, resamples) of ``x`` (groups, n); ``+-inf``
    (0 at the mean) without spread."""
    n = x.shape[1]
    centred = x - x.mean(axis=1, keepdims=True)  # smaller cancellation than raw values
    scale = np.abs(centred).max(axis=1, keepdims=True)
    mean = centred @ counts.T / n
    var = np.maximum(centred**2 @ counts.T / n - mean**2, 0.0) * n / (n - 1)
    # E[c^2] - mean^2 of a resample of one repeated value leaves rounding residue of about
    # 1e-16 scale^2, not 0: a variance below (1e-6 scale)^2 counts as no spread
    tiny = 1e-6 * scale
    with np.errstate(divide="ignore", invalid="ignore"):
        t = mean / np.sqrt(var / n)
    degenerate = np.where(mean > tiny, np.inf, np.where(mean < -tiny, -np.inf, 0.0))
    return np.where(var > tiny**2, t, degenerate)


def rmse_intervals(squared_errors: Sequence[ArrayLike], level: float = 0.95,
                   resamples: int = 2000, seed: int = 0) -> np.ndarray:
    """Interval (len, 2) of ``sqrt(mean(e^2))`` from squared errors: the bootstrap-t interval of
    the mean square, clipped at 0, square-rooted."""
    mse = bootstrap_t_mean_intervals(squared_errors, level, resamples, seed)
    return np.sqrt(np.clip(mse, 0.0, None))

"""Aligning radar samples to ESM sample times (paper 001 eq. 1-2, corrected; W001-7).

With ``t1 <= t_g < t2`` the neighbouring radar times and ``a = (t_g - t1) / (t2 - t1)``:
``y(t_g) = y(t1) + a (y(t2) - y(t1))`` (eq. 1) and, for independent errors of variance
``sigma^2``, ``var y(t_g) = sigma^2 ((1 - a)^2 + a^2)`` (eq. 2 corrected). Without alignment
the latest radar sample is used (``a = 0``), the same for synchronous sensors. See
``docs/papers/esm_radar.md``, "Time alignment".
"""

from __future__ import annotations

import numpy as np

from trackfuse.tracking.models import wrap


def bracket(t: np.ndarray, period: float, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Index of the radar sample at or before each time, and the interpolation fraction.

    Parameters: ``t`` (K,) query times (s), >= 0. ``period`` radar sampling period ``T_R`` (s).
    ``n_samples`` number of radar samples M (times ``0 .. (M-1) T_R``); needs ``t < (M - 1) T_R`` so
    that ``m1 + 1`` exists.
    Returns ``m1`` (K,) int, ``a`` (K,) fraction in [0, 1)."""
    pos = np.asarray(t, dtype=float) / period
    m1 = np.floor(pos + 1e-9).astype(int)
    if np.any(m1 < 0) or np.any(m1 + 1 >= n_samples):
        raise ValueError("query times outside the radar sample span")
    return m1, np.clip(pos - m1, 0.0, 1.0)


def interpolate(y: np.ndarray, m1: np.ndarray, a: np.ndarray, angular: bool = False,
                axis: int = 0) -> np.ndarray:
    """Linear interpolation ``y(m1) + a (y(m1 + 1) - y(m1))`` along ``axis`` (eq. 1).

    Parameters: ``y`` array with the radar-sample axis at ``axis`` (length M). ``m1`` (K,) left
    indices; ``a`` (K,) fractions. ``angular`` interpolate the wrapped difference (for angles in
    rad). ``axis`` sample axis of ``y``.
    Returns array like ``y`` with that axis of length K."""
    y1 = np.take(y, m1, axis=axis)
    step = np.take(y, m1 + 1, axis=axis) - y1
    if angular:
        step = wrap(step)
    shape = [1] * y.ndim
    shape[axis] = -1
    out = y1 + np.reshape(a, shape) * step
    return wrap(out) if angular else out


def interpolate_covariance(P: np.ndarray, m1: np.ndarray, a: np.ndarray,
                           axis: int = 0) -> np.ndarray:
    """Covariance of the interpolant of independent samples (eq. 2, corrected):
    ``(1 - a)^2 P(m1) + a^2 P(m1 + 1)``, i.e. ``sigma^2 ((1 - a)^2 + a^2)`` for equal
    variances.

    Parameters: ``P`` covariances with the radar-sample axis at ``axis`` (length M), any trailing
    shape. ``m1`` (K,) left indices; ``a`` (K,) fractions (:func:`bracket`). ``axis`` sample axis of
    ``P``.
    Returns array like ``P`` with that axis of length K."""
    m1 = np.asarray(m1)
    shape = [1] * np.ndim(P)
    shape[axis] = -1
    a = np.reshape(a, shape)
    return (1 - a) ** 2 * np.take(P, m1, axis=axis) + a**2 * np.take(P, m1 + 1, axis=axis)

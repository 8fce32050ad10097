"""Aligning radar samples to ESM sample times (paper 001 eq. 1-2, corrected; W001-7).

Linear interpolation with variance ``sigma^2 ((1 - a)^2 + a^2)``; without alignment the
latest radar sample is used. See ``docs/papers/esm_radar.md``, "Time alignment"."""

from __future__ import annotations

import numpy as np

from trackfuse.tracking.models import wrap


def bracket(t: np.ndarray, period: float, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Left radar index ``m1`` (K,) and fraction ``a`` (K,) in [0, 1) for times ``t`` (K,) in s.

    Radar samples are at ``0 .. (M-1) T_R``; raises ValueError unless ``0 <= t < (M - 1) T_R``."""
    pos = np.asarray(t, dtype=float) / period
    m1 = np.floor(pos + 1e-9).astype(int)
    if np.any(m1 < 0) or np.any(m1 + 1 >= n_samples):
        raise ValueError("query times outside the radar sample span")
    return m1, np.clip(pos - m1, 0.0, 1.0)


def interpolate(y: np.ndarray, m1: np.ndarray, a: np.ndarray, angular: bool = False,
                axis: int = 0) -> np.ndarray:
    """``y(m1) + a (y(m1 + 1) - y(m1))`` along ``axis`` (eq. 1); that axis becomes length K.

    ``angular`` interpolates the wrapped difference (rad)."""
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
    """``(1 - a)^2 P(m1) + a^2 P(m1 + 1)`` along ``axis`` (eq. 2, corrected)."""
    m1 = np.asarray(m1)
    shape = [1] * np.ndim(P)
    shape[axis] = -1
    a = np.reshape(a, shape)
    return (1 - a) ** 2 * np.take(P, m1, axis=axis) + a**2 * np.take(P, m1 + 1, axis=axis)

"""Emitter range from one bearing and one time difference of arrival (TDOA + DF).

With bearing ``theta`` (rad) at A1, baseline ``b = A2 - A1`` (m), range difference
``dr = c dt`` (m) and ``u = [cos theta, sin theta]'``: ``r = (|b|^2 - dr^2) / (2 (u'b - dr))``.
Equations and validity: ``docs/papers/esm_radar.md``, "TDOA-DF range".

Reference: Torrieri D., IEEE Trans. AES 20(2), 1984, 183-198."""

from __future__ import annotations

import numpy as np

C = 299_792_458.0  # speed of light, m/s


def tdoa_df_range(theta: np.ndarray, dr: np.ndarray, b: np.ndarray,
                  min_denominator: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Range from A1 (m), NaN where ``|2 (u'b - dr)| < min_denominator`` (m) or ``r <= 0``.

    ``theta`` (...,) rad, ``dr`` (...,) ``|p - A1| - |p - A2|`` m, ``b`` (2,) m. Returns
    ``r`` (...,) and ``valid`` (...,) bool."""
    theta = np.asarray(theta, dtype=float)
    dr = np.asarray(dr, dtype=float)
    D = 2.0 * (np.cos(theta) * b[0] + np.sin(theta) * b[1] - dr)
    num = b[0] ** 2 + b[1] ** 2 - dr**2
    ok = np.abs(D) >= min_denominator
    r = np.divide(num, D, out=np.full(np.broadcast(num, D).shape, np.nan), where=ok)
    valid = ok & (r > 0)
    return np.where(valid, r, np.nan), valid


def tdoa_df_jacobian(theta: np.ndarray, dr: np.ndarray,
                     b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``dr/dtheta`` (m/rad) and ``dr/d(dr)`` (m/m), each (...,); NaN where ``r <= 0``."""
    r, _ = tdoa_df_range(theta, dr, b, min_denominator=0.0)
    D = 2.0 * (np.cos(theta) * b[0] + np.sin(theta) * b[1] - dr)
    ub_perp = -np.sin(theta) * b[0] + np.cos(theta) * b[1]
    return -2.0 * r * ub_perp / D, 2.0 * (r - dr) / D


def tdoa_df_range_sigma(theta: np.ndarray, dr: np.ndarray, b: np.ndarray, sigma_theta: float,
                        sigma_dr: float) -> np.ndarray:
    """First-order range sd (...,) m from ``sigma_theta`` (rad) and ``sigma_dr = c sigma_dt`` (m).

    The tests' reference for the scenario's range accuracy; the package does not call it."""
    d_theta, d_dr = tdoa_df_jacobian(theta, dr, b)
    return np.sqrt((d_theta * sigma_theta) ** 2 + (d_dr * sigma_dr) ** 2)


def carry_forward(x: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Replace invalid samples (..., K) by the last valid one before them.

    Leading invalid samples take the row's first valid value; a row with none stays NaN."""
    K = x.shape[-1]
    idx = np.where(valid, np.arange(K), -1)
    idx = np.maximum.accumulate(idx, axis=-1)
    first = np.argmax(valid, axis=-1)[..., None]
    idx = np.where(idx < 0, first, idx)
    out = np.take_along_axis(x, idx, axis=-1)
    return np.where(valid.any(axis=-1, keepdims=True), out, np.nan)

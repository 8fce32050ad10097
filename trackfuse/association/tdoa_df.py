"""Emitter range from one bearing and one time difference of arrival (TDOA + DF).

A1 measures the bearing ``theta`` (rad), the pair A1, A2 (baseline ``b``, m) the range
difference ``dr = c dt`` (m); with ``u = [cos theta, sin theta]'``,
``r = (|b|^2 - dr^2) / (2 (u'b - dr))``. Samples whose denominator is near 0 or whose
``r <= 0`` are invalid (:func:`carry_forward` holds the last valid value). The range sd is
propagated to first order in closed form (exact, and checked against central differences).
Equations: ``docs/papers/esm_radar.md``, "TDOA-DF range".

Reference: Torrieri D., IEEE Trans. AES 20(2), 1984, 183-198.
"""

from __future__ import annotations

import numpy as np

C = 299_792_458.0  # speed of light, m/s


def tdoa_df_range(theta: np.ndarray, dr: np.ndarray, b: np.ndarray,
                  min_denominator: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Range from A1 by the TDOA-DF inversion.

    Parameters: ``theta`` (...,) bearing at A1 (rad). ``dr`` (...,) range difference ``|p - A1| - |p
    - A2|`` (m). ``b`` (2,) baseline ``A2 - A1`` (m). ``min_denominator`` samples with ``|2 (u'b -
    dr)|`` below this (m) are invalid.
    Returns ``r`` (...,) range (m); NaN where invalid. ``valid`` (...,) bool."""
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
    """Partial derivatives of the TDOA-DF range.

    Parameters: ``theta`` (...,) bearing (rad); ``dr`` (...,) range difference (m); ``b`` (2,)
    baseline (m).
    Returns ``dr_dtheta`` (...,) m/rad; ``dr_ddr`` (...,) m/m. NaN where ``r <= 0``."""
    r, _ = tdoa_df_range(theta, dr, b, min_denominator=0.0)
    D = 2.0 * (np.cos(theta) * b[0] + np.sin(theta) * b[1] - dr)
    ub_perp = -np.sin(theta) * b[0] + np.cos(theta) * b[1]
    return -2.0 * r * ub_perp / D, 2.0 * (r - dr) / D


def tdoa_df_range_sigma(theta: np.ndarray, dr: np.ndarray, b: np.ndarray, sigma_theta: float,
                        sigma_dr: float) -> np.ndarray:
    """First-order standard deviation of the TDOA-DF range (m).

    Parameters: ``theta`` (...,) bearing (rad); ``dr`` (...,) range difference (m); ``b`` (2,)
    baseline (m). ``sigma_theta`` bearing sd (rad). ``sigma_dr`` range-difference sd (m), i.e. ``c
    sigma_dt``.
    Returns ``sigma_r`` (...,) m; NaN where the inversion is invalid.

    The tests' reference for the scenario's range accuracy (tests/test_esm_radar_geometry.py);
    the package does not call it."""
    d_theta, d_dr = tdoa_df_jacobian(theta, dr, b)
    return np.sqrt((d_theta * sigma_theta) ** 2 + (d_dr * sigma_dr) ** 2)


def carry_forward(x: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Replace invalid samples along the last axis by the last valid one before them.

    Leading invalid samples take the first valid value of their row; a row with no valid
    sample stays NaN.

    Parameters: ``x`` (..., K) samples; ``valid`` (..., K) bool.
    Returns (..., K) array."""
    K = x.shape[-1]
    idx = np.where(valid, np.arange(K), -1)
    idx = np.maximum.accumulate(idx, axis=-1)
    first = np.argmax(valid, axis=-1)[..., None]
    idx = np.where(idx < 0, first, idx)
    out = np.take_along_axis(x, idx, axis=-1)
    return np.where(valid.any(axis=-1, keepdims=True), out, np.nan)

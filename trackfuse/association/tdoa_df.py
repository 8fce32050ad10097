"""Emitter range from one bearing and one time difference of arrival (TDOA + DF).

Two platforms A1 and A2 (baseline ``b = A2 - A1``, m) receive the same emission. A1 measures
the bearing ``theta`` (rad, from +x toward +y) and the pair measures the range difference
``dr = c dt = |p - A1| - |p - A2|`` (m). With ``u = [cos theta, sin theta]'`` the emitter is at
``p = A1 + r u`` and ``|r u - b| = r - dr``; squaring gives

    r = (|b|^2 - dr^2) / (2 (u'b - dr)).

The inversion is exact for noise-free inputs. It fails when the denominator is near 0 (the
bearing points along the hyperbola's asymptote) or gives ``r <= 0``: such samples are flagged
invalid, and :func:`carry_forward` holds the last valid value.

The range error follows from first-order propagation,
``sigma_r^2 = J diag(sigma_theta^2, sigma_dr^2) J'`` with ``J = [dr/dtheta, dr/d(dr)]``:

    dr/dtheta = -2 r (u_perp'b) / D,     dr/d(dr) = 2 (r - dr) / D,

``D = 2 (u'b - dr)`` and ``u_perp = [-sin theta, cos theta]'``. The closed form is used rather
than numerical derivatives because it is exact and cheaper; a test checks it against central
differences.

References
----------
D. Torrieri, "Statistical theory of passive location systems", IEEE Trans. AES 20(2), 1984,
183-198 (TDOA/DF geometry and error propagation).
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

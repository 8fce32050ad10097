"""Manoeuvre index from the residuals of a 1-D constant-velocity Kalman filter.

Paper 001 (eq. 8-13) scales the range weight by a manoeuvre index built from the Kalata
tracking index ``(sigma_w T^2 / sigma_n)`` and estimates the manoeuvre noise from the mean
square of the measurement residual ``V = Z - Zhat(k|k-1)``. That mixes metres with
accelerations (W001-4). The dimensionally consistent reading (SPEC 3.4 item 6): a CV
prediction under a constant acceleration ``a`` misses by ``a T^2 / 2``, so
``sigma_w = 2 sigma_V / T^2`` and

    alpha(k) = sigma_V(k)^2 / sigma_n(k)^2,   sigma_V(k)^2 = (1/N) sum_{last N residuals} V(i)^2.

``alpha`` is about 1 (slightly above: the residual also carries the prediction uncertainty)
for a target the CV model follows, and grows when the target manoeuvres.

The residuals come from a CV Kalman filter on the ESM range sequence ``r_E(k)``: state
``x = [r, rdot]`` (m, m/s), ``F = [[1, T], [0, 1]]``, ``H = [1, 0]``, piecewise-constant white
acceleration noise ``Q = q [[T^4/4, T^3/2], [T^3/2, T^2]]`` (``q`` in m^2/s^4) and a
time-varying measurement variance ``R(k) = sigma_rE(k)^2``. It starts by two-point
differencing, so the first residual is at scan 2; ``alpha`` is 0 (no evidence of a
manoeuvre) before that.

References
----------
P. R. Kalata, "The tracking index: a generalized parameter for alpha-beta and
alpha-beta-gamma target trackers", IEEE Trans. AES 20(2), 1984, 174-182.
Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
Navigation*, Wiley, 2001, sec. 6.3.2 (DWNA model) and 5.5 (two-point initialization).
"""

from __future__ import annotations

import numpy as np


def cv_residuals(z: np.ndarray, R: np.ndarray, T: float, q: float) -> np.ndarray:
    """Innovation sequence of a 1-D CV Kalman filter, vectorized over leading axes.

    Parameters
    ----------
    z : (..., K) measurements (m), K >= 2.
    R : (..., K) measurement variances (m^2), > 0.
    T : sampling period (s).
    q : white acceleration variance (m^2/s^4).

    Returns
    -------
    V : (..., K) residuals ``z(k) - H x(k|k-1)`` (m); NaN at scans 0 and 1.
    """
    z = np.asarray(z, dtype=float)
    R = np.broadcast_to(np.asarray(R, dtype=float), z.shape)
    K = z.shape[-1]
    V = np.full(z.shape, np.nan)
    # Two-point initialization at scan 1.
    r = z[..., 1].copy()
    v = (z[..., 1] - z[..., 0]) / T
    p11 = R[..., 1].copy()
    p12 = R[..., 1] / T
    p22 = (R[..., 0] + R[..., 1]) / T**2
    q11, q12, q22 = q * T**4 / 4, q * T**3 / 2, q * T**2
    for k in range(2, K):
        # Predict.
        r = r + T * v
        p11, p12, p22 = (p11 + 2 * T * p12 + T * T * p22 + q11, p12 + T * p22 + q12, p22 + q22)
        # Update.
        V[..., k] = nu = z[..., k] - r
        S = p11 + R[..., k]
        k1, k2 = p11 / S, p12 / S
        r = r + k1 * nu
        v = v + k2 * nu
        p11, p12, p22 = (1 - k1) * p11, (1 - k1) * p12, p22 - k2 * p12
    return V


def manoeuvre_index(V: np.ndarray, R: np.ndarray, window: int = 5) -> np.ndarray:
    """``alpha(k)``: mean square of the last ``window`` residuals over ``R(k)``.

    Parameters
    ----------
    V : (..., K) residuals (m); NaN where none exists yet.
    R : (..., K) measurement variances ``sigma_n(k)^2`` (m^2), > 0.
    window : number N of most recent residuals averaged (fewer at the start).

    Returns
    -------
    alpha : (..., K) dimensionless, >= 0; 0 where no residual exists yet.
    """
    valid = ~np.isnan(V)
    sq = np.where(valid, np.square(np.nan_to_num(V)), 0.0)
    csum = np.cumsum(sq, axis=-1)
    ccount = np.cumsum(valid, axis=-1)
    pad = [(0, 0)] * (V.ndim - 1) + [(window, 0)]
    csum_lag = np.pad(csum, pad)[..., :-window]
    ccount_lag = np.pad(ccount, pad)[..., :-window]
    n = ccount - ccount_lag
    mean_sq = np.divide(csum - csum_lag, n, out=np.zeros_like(csum), where=n > 0)
    return mean_sq / R

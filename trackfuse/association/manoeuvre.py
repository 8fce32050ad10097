"""Manoeuvre indices ``alpha(k)`` of the ESM track (paper 001 eq. 8-13); they cut the range weight.

Default: the windowed NIS of a 1-D nearly-constant-acceleration filter on ``c dt_E`` (m),
``N alpha ~ chi2(N)`` without a manoeuvre. The paper's literal form: mean square of the last
``N`` residuals of a 1-D CV filter on the TDOA-DF range over ``R``. Equations and why:
``docs/papers/esm_radar.md``, "Manoeuvre index and dynamic weights" and W001-4.

References: Bar-Shalom, Li, Kirubarajan, *Estimation with Applications to Tracking and
Navigation*, Wiley, 2001, sec. 5.4.2, 6.3.3, 11.2; Kalata P. R., IEEE Trans. AES 20(2), 1984."""

from __future__ import annotations

import numpy as np

from trackfuse.chi2 import chi2_quantile

#: Scan of the first innovation of the constant-acceleration filter (three-point start).
FIRST_CA_INNOVATION = 3


def _ca_start(z: np.ndarray, R: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray]:
    """State ``(..., 3)`` and covariance ``(..., 3, 3)`` at scan 2 from scans 0-2."""
    M = np.array([[0.0, 0.0, 1.0],
                  [1.0 / (2 * T), -2.0 / T, 3.0 / (2 * T)],
                  [1.0 / T**2, -2.0 / T**2, 1.0 / T**2]])   # x(2) = M z(0:3)
    x = np.einsum("ij,...j->...i", M, z[..., :3])
    P = np.einsum("ik,...k,jk->...ij", M, R[..., :3], M)
    return x, P


def ca_innovations(z: np.ndarray, R: np.ndarray, T: float,
                   q: float) -> tuple[np.ndarray, np.ndarray]:
    """Innovations ``nu`` (m) and variances ``S`` (m^2), (..., K), of a 1-D DWPA Kalman filter.

    ``z`` (..., K) m with K >= 4, ``R`` m^2, ``T`` s, ``q`` variance of the acceleration change
    per period (m^2/s^4). NaN at scans 0-2 (three-point start)."""
    z = np.asarray(z, dtype=float)
    R = np.broadcast_to(np.asarray(R, dtype=float), z.shape)
    F = np.array([[1.0, T, T * T / 2], [0.0, 1.0, T], [0.0, 0.0, 1.0]])
    G = np.array([T * T / 2, T, 1.0])
    Q = q * np.outer(G, G)
    nu = np.full(z.shape, np.nan)
    S = np.full(z.shape, np.nan)
    x, P = _ca_start(z, R, T)
    for k in range(FIRST_CA_INNOVATION, z.shape[-1]):
        x = x @ F.T
        P = F @ P @ F.T + Q
        S[..., k] = P[..., 0, 0] + R[..., k]
        nu[..., k] = z[..., k] - x[..., 0]
        gain = P[..., :, 0] / S[..., k, None]
        x = x + gain * nu[..., k, None]
        P = P - gain[..., :, None] * P[..., None, 0, :]
    return nu, S


def windowed_nis(nu: np.ndarray, S: np.ndarray, window: int) -> np.ndarray:
    """Mean NIS ``nu^2 / S`` (..., K) over the last ``window`` scans; NaN until full."""
    eps = np.square(nu) / S
    csum = np.cumsum(np.nan_to_num(eps), axis=-1)
    count = np.cumsum(~np.isnan(eps), axis=-1)
    pad = [(0, 0)] * (eps.ndim - 1) + [(window, 0)]
    total = csum - np.pad(csum, pad)[..., :-window]
    n = count - np.pad(count, pad)[..., :-window]
    return np.where(n == window, total / window, np.nan)


def nis_threshold(window: int, false_alarm: float) -> float:
    """``alpha_max``: the ``1 - false_alarm`` quantile of ``chi2(window) / window``."""
    return chi2_quantile(1.0 - false_alarm, window) / window


def cv_innovations(z: np.ndarray, R: np.ndarray, T: float,
                   q: float) -> tuple[np.ndarray, np.ndarray]:
    """Residuals ``nu`` (m) and variances ``S`` (m^2), (..., K), of a 1-D CV Kalman filter.

    ``z`` (..., K) m with K >= 2, ``R`` m^2, ``T`` s, ``q`` white acceleration variance
    (m^2/s^4). NaN at scans 0 and 1 (two-point start)."""
    z = np.asarray(z, dtype=float)
    R = np.broadcast_to(np.asarray(R, dtype=float), z.shape)
    K = z.shape[-1]
    V = np.full(z.shape, np.nan)
    S = np.full(z.shape, np.nan)
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
        S[..., k] = p11 + R[..., k]
        k1, k2 = p11 / S[..., k], p12 / S[..., k]
        r = r + k1 * nu
        v = v + k2 * nu
        p11, p12, p22 = (1 - k1) * p11, (1 - k1) * p12, p22 - k2 * p12
    return V, S


def manoeuvre_index(V: np.ndarray, R: np.ndarray, window: int = 5) -> np.ndarray:
    """The paper's literal ``alpha(k)`` (..., K): mean square of recent residuals over ``R(k)``.

    Averages the last ``window`` residuals (fewer at the start); NaN where none exists yet."""
    valid = ~np.isnan(V)
    sq = np.where(valid, np.square(np.nan_to_num(V)), 0.0)
    csum = np.cumsum(sq, axis=-1)
    ccount = np.cumsum(valid, axis=-1)
    pad = [(0, 0)] * (V.ndim - 1) + [(window, 0)]
    csum_lag = np.pad(csum, pad)[..., :-window]
    ccount_lag = np.pad(ccount, pad)[..., :-window]
    n = ccount - ccount_lag
    mean_sq = np.divide(csum - csum_lag, n, out=np.full_like(csum, np.nan), where=n > 0)
    return mean_sq / R

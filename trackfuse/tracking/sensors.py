"""Passive azimuth/elevation sensors: measurement function, Jacobian, MGEKF rows, gates, clutter.

Fixed Cartesian frame, z up; ``d`` is target minus sensor (m). ``h`` and ``H`` are paper
000 eq. 7, corrected; the modified rows are Song & Speyer's. Equations:
``docs/papers/twin_sensor.md``, "Measurements" and "MGEKF".

References: Song T. L., Speyer J. L., IEEE TAC 30(10), 1985; Bar-Shalom Y., Fortmann T. E.,
*Tracking and Data Association*, 1988, sec. 2.3."""

from __future__ import annotations

import math

import numpy as np

from trackfuse.chi2 import chi2_quantile


def azel(d: np.ndarray) -> np.ndarray:
    """Azimuth and elevation ``(..., 2)`` (rad) of relative positions ``d: (..., 3)`` (m)."""
    out = np.empty(d.shape[:-1] + (2,))
    np.arctan2(d[..., 1], d[..., 0], out=out[..., 0])
    np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]), out=out[..., 1])
    return out


def azel_jacobian(d: np.ndarray) -> np.ndarray:
    """Jacobian ``(..., 2, 6)`` (rad/m) of :func:`azel` w.r.t. the CV state, at ``d: (..., 3)``."""
    dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
    rh2 = dx * dx + dy * dy
    rh = np.sqrt(rh2)
    r2 = rh2 + dz * dz
    H = np.zeros(d.shape[:-1] + (2, 6))
    H[..., 0, 0] = -dy / rh2
    H[..., 0, 1] = dx / rh2
    H[..., 1, 0] = -dx * dz / (rh * r2)
    H[..., 1, 1] = -dy * dz / (rh * r2)
    H[..., 1, 2] = rh / r2
    return H


def modified_rows(z: np.ndarray, d_bar: np.ndarray) -> np.ndarray:
    """Song-Speyer modified rows (..., 2, 6) rad/m at measured angles ``z`` (..., 2) rad and
    predicted ``d_bar`` (..., 3) m. The tests' reference; the package uses the position columns."""
    g3 = modified_position_rows(z, d_bar)
    return np.concatenate([g3, np.zeros(g3.shape)], axis=-1)


def modified_position_rows(z: np.ndarray, d_bar: np.ndarray) -> np.ndarray:
    """The position columns ``(..., 2, 3)`` of :func:`modified_rows` (the rest are zero)."""
    c_th, s_th = np.cos(z[..., 0]), np.sin(z[..., 0])
    c_ph, s_ph = np.cos(z[..., 1]), np.sin(z[..., 1])
    rho = d_bar[..., 0] * c_th + d_bar[..., 1] * s_th
    inv_el = 1.0 / (rho * c_ph + d_bar[..., 2] * s_ph)
    inv_az = 1.0 / rho
    G = np.empty(np.broadcast_shapes(z.shape[:-1], d_bar.shape[:-1]) + (2, 3))
    G[..., 0, 0] = -s_th * inv_az
    G[..., 0, 1] = c_th * inv_az
    G[..., 0, 2] = 0.0
    G[..., 1, 0] = -s_ph * c_th * inv_el
    G[..., 1, 1] = -s_ph * s_th * inv_el
    G[..., 1, 2] = c_ph * inv_el
    return G


def gate_threshold(P_G: float, nz: int = 2) -> float:
    """Chi-square gate ``gamma`` with probability ``P_G`` for an ``nz``-dimensional innovation."""
    return chi2_quantile(P_G, nz)


def _gamma(x: float) -> float:
    """Gamma function: exact ``math.gamma`` at integers, scipy's elsewhere."""
    if float(x).is_integer():
        return math.gamma(x)
    from scipy.special import gamma  # on first use: see trackfuse/chi2.py

    return float(gamma(x))


def gate_volume(S: np.ndarray, gamma: float) -> np.ndarray:
    """Gate volume (...,) ``c_n gamma^(n/2) |S|^(1/2)``, ``S`` (..., n, n)."""
    n = S.shape[-1]
    c_n = np.pi ** (n / 2) / _gamma(n / 2 + 1)
    det = inv2(S)[1] if n == 2 else np.linalg.det(S)
    with np.errstate(invalid="ignore"):
        return c_n * gamma ** (n / 2) * np.sqrt(det)


def inv2(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and determinant of ``S`` (..., 2, 2); never raises (a singular ``S`` gives
    non-finite entries, so one diverged trial cannot stop a batch)."""
    a, b, c, d = S[..., 0, 0], S[..., 0, 1], S[..., 1, 0], S[..., 1, 1]
    det = a * d - b * c
    inv = np.empty(S.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(d, det, out=inv[..., 0, 0])
        np.divide(-b, det, out=inv[..., 0, 1])
        np.divide(-c, det, out=inv[..., 1, 0])
        np.divide(a, det, out=inv[..., 1, 1])
    return inv, det


def chol2(S: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of symmetric 2x2 matrices ``S: (..., 2, 2)``; NaN if not PD."""
    with np.errstate(divide="ignore", invalid="ignore"):
        l11 = np.sqrt(S[..., 0, 0])
        l21 = S[..., 1, 0] / l11
        l22 = np.sqrt(S[..., 1, 1] - l21 * l21)
    L = np.empty(S.shape)
    L[..., 0, 0], L[..., 0, 1], L[..., 1, 0], L[..., 1, 1] = l11, 0.0, l21, l22
    return L


def ellipse_points(u: np.ndarray, centre: np.ndarray, S: np.ndarray, gamma: float) -> np.ndarray:
    """Map unit-disk points ``u`` (N, M, 2) into the gates ``nu' S^-1 nu <= gamma`` about ``centre``
    (N, 2) with ``S`` (N, 2, 2): (N, M, 2) rad, still uniform (the map is linear)."""
    L = chol2(S)
    return centre[:, None, :] + np.sqrt(gamma) * (u @ L.transpose(0, 2, 1))

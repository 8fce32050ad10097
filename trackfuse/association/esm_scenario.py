"""Paper 001 world: snake-weaving and crossing targets and the five association factors.

Factors (:data:`FACTORS`, measured at A1): range (m), speed (m/s), bearing (rad), TDOA (s),
phase (rad). The ESM sees T2 only; its range comes from the TDOA-DF inversion. Geometry and
sensor models: ``docs/papers/esm_radar.md``, "Scenario" and "Factors and sensor models".

Reference: Zhang Xiaoqiang et al., J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49,
sec. 3."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackfuse.association.tdoa_df import (
    C,
    carry_forward,
    tdoa_df_jacobian,
    tdoa_df_range,
)

FACTORS = ("range", "speed", "angle", "tdoa", "phase")
ANGULAR = np.array([False, False, True, False, True])  # differences wrapped to (-pi, pi]


@dataclass(frozen=True)
class SnakeCross:
    """The three-target scenario; all lengths in m, times in s, speeds in m/s."""

    separation: float = 200.0
    amplitude: float = 1000.0
    snake_period: float = 40.0
    speed: float = 200.0
    t_cross: float = 30.0
    start: tuple[float, float] = (13000.0, 20000.0)
    start3: tuple[float, float] = (10200.0, 15000.0)

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions ``p`` (T, 3, 2) m, velocities ``v`` (T, 3, 2) m/s of T1-T3 at ``t`` (T,) s."""
        t = np.asarray(t, dtype=float)
        w = 2 * np.pi / self.snake_period
        x0, y0 = self.start
        p1 = np.stack([x0 + self.amplitude * np.sin(w * t), y0 - self.speed * t], axis=-1)
        v1 = np.stack([self.amplitude * w * np.cos(w * t), np.full_like(t, -self.speed)],
                      axis=-1)
        meet = np.array([x0 + self.separation / 2, y0 - self.speed * self.t_cross])
        v3 = (meet - np.asarray(self.start3)) / self.t_cross
        p3 = np.asarray(self.start3) + t[:, None] * v3
        p = np.stack([p1, p1 + [self.separation, 0.0], p3], axis=1)
        v = np.stack([v1, v1, np.broadcast_to(v3, v1.shape)], axis=1)
        return p, v


def position_factors(r: np.ndarray, theta: np.ndarray, A1: np.ndarray, A2: np.ndarray,
                     d_over_lambda: float) -> tuple[np.ndarray, np.ndarray]:
    """TDOA (s) and phase (rad) of the point at range ``r`` (m), bearing ``theta`` (rad) from A1."""
    b = np.asarray(A2, dtype=float) - np.asarray(A1, dtype=float)
    rho2 = np.hypot(r * np.cos(theta) - b[0], r * np.sin(theta) - b[1])
    return (r - rho2) / C, 2 * np.pi * d_over_lambda * np.cos(theta)


def position_factor_jacobian(r: np.ndarray, theta: np.ndarray, A1: np.ndarray, A2: np.ndarray,
                             d_over_lambda: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``dtdoa/dr`` (s/m), ``dtdoa/dtheta`` (s/rad), ``dphase/dtheta`` (rad/rad), each (...,)."""
    b = np.asarray(A2, dtype=float) - np.asarray(A1, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    rho2 = np.hypot(r * c - b[0], r * s - b[1])
    dtdoa_dr = (1.0 - (r - (c * b[0] + s * b[1])) / rho2) / C
    dtdoa_dtheta = r * (-s * b[0] + c * b[1]) / (rho2 * C)
    return dtdoa_dr, dtdoa_dtheta, -2 * np.pi * d_over_lambda * s


def true_factors(p: np.ndarray, v: np.ndarray, A1: np.ndarray, A2: np.ndarray,
                 d_over_lambda: float) -> np.ndarray:
    """The five factors (..., 5) of targets at ``p`` (m), velocity ``v`` (m/s), (..., 2)."""
    dp = p - np.asarray(A1, dtype=float)
    r = np.hypot(dp[..., 0], dp[..., 1])
    theta = np.arctan2(dp[..., 1], dp[..., 0])
    tdoa, phase = position_factors(r, theta, A1, A2, d_over_lambda)
    return np.stack([r, np.hypot(v[..., 0], v[..., 1]), theta, tdoa, phase], axis=-1)


@dataclass(frozen=True)
class ESMNoise:
    """ESM standard deviations (Table 2): speed m/s, angle rad, tdoa s, phase rad."""

    speed: float = 20.0
    angle: float = 0.03
    tdoa: float = 3e-8
    phase: float = 1.0


@dataclass(frozen=True)
class RadarNoise:
    """Radar standard deviations (Table 2); ``range_coef`` times the range gives the range sd."""

    range_coef: float = 0.01
    speed: float = 10.0
    angle: float = 8e-3
    tdoa: float = 3e-8
    phase: float = 0.5


def esm_factors(f_true: np.ndarray, z: np.ndarray, noise: ESMNoise, A1: np.ndarray,
                A2: np.ndarray, min_denominator: float = 1.0):
    """ESM measurements ``x`` (N, K, 5), covariance ``P`` (N, K, 5, 5) and ``valid`` (N, K).

    ``f_true`` (K, 5) true factors; ``z`` (N, K, 4) scaled standard-normal draws for (angle,
    tdoa, speed, phase). The TDOA-DF range is correlated with angle and tdoa; invalid samples
    are carried forward."""
    b = np.asarray(A2, dtype=float) - np.asarray(A1, dtype=float)
    theta = f_true[:, 2] + noise.angle * z[..., 0]
    tdoa = f_true[:, 3] + noise.tdoa * z[..., 1]
    speed = f_true[:, 1] + noise.speed * z[..., 2]
    phase = f_true[:, 4] + noise.phase * z[..., 3]
    r, valid = tdoa_df_range(theta, C * tdoa, b, min_denominator)
    dr_dtheta, dr_ddr = tdoa_df_jacobian(theta, C * tdoa, b)
    dr_ddt = C * dr_ddr
    sigma_r = np.sqrt((dr_dtheta * noise.angle) ** 2 + (dr_ddt * noise.tdoa) ** 2)
    r = carry_forward(r, valid)
    sigma_r = carry_forward(sigma_r, valid)
    dr_dtheta = carry_forward(dr_dtheta, valid)
    dr_ddt = carry_forward(dr_ddt, valid)
    x = np.stack([r, speed, theta, tdoa, phase], axis=-1)
    P = np.zeros(x.shape + (5,))
    P[..., 0, 0] = sigma_r**2
    P[..., 1, 1] = noise.speed**2
    P[..., 2, 2] = noise.angle**2
    P[..., 3, 3] = noise.tdoa**2
    P[..., 4, 4] = noise.phase**2
    P[..., 0, 2] = P[..., 2, 0] = dr_dtheta * noise.angle**2
    P[..., 0, 3] = P[..., 3, 0] = dr_ddt * noise.tdoa**2
    return x, P, valid


def radar_factors(f_true: np.ndarray, z: np.ndarray, noise: RadarNoise, model: str,
                  A1: np.ndarray, A2: np.ndarray, d_over_lambda: float):
    """Radar measurements ``x`` (N, M, J, 5) and covariance ``P`` (N, M, J, 5, 5) of every track.

    ``z`` (N, M, J, 5) scaled draws (the ``"derived"`` model ignores the last two). ``P`` is
    evaluated at the measured range and bearing (what the association algorithm knows)."""
    sig_r_true = noise.range_coef * f_true[..., 0]
    r = f_true[..., 0] + sig_r_true * z[..., 0]
    speed = f_true[..., 1] + noise.speed * z[..., 1]
    theta = f_true[..., 2] + noise.angle * z[..., 2]
    var_r = (noise.range_coef * r) ** 2
    P = np.zeros(r.shape + (5, 5))
    P[..., 0, 0] = var_r
    P[..., 1, 1] = noise.speed**2
    P[..., 2, 2] = noise.angle**2
    if model == "table":
        tdoa = f_true[..., 3] + noise.tdoa * z[..., 3]
        phase = f_true[..., 4] + noise.phase * z[..., 4]
        P[..., 3, 3] = noise.tdoa**2
        P[..., 4, 4] = noise.phase**2
    elif model == "derived":
        tdoa, phase = position_factors(r, theta, A1, A2, d_over_lambda)
        g_r, g_t, h_t = position_factor_jacobian(r, theta, A1, A2, d_over_lambda)
        var_t = noise.angle**2
        P[..., 3, 3] = g_r**2 * var_r + g_t**2 * var_t
        P[..., 4, 4] = h_t**2 * var_t
        P[..., 0, 3] = P[..., 3, 0] = g_r * var_r
        P[..., 2, 3] = P[..., 3, 2] = g_t * var_t
        P[..., 2, 4] = P[..., 4, 2] = h_t * var_t
        P[..., 3, 4] = P[..., 4, 3] = g_t * h_t * var_t
    else:
        raise ValueError(f"unknown radar factor model {model!r}")
    return np.stack([r, speed, theta, tdoa, phase], axis=-1), P


def nominal_sd(f_true: np.ndarray, esm_noise: ESMNoise, radar_noise: RadarNoise, model: str,
               A1: np.ndarray, A2: np.ndarray, d_over_lambda: float,
               min_denominator: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Per-factor sd (5,) of ESM and radar at the noise-free geometry, averaged over scans (no
    trial's noise); NaN where the TDOA-DF inversion fails at every scan."""
    K = f_true.shape[0]
    _, P_e, _ = esm_factors(f_true, np.zeros((1, K, 4)), esm_noise, A1, A2, min_denominator)
    _, P_r = radar_factors(f_true[:, None], np.zeros((1, K, 1, 5)), radar_noise, model, A1,
                           A2, d_over_lambda)
    sd_e = np.sqrt(np.diagonal(P_e[0], axis1=-2, axis2=-1))
    sd_r = np.sqrt(np.diagonal(P_r[0, :, 0], axis1=-2, axis2=-1))
    return _mean_or_nan(sd_e), _mean_or_nan(sd_r)


def _mean_or_nan(x: np.ndarray) -> np.ndarray:
    """Mean over the first axis ignoring NaN; NaN where a column has no finite value."""
    ok = np.isfinite(x)
    total = np.where(ok, x, 0.0).sum(axis=0)
    n = ok.sum(axis=0)
    return np.divide(total, n, out=np.full(total.shape, np.nan), where=n > 0)

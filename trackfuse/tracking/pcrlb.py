"""Posterior Cramer-Rao lower bound (PCRLB) for angle-only tracking from moving platforms.

Information recursion for linear-Gaussian dynamics (Tichavsky, Muravchik & Nehorai 1998),
written so that a singular (or zero) process noise ``Q = G q G'`` is allowed:

    J_0     = P_0^-1
    J_{k+1} = (Q + F J_k^-1 F')^-1 + J_z(k+1)
    J_z(k)  = sum_s q2_s(k) E[H_s(x_k)' R_s^-1 H_s(x_k)]

``H_s`` is the az/el Jacobian at the *true* state (for a deterministic truth the expectation
is an evaluation, for a random CV truth a Monte Carlo average over truth samples). With
``Q = 0`` the first term is ``F^-T J_k F^-1``, the information of a stationary target.

Clutter and missed detections enter through the information-reduction factor ``q2`` (Niu,
Willett & Bar-Shalom 2001; Zhang, Willett & Bar-Shalom 2005), computed by Monte Carlo in
whitened measurement coordinates with clutter density ``lambda_w = lambda |R|^(1/2)``:

    s(Z) = sum_i a_i z_i / ((1 - P_D) + sum_i a_i),   a_i = (P_D / lambda_w) phi(z_i)
    q2   = E[s_1^2]

Bounds: ``RMSE_range(k) >= sqrt(u_k' [J_k^-1]_pos u_k)`` along the true line of sight ``u_k``
and ``RMSE_pos(k) >= sqrt(trace [J_k^-1]_pos)``.

References
----------
P. Tichavsky, C. H. Muravchik and A. Nehorai, "Posterior Cramer-Rao bounds for discrete-time
nonlinear filtering", IEEE TSP 46(5), 1998.
R. Niu, P. Willett and Y. Bar-Shalom, "Matrix CRLB scaling due to measurements of uncertain
origin", IEEE TSP 49(7), 2001.
X. Zhang, P. Willett and Y. Bar-Shalom, "Dynamic Cramer-Rao bound for target tracking in
clutter", IEEE TAES 41(4), 2005.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np

from trackfuse.tracking.sensors import azel_jacobian


def measurement_information(x_true: np.ndarray, sensor_pos: np.ndarray,
                            R: np.ndarray) -> np.ndarray:
    """Expected clutter-free measurement information per sensor, ``(K, S, 6, 6)``.

    Parameters
    ----------
    x_true : (K, 6) true states, or (M, K, 6) Monte Carlo truth samples (averaged).
    sensor_pos : (K, S, 3) sensor positions (m).
    R : (S, 2, 2) measurement noise covariances (rad^2).
    """
    x = x_true if x_true.ndim == 3 else x_true[None]
    d = x[:, :, None, :3] - sensor_pos[None]  # (M, K, S, 3)
    H = azel_jacobian(d)  # (M, K, S, 2, 6)
    Ht_Rinv_H = H.transpose(0, 1, 2, 4, 3) @ np.linalg.inv(R)[None, None] @ H
    return Ht_Rinv_H.mean(axis=0)


def information_recursion(J0: np.ndarray, F: np.ndarray, Q: np.ndarray, Jz: np.ndarray,
                          q2: np.ndarray | Callable[[int, np.ndarray], np.ndarray] | None = None
                          ) -> np.ndarray:
    """Bound covariances ``J_k^-1: (K+1, 6, 6)`` for ``k = 0..K`` from ``J0: (6, 6)``.

    Parameters
    ----------
    J0 : (6, 6) prior information.
    F, Q : (6, 6) truth-model transition and process noise.
    Jz : (K, S, 6, 6) per-sensor information from :func:`measurement_information`.
    q2 : information-reduction factors, ``(K, S)``, or a function ``q2(k, Pp) -> (S,)`` of
        the scan ``k = 1..K`` and the bound's predicted covariance ``Pp: (6, 6)`` (for
        clutter whose density depends on the gate); ``None`` means no clutter, ``P_D = 1``.
    """
    out = np.empty((Jz.shape[0] + 1,) + J0.shape)
    Jinv = np.linalg.inv(J0)
    out[0] = Jinv
    for k in range(1, Jz.shape[0] + 1):
        Pp = Q + F @ Jinv @ F.T
        if q2 is None:
            factors = np.ones(Jz.shape[1])
        elif callable(q2):
            factors = np.asarray(q2(k, Pp))
        else:
            factors = np.asarray(q2)[k - 1]
        J = np.linalg.inv(Pp) + np.einsum("s,sab->ab", factors, Jz[k - 1])
        Jinv = np.linalg.inv(J)
        out[k] = 0.5 * (Jinv + Jinv.T)
    return out


def range_bound(Jinv: np.ndarray, x_true: np.ndarray, platform_pos: np.ndarray) -> np.ndarray:
    """``sqrt(u' [J^-1]_pos u)``: ``(K,)`` (m) along the true lines of sight.

    ``Jinv: (K, 6, 6)``, ``x_true: (K, 6)``, ``platform_pos: (K, 3)``.
    """
    u = x_true[:, :3] - platform_pos
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    return np.sqrt(np.einsum("ka,kab,kb->k", u, Jinv[:, :3, :3], u))


def position_bound(Jinv: np.ndarray) -> np.ndarray:
    """``sqrt(trace [J^-1]_pos)``: ``(K,)`` (m)."""
    return np.sqrt(np.trace(Jinv[:, :3, :3], axis1=1, axis2=2))


def irf_q2(lam_w: float, P_D: float = 1.0, n_samples: int = 20000, half_width: float = 6.0,
           seed: int = 0) -> float:
    """Information-reduction factor ``q2`` for a 2-D measurement (Monte Carlo, fixed seed).

    ``lam_w`` is the clutter density in whitened coordinates (per unit area), ``P_D`` the
    detection probability. Clutter is Poisson and uniform on the square
    ``[-half_width, half_width]^2`` (``P_G = 1`` up to a negligible truncation).
    """
    if lam_w <= 0.0:
        return float(P_D)
    rng = np.random.default_rng(seed)
    area = (2.0 * half_width) ** 2
    counts = rng.poisson(lam_w * area, n_samples)
    width = int(counts.max()) + 1
    pts = rng.uniform(-half_width, half_width, (n_samples, width, 2))
    present = rng.random(n_samples) < P_D
    pts[:, 0] = rng.standard_normal((n_samples, 2))
    mask = np.arange(width)[None, :] <= counts[:, None]
    mask[:, 0] = present
    a = np.where(mask, (P_D / lam_w) * np.exp(-0.5 * (pts**2).sum(axis=2)) / (2 * np.pi), 0.0)
    s1 = (a * pts[:, :, 0]).sum(axis=1) / ((1.0 - P_D) + a.sum(axis=1))
    return float(np.mean(s1**2))


#: ``_q2_table(P_D)`` for the detection probabilities of the shipped configs, as computed by
#: :func:`irf_q2` (seed 0, 6000 samples per point); tests/test_tracking_pcrlb.py recomputes
#: them to 1e-12 (numpy's ``exp`` differs in the last bit between CPUs with and without
#: AVX-512, so a recomputed table would too; the stored one is the same everywhere). Saves
#: each process about 1.2 s of CPU per value of ``P_D``.
Q2_TABLES: dict[float, tuple[float, ...]] = {
    1.0: (
        1.0, 1.0117041911020417, 1.0058804856065058, 0.9661613079584045, 0.9694959359726852,
        0.9689684617200449, 0.9679600432757322, 0.9725985702208934, 1.003605570048682,
        0.9656758234602962, 0.9781855498897576, 0.9899879801982248, 0.9672613394360318,
        0.9508305133033264, 0.9436808304373271, 0.9382741410658282, 0.8798984822253185,
        0.8436407803609152, 0.8465945183462106, 0.8172974976639689, 0.7057611373231087,
        0.6348095029489872, 0.5647656609319034, 0.48603002904428394, 0.38009949876359256,
        0.3203966204358016, 0.24340124092113039, 0.19313753297466485, 0.14107548775322312,
        0.10348100479945241, 0.07973079177054015, 0.05910829162237655, 0.04354203546235338,
        0.031949178642751784, 0.023898148524095955, 0.017796535402891608, 0.013007370430761014,
    ),
    0.8: (
        0.8, 0.7963186568478718, 0.7983520399857152, 0.7693910629658222, 0.7736242195996729,
        0.7698916746422017, 0.7456044941886096, 0.7524171301809546, 0.7980281586911893,
        0.7483390473073698, 0.7497436867129256, 0.7320865828778956, 0.7144191129313303,
        0.6999084193754076, 0.6807893139270876, 0.6655909394912608, 0.6240341936137037,
        0.6011976144217006, 0.5490178636229273, 0.5146067868478444, 0.45447215808293695,
        0.39330643831967116, 0.34024250788751814, 0.287909947093725, 0.22957149518819497,
        0.18627140265525452, 0.14358678406245495, 0.11467352551107324, 0.08527318242497277,
        0.06472033606829423, 0.04960658704446647, 0.036688760261208896, 0.027434943119415692,
        0.020305343116377245, 0.015084503022925463, 0.011357088500902213, 0.00828306460590793,
    ),
}


def q2_grid() -> np.ndarray:
    """Whitened densities ``(37,)`` of the ``q2`` table: 0, then 36 points from 1e-4 to 3."""
    return np.concatenate([[0.0], np.geomspace(1e-4, 3.0, 36)])


def compute_q2_table(P_D: float) -> np.ndarray:
    """``q2`` at every density of :func:`q2_grid` by :func:`irf_q2` (6000 samples, seed 0)."""
    return np.array([irf_q2(g, P_D, n_samples=6000) for g in q2_grid()])


@lru_cache(maxsize=16)
def _q2_table(P_D: float) -> tuple[np.ndarray, np.ndarray]:
    stored = Q2_TABLES.get(P_D)
    return q2_grid(), (np.array(stored) if stored is not None else compute_q2_table(P_D))


def irf_q2_interp(lam_w: np.ndarray, P_D: float = 1.0) -> np.ndarray:
    """``q2`` for an array of whitened densities, interpolated from a cached Monte Carlo table.

    Interpolation is linear in ``log lam_w`` on ``[1e-4, 3]``; below the table ``q2`` goes to
    its clutter-free value ``P_D``.
    """
    grid, table = _q2_table(float(P_D))
    lam = np.clip(np.asarray(lam_w, dtype=float), 0.0, grid[-1])
    log_grid = np.log(grid[1:])
    with np.errstate(divide="ignore"):
        q_log = np.interp(np.log(np.maximum(lam, 1e-300)), log_grid, table[1:],
                          left=np.nan, right=table[-1])
    small = lam < grid[1]
    q_small = table[0] + (table[1] - table[0]) * lam / grid[1]
    return np.where(small, q_small, q_log)

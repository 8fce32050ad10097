"""Posterior Cramer-Rao lower bound (PCRLB) for angle-only tracking from moving platforms.

Tichavsky's information recursion with a singular ``Q``; clutter and missed detections
enter through the information-reduction factor ``q2`` (Niu et al. 2001). Equations and the
stored ``q2`` table: ``docs/papers/twin_sensor.md``, "PCRLB".

References: Tichavsky, Muravchik, Nehorai, IEEE TSP 46(5), 1998; Niu, Willett, Bar-Shalom,
IEEE TSP 49(7), 2001; Zhang, Willett, Bar-Shalom, IEEE TAES 41(4), 2005."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from trackfuse.tracking.sensors import azel_jacobian

#: Samples per chunk of :func:`irf_q2`: at ``lam_w = 3`` about 0.9 million clutter points
#: (computing a whole table peaks at about 80 MB resident).
_IRF_CHUNK = 2048


def measurement_information(x_true: np.ndarray, sensor_pos: np.ndarray,
                            R: np.ndarray) -> np.ndarray:
    """Expected clutter-free information ``E[H' R^-1 H]`` per sensor, (K, S, 6, 6).

    ``x_true`` (K, 6), or (M, K, 6) truth samples averaged; ``sensor_pos`` (K, S, 3) m; ``R``
    (S, 2, 2) rad^2."""
    x = x_true if x_true.ndim == 3 else x_true[None]
    d = x[:, :, None, :3] - sensor_pos[None]  # (M, K, S, 3)
    H = azel_jacobian(d)  # (M, K, S, 2, 6)
    Ht_Rinv_H = H.transpose(0, 1, 2, 4, 3) @ np.linalg.inv(R)[None, None] @ H
    return Ht_Rinv_H.mean(axis=0)


def information_recursion(J0: np.ndarray, F: np.ndarray, Q: np.ndarray, Jz: np.ndarray,
                          q2: np.ndarray | Callable[[int, np.ndarray], np.ndarray] | None = None
                          ) -> np.ndarray:
    """Bound covariances ``J_k^-1`` (K+1, 6, 6), ``k = 0..K``, from prior information ``J0``.

    ``Jz`` (K, S, 6, 6) from :func:`measurement_information`; ``q2`` (K, S), or ``q2(k, Pp) ->
    (S,)`` when the clutter density depends on the gate, or ``None`` (no clutter, ``P_D = 1``)."""
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
    """``sqrt(u' [J^-1]_pos u)`` (K,) m along the true lines of sight from ``platform_pos``."""
    u = x_true[:, :3] - platform_pos
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    return np.sqrt(np.einsum("ka,kab,kb->k", u, Jinv[:, :3, :3], u))


def position_bound(Jinv: np.ndarray) -> np.ndarray:
    """``sqrt(trace [J^-1]_pos)``: ``(K,)`` (m)."""
    return np.sqrt(np.trace(Jinv[:, :3, :3], axis1=1, axis2=2))


def irf_q2(lam_w: float, P_D: float = 1.0, n_samples: int = 1_000_000,
           half_width: float = 6.0, seed: int = 0) -> tuple[float, float]:
    """``q2`` of a 2-D measurement and its standard error, by Monte Carlo from a fixed seed.

    ``lam_w`` clutter per unit whitened area (Poisson, uniform on a square). Each sample weighs
    "no clutter" and "at least one point" exactly, uses the square's symmetry and a control
    variate; the target draws are common to every ``lam_w``."""
    if lam_w <= 0.0 or P_D <= 0.0:  # no clutter, or no detection: nothing to estimate
        return float(P_D), 0.0
    mu = lam_w * (2.0 * half_width) ** 2
    target_rng, clutter_rng = (np.random.default_rng([seed, stream]) for stream in (0, 1))
    sums = np.zeros(6)  # n, sum g, sum c, sum g^2, sum c^2, sum g c (c centred at P_D)
    for start in range(0, n_samples, _IRF_CHUNK):
        m = min(_IRF_CHUNK, n_samples - start)
        g, c = _irf_chunk(lam_w, P_D, mu, half_width, m, target_rng, clutter_rng)
        c -= P_D
        sums += (m, g.sum(), c.sum(), g @ g, c @ c, g @ c)
    n = sums[0]
    g_mean, c_mean, gg, cc, gc = sums[1:] / n
    cov_gc = gc - g_mean * c_mean
    beta = cov_gc / (cc - c_mean**2)
    return (float(g_mean - beta * c_mean),
            float(np.sqrt((gg - g_mean**2 - beta * cov_gc) / n)))


def _irf_chunk(lam_w: float, P_D: float, mu: float, half_width: float, m: int,
               target_rng: np.random.Generator, clutter_rng: np.random.Generator
               ) -> tuple[np.ndarray, np.ndarray]:
    """The samples ``g`` and control variates ``c`` of :func:`irf_q2`, ``(m,)`` each."""
    z = target_rng.standard_normal((m, 2))
    c = np.where(target_rng.random(m) < P_D, 0.5 * np.einsum("ij,ij->i", z, z), 0.0)
    e_t = np.where(c > 0, np.exp(-c), 0.0)  # a_i = (P_D / lam_w) e_i / (2 pi)
    kappa = 2.0 * np.pi * lam_w * (1.0 - P_D) / P_D
    # N >= 1: the first point of a rate-mu Poisson process on [0, 1] given one, then the rest
    first = -np.log1p(clutter_rng.random(m) * np.expm1(-mu)) / mu
    counts = 1 + clutter_rng.poisson(mu * (1.0 - first))
    xy = clutter_rng.uniform(-half_width, half_width, (int(counts.sum()), 2))
    e = np.exp(-0.5 * np.einsum("ij,ij->i", xy, xy))
    starts = np.cumsum(counts) - counts
    s = ((np.add.reduceat(e[:, None] * xy, starts) + e_t[:, None] * z)
         / (kappa + np.add.reduceat(e, starts) + e_t)[:, None])
    p0 = np.exp(-mu)
    g = (p0 * c * (e_t / (kappa + e_t)) ** 2
         + (1.0 - p0) * 0.5 * np.einsum("ij,ij->i", s, s))
    return g, c


#: ``_q2_table(P_D)`` for the detection probabilities of the shipped configs: ``q2`` by
#: :func:`compute_q2_table` (seed 0, 10^6 samples a point), with standard errors from
#: 0.0005 % (``P_D = 1``, ``lam_w = 1e-4``) to 0.12 % (``P_D = 1``, ``lam_w = 0.3``) of
#: ``q2``. tests/test_tracking_pcrlb.py recomputes a few points to 1e-12 (numpy's ``exp``
#: differs in the last bit between CPUs with and without AVX-512, so a recomputed table would
#: too; the stored one is the same everywhere). Saves each process about 1 min of CPU per
#: value of ``P_D`` (another ``P_D`` is tabulated on demand: :data:`ON_DEMAND_SAMPLES`).
Q2_TABLES: dict[float, tuple[float, ...]] = {
    1.0: (
        1.0, 0.9986191082476626, 0.9981432726977686, 0.997503036109426, 0.9966415645323962,
        0.9954852815685292, 0.9939663616021858, 0.9919286442992484, 0.989215994769015,
        0.9854566224393181, 0.9805978390821625, 0.9740500637604249, 0.9655206157095744,
        0.9539651101914941, 0.939007623923479, 0.9194735630790871, 0.8946479066886857,
        0.861923338683082, 0.8215671274426503, 0.7708977154019715, 0.7111528676931186,
        0.6416796872553178, 0.5637367717612504, 0.48150730798950914, 0.39754533812841,
        0.31895238090434197, 0.24882037616047828, 0.18965050990353266, 0.14247717630821216,
        0.10596391017023624, 0.0789393625467593, 0.0584874412407389, 0.04348394241230833,
        0.032310028195243166, 0.02400888645453443, 0.017860576750445275, 0.013284449073474206,
    ),
    0.8: (
        0.8, 0.7937745706105427, 0.792110464452058, 0.7899609835002117, 0.7872472551269117,
        0.7839024581369975, 0.7796406154070813, 0.7744315458800498, 0.7678503901210619,
        0.7595941343902513, 0.7496422737624715, 0.7371306683899886, 0.722097034735722,
        0.7034213048979144, 0.6813090213970554, 0.6546674146727444, 0.6234181190129839,
        0.5872603528396373, 0.5456364390845242, 0.4990386879772871, 0.44798098872120423,
        0.3941004448680821, 0.33960262863909896, 0.2850588796405928, 0.23361521645768293,
        0.18693637981094904, 0.14682826687283887, 0.11321263814956325, 0.08617775601192669,
        0.0649944168462915, 0.048930957166155795, 0.03659695275066921, 0.02737496351579048,
        0.020430624822380644, 0.015231378735812273, 0.011353847763572823, 0.008460386763195162,
    ),
}


def q2_grid() -> np.ndarray:
    """Whitened densities ``(37,)`` of the ``q2`` table: 0, then 36 points from 1e-4 to 3."""
    return np.concatenate([[0.0], np.geomspace(1e-4, 3.0, 36)])


#: Samples a point of a table computed on demand, for a ``P_D`` not in :data:`Q2_TABLES`:
#: about 3 s of CPU instead of about a minute, standard errors up to about 0.5 % of ``q2``.
ON_DEMAND_SAMPLES = 50_000


def compute_q2_table(P_D: float, n_samples: int = 1_000_000) -> tuple[np.ndarray, np.ndarray]:
    """``q2`` and its standard error (37,) at each density of :func:`q2_grid` (seed 0)."""
    q2, se = np.array([irf_q2(g, P_D, n_samples=n_samples) for g in q2_grid()]).T
    return q2, se


@lru_cache(maxsize=16)
def _q2_table(P_D: float) -> tuple[np.ndarray, np.ndarray]:
    """Grid and ``q2`` table, ``(37,)`` each, read-only (the cache shares them)."""
    stored = Q2_TABLES.get(P_D)
    grid, table = q2_grid(), (np.array(stored) if stored is not None
                              else compute_q2_table(P_D, ON_DEMAND_SAMPLES)[0])
    grid.flags.writeable = table.flags.writeable = False
    return grid, table


def irf_q2_interp(lam_w: ArrayLike, P_D: float = 1.0) -> np.ndarray:
    """``q2`` for whitened densities ``lam_w`` (any shape), from the cached Monte Carlo table.

    Linear in ``log lam_w`` on ``[1e-4, 3]``; below, linear to ``P_D`` at 0; above, the last value.
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

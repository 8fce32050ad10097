"""Track-to-track association over the track history: the counting test and Wald's SPRT.

Both read whether ``m2_k = d_k' S_k^-1 d_k`` falls inside the chi-square gate ``gamma``;
competing tracks and "no decision" (-1) as in ``docs/papers/esm_radar.md``, "Tests over the
track history".

References: Sagild, Hem, Brekke, FUSION 2021; Wald A., Ann. Math. Statist. 16(2), 1945."""

from __future__ import annotations

import math

import numpy as np


def binomial_tail(n: int, p: float, m: int) -> float:
    """``P(Binomial(n, p) >= m)``, summed exactly."""
    return float(sum(math.comb(n, k) * p**k * (1.0 - p) ** (n - k)
                     for k in range(max(m, 0), n + 1)))


def counting_threshold(n: int, p_false: float, alpha: float) -> int:
    """Least ``M`` with ``P(Binomial(n, p_false) >= M) <= alpha``; ``n + 1`` (never) if none."""
    return next((m for m in range(n + 2) if binomial_tail(n, p_false, m) <= alpha), n + 1)


def _pick(accepted: np.ndarray, score: np.ndarray, m2_sum: np.ndarray) -> np.ndarray:
    """Accepted track of lowest ``score``, ties to smaller ``m2_sum``; -1 if none. All (..., J)."""
    key = np.where(accepted, score, np.inf)
    best = key.min(axis=-1, keepdims=True)
    tied = accepted & (key == best)
    j = np.argmin(np.where(tied, m2_sum, np.inf), axis=-1)
    return np.where(accepted.any(axis=-1), j, -1)


def counting_decision(m2: np.ndarray, gamma: float, n: int, threshold: int
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Counting test on the last ``n`` scans of ``m2`` (..., K, J): track (...,), counts."""
    window = m2[..., -n:, :]
    counts = (window <= gamma).sum(axis=-2)
    chosen = _pick(counts >= threshold, -counts.astype(float), window.sum(axis=-2))
    return chosen, counts


def sprt_decision(m2: np.ndarray, gamma: float, p_gate: float, p_false: float, alpha: float,
                  beta: float) -> tuple[np.ndarray, np.ndarray]:
    """Wald's SPRT on ``m2`` (..., K, J): chosen track (...,), final LLR (..., J) in nats."""
    inside = m2 <= gamma
    step = np.where(inside, math.log(p_gate / p_false),
                    math.log((1.0 - p_gate) / (1.0 - p_false)))
    llr = np.cumsum(step, axis=-2)
    upper, lower = math.log((1.0 - beta) / alpha), math.log(beta / (1.0 - alpha))
    crossed = (llr >= upper) | (llr <= lower)
    k = m2.shape[-2]
    stop = np.where(crossed.any(axis=-2), np.argmax(crossed, axis=-2), k - 1)
    final = np.take_along_axis(llr, stop[..., None, :], axis=-2)[..., 0, :]
    accepted = final >= upper
    chosen = _pick(accepted, stop.astype(float), m2.sum(axis=-2))
    return chosen, final

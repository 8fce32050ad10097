"""Fuzzy comprehensive evaluation for one-to-many track association (paper 001).

One ESM track against ``J`` radar tracks on ``F`` factors at ``K`` scans: memberships
``R(k)`` (F, J) are composed by weights ``a(k)`` (F,) into ``b(k) = a(k) R(k)`` (J,), and a
decision picks a track. Functions broadcast over leading axes (a batch is (N, K, F, J)).
Equations: ``docs/papers/esm_radar.md``, "Traditional baseline", "Improved fuzzy evaluation".

References: He You et al., *Multisensor Information Fusion with Applications*, 2000, ch. 7;
Zhang Xiaoqiang et al., J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49."""

from __future__ import annotations

import numpy as np


def inverse_distance_membership(d: np.ndarray, eps: np.ndarray, norm: str = "l1") -> np.ndarray:
    """Inverse-distance membership (paper 001 eq. 4, corrected), (..., J) in (0, 1].

    ``d`` (..., J) differences >= 0 floored at ``eps`` > 0 (same unit); ``norm`` "l1" makes rows
    sum to 1, "l2" gives them unit Euclidean norm."""
    inv = 1.0 / np.maximum(d, eps)
    if norm == "l1":
        return inv / inv.sum(axis=-1, keepdims=True)
    if norm == "l2":
        return inv / np.sqrt((inv * inv).sum(axis=-1, keepdims=True))
    raise ValueError(f"unknown membership norm {norm!r}")


def gaussian_membership(d: np.ndarray, var: np.ndarray, tau: float = 0.5) -> np.ndarray:
    """Gaussian grade ``exp(-tau d^2 / var)`` (..., J); ``var``: ESM + radar variance."""
    return np.exp(-tau * np.square(d) / var)


def gaussian_posterior_membership(d: np.ndarray, var: np.ndarray,
                                  tau: float = 0.5) -> np.ndarray:
    """Gaussian grade normalised over the track axis (a stable softmax); rows sum to 1."""
    logits = -tau * np.square(d) / var
    logits = logits - logits.max(axis=-1, keepdims=True)
    e = np.exp(logits)
    return e / e.sum(axis=-1, keepdims=True)


def compose(a: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``b_j = sum_i a_i r_ij`` (paper 001 eq. 17-18): (..., F), (..., F, J) -> (..., J)."""
    return np.einsum("...f,...fj->...j", a, R)


def decide_mean(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pick ``argmax_j mean_k b_j(k)`` from ``b`` (..., K, J); ties go to the lowest index.

    Returns the 0-based track index (...,) and the best minus second-best mean (>= 0)."""
    bbar = b.mean(axis=-2)
    top2 = np.sort(bbar, axis=-1)[..., -2:]
    return np.argmax(bbar, axis=-1), top2[..., 1] - top2[..., 0]


def decide_vote(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Majority vote over per-scan argmax decisions of ``b`` (..., K, J).

    Vote ties go to the larger mean membership (in [0, 1], so it never beats a one-vote lead).
    Returns the 0-based track index (...,) and the winner's vote lead as a fraction of K."""
    K, J = b.shape[-2:]
    votes = (np.argmax(b, axis=-1)[..., None] == np.arange(J)).sum(axis=-2)
    key = votes + 0.5 * np.clip(b.mean(axis=-2), 0.0, 1.0)
    top2 = np.sort(votes, axis=-1)[..., -2:]
    return np.argmax(key, axis=-1), (top2[..., 1] - top2[..., 0]) / K

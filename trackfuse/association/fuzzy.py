"""Fuzzy comprehensive evaluation for one-to-many track association (paper 001).

One ESM track against ``J`` radar tracks on ``F`` factors at ``K`` scans: per scan the
evaluation matrix ``R(k)`` (F, J) of memberships ``r_ij(k)`` is composed by the weights
``a(k)`` (F,) into ``b(k) = a(k) R(k)`` (J,), and the decision picks a track from ``b``.
Memberships, with ``d_ij >= 0`` the (wrapped) difference and ``s_ij^2 = sigma_i,E^2 +
sigma_i,R^2``: inverse distance L1 ``(1/d_ij) / sum_j' (1/d_ij')`` (``d`` floored at
``eps_i``), L2 ``(1/d_ij) / sqrt(sum_j' d_ij'^-2)``, the Gaussian grade ``exp(-tau d_ij^2 /
s_ij^2)`` (traditional) and the Gaussian posterior (the grade normalised over tracks; W001-1).
All functions broadcast over leading axes: a batch is (N, K, F, J). Equations:
``docs/papers/esm_radar.md``, "Traditional baseline" and "Improved fuzzy evaluation".

References: He You et al., *Multisensor Information Fusion with Applications*, 2000, ch. 7;
Zhang Xiaoqiang et al., J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49.
"""

from __future__ import annotations

import numpy as np


def inverse_distance_membership(d: np.ndarray, eps: np.ndarray, norm: str = "l1") -> np.ndarray:
    """Dynamic inverse-distance membership (paper 001 eq. 4, corrected).

    Parameters: ``d`` (..., J) absolute factor differences, >= 0, in the factor's unit. ``eps``
    floor for ``d`` (same unit), broadcastable to ``d``; must be > 0. ``norm`` ``"l1"`` (rows sum to
    1) or ``"l2"`` (rows have unit Euclidean norm).
    Returns ``r`` (..., J) memberships in (0, 1]."""
    inv = 1.0 / np.maximum(d, eps)
    if norm == "l1":
        return inv / inv.sum(axis=-1, keepdims=True)
    if norm == "l2":
        return inv / np.sqrt((inv * inv).sum(axis=-1, keepdims=True))
    raise ValueError(f"unknown membership norm {norm!r}")


def gaussian_membership(d: np.ndarray, var: np.ndarray, tau: float = 0.5) -> np.ndarray:
    """Static Gaussian grade of membership ``exp(-tau d^2 / var)``.

    Parameters: ``d`` (..., J) factor differences. ``var`` summed ESM + radar variance of the
    factor, broadcastable to ``d``, > 0. ``tau`` kernel sharpness (1/2 gives the Gaussian likelihood
    shape).
    Returns ``mu`` (..., J) in [0, 1]; 1 for a zero difference."""
    return np.exp(-tau * np.square(d) / var)


def gaussian_posterior_membership(d: np.ndarray, var: np.ndarray,
                                  tau: float = 0.5) -> np.ndarray:
    """Gaussian grade normalized over the last (track) axis, computed stably (softmax).

    Parameters and units as :func:`gaussian_membership`; each row sums to 1."""
    logits = -tau * np.square(d) / var
    logits = logits - logits.max(axis=-1, keepdims=True)
    e = np.exp(logits)
    return e / e.sum(axis=-1, keepdims=True)


def compose(a: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Weighted-average composition ``b_j = sum_i a_i r_ij`` (paper 001 eq. 17-18).

    Parameters: ``a`` (..., F) factor weights. ``R`` (..., F, J) evaluation matrices.
    Returns ``b`` (..., J)"""
    return np.einsum("...f,...fj->...j", a, R)


def decide_mean(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean-membership decision ``j* = argmax_j (1/K) sum_k b_j(k)``.

    Parameters: ``b`` (..., K, J) composed memberships per scan.
    Returns ``j`` (...,) chosen track index (0-based; ties go to the lowest index). ``margin``
    (...,) best minus second-best mean membership (>= 0)."""
    bbar = b.mean(axis=-2)
    top2 = np.sort(bbar, axis=-1)[..., -2:]
    return np.argmax(bbar, axis=-1), top2[..., 1] - top2[..., 0]


def decide_vote(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Majority vote over per-scan maximum-membership decisions.

    Ties in the vote count are broken by the larger mean membership (which lies in [0, 1] for
    weights summing to 1 and memberships in [0, 1], so it never overrides a one-vote lead).

    Parameters: ``b`` (..., K, J) composed memberships per scan.
    Returns ``j`` (...,) chosen track index (0-based). ``margin`` (...,) vote lead of the winner
    over the runner-up, as a fraction of K."""
    K, J = b.shape[-2:]
    votes = (np.argmax(b, axis=-1)[..., None] == np.arange(J)).sum(axis=-2)
    key = votes + 0.5 * np.clip(b.mean(axis=-2), 0.0, 1.0)
    top2 = np.sort(votes, axis=-1)[..., -2:]
    return np.argmax(key, axis=-1), (top2[..., 1] - top2[..., 0]) / K

"""Analytic hierarchy process (AHP): priority weights from a pairwise judgement matrix.

``B`` (n, n) positive reciprocal; weights ``a`` (n,) sum to 1. Consistency
``CR = CI / RI(n)``, accept ``CR < 0.1``. Paper 001's numbers: ``docs/papers/esm_radar.md``,
"Improved fuzzy evaluation" and W001-5.

References: Saaty T. L., J. Math. Psychol. 15(3), 1977, 234-281; Saaty T. L., *The Analytic
Hierarchy Process*, 1980."""

from __future__ import annotations

import numpy as np

#: Paper 001 Table 1, rows/columns (range, speed, angle, time difference, phase difference).
PAPER_001_JUDGEMENT = np.array([
    [1.0, 3.0, 5.0, 7.0, 9.0],
    [1 / 3, 1.0, 3.0, 5.0, 7.0],
    [1 / 5, 1 / 3, 1.0, 3.0, 5.0],
    [1 / 7, 1 / 5, 1 / 3, 1.0, 3.0],
    [1 / 9, 1 / 7, 1 / 5, 1 / 3, 1.0],
])

#: Paper 001's printed (rounded) weights for the same five factors: a model input (the AHP
#: method ``paper_rounded``) and the value the report compares the computed weights with.
PAPER_001_WEIGHTS = (0.51, 0.26, 0.13, 0.07, 0.03)

#: Saaty's random consistency index RI(n), n = 1..10 (index 0 unused).
RANDOM_INDEX = (0.0, 0.0, 0.0, 0.58, 0.90, 1.12, 1.24, 1.32, 1.41, 1.45, 1.49)


def _check(B: np.ndarray) -> np.ndarray:
    B = np.asarray(B, dtype=float)
    if B.ndim != 2 or B.shape[0] != B.shape[1] or np.any(B <= 0):
        raise ValueError("a judgement matrix must be square with positive entries")
    return B


def root_weights(B: np.ndarray) -> np.ndarray:
    """Root (geometric-mean) weights (n,) of ``B`` (n, n), summing to 1."""
    B = _check(B)
    g = np.exp(np.mean(np.log(B), axis=1))
    return g / g.sum()


def eigen_weights(B: np.ndarray) -> np.ndarray:
    """Principal-eigenvector weights (n,) of ``B`` (n, n), summing to 1 (Saaty 1977)."""
    B = _check(B)
    values, vectors = np.linalg.eig(B)
    v = np.real(vectors[:, np.argmax(np.real(values))])
    return v / v.sum()


def lambda_max(B: np.ndarray, a: np.ndarray | None = None) -> float:
    """Principal eigenvalue of ``B``; with weights ``a``, the estimate ``mean_i (B a)_i / a_i``."""
    B = _check(B)
    if a is None:
        return float(np.max(np.real(np.linalg.eigvals(B))))
    a = np.asarray(a, dtype=float)
    return float(np.mean(B @ a / a))


def consistency_index(lam: float, n: int) -> float:
    """``CI = (lambda_max - n) / (n - 1)``; 0 for ``n <= 2`` (always consistent)."""
    return 0.0 if n <= 2 else (lam - n) / (n - 1)


def consistency_ratio(B: np.ndarray) -> float:
    """``CR = CI / RI(n)``; 0 for ``n <= 2``; ValueError beyond n = 10."""
    B = _check(B)
    n = B.shape[0]
    if n <= 2:
        return 0.0
    if n >= len(RANDOM_INDEX):
        raise ValueError(f"no random index tabulated for n = {n}")
    return consistency_index(lambda_max(B), n) / RANDOM_INDEX[n]


def weights(B: np.ndarray, method: str = "root") -> np.ndarray:
    """AHP weights by ``method`` in ``{"root", "eigen"}``; see :func:`root_weights`."""
    if method == "root":
        return root_weights(B)
    if method == "eigen":
        return eigen_weights(B)
    raise ValueError(f"unknown AHP method {method!r}")

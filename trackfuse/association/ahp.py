"""Analytic hierarchy process (AHP): priority weights from a pairwise judgement matrix.

A judgement matrix ``B`` (``(n, n)``, positive, reciprocal: ``B[j, i] = 1 / B[i, j]``) holds
Saaty-scale comparisons of ``n`` criteria. Two standard ways turn it into a weight vector
``a`` (``(n,)``, positive, summing to 1):

* the **root (geometric-mean) method**: ``a_i = (prod_j b_ij)^(1/n) / sum_k (prod_j b_kj)^(1/n)``;
* the **eigenvector method**: ``a`` is the principal (Perron) eigenvector of ``B``, scaled to
  sum 1.

Consistency: ``lambda_max`` is the principal eigenvalue of ``B`` (``= n`` for a perfectly
consistent matrix), the consistency index ``CI = (lambda_max - n) / (n - 1)`` and the
consistency ratio ``CR = CI / RI(n)`` with Saaty's random index ``RI``. ``CR < 0.1`` is the
usual acceptance rule.

Paper 001 (Zhang et al. 2017, Table 1) orders its five factors as (range, speed, angle,
time difference, phase difference); :data:`PAPER_001_JUDGEMENT` is that matrix. Its root
weights are (0.5100, 0.2638, 0.1296, 0.0636, 0.0329), ``lambda_max = 5.23748``,
``CI = 0.0594`` and ``CR = 0.0530`` (``docs/papers/esm_radar.md``, section
"W001-5 factor numbering and rounded weights").

References
----------
T. L. Saaty, "A scaling method for priorities in hierarchical structures", J. Math. Psychol.
15(3), 1977, 234-281.
T. L. Saaty, *The Analytic Hierarchy Process*, McGraw-Hill, 1980 (random index table).
"""

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
    """Root (geometric-mean) method weights.

    Parameters: ``B`` (n, n) positive reciprocal judgement matrix.
    Returns ``a`` (n,) weights summing to 1."""
    B = _check(B)
    g = np.exp(np.mean(np.log(B), axis=1))
    return g / g.sum()


def eigen_weights(B: np.ndarray) -> np.ndarray:
    """Principal-eigenvector weights (Saaty 1977), scaled to sum to 1.

    Parameters: ``B`` (n, n) positive reciprocal judgement matrix.
    Returns ``a`` (n,) positive weights summing to 1."""
    B = _check(B)
    values, vectors = np.linalg.eig(B)
    v = np.real(vectors[:, np.argmax(np.real(values))])
    return v / v.sum()


def lambda_max(B: np.ndarray, a: np.ndarray | None = None) -> float:
    """Principal eigenvalue of ``B``, or its textbook estimate from a weight vector.

    Parameters: ``B`` (n, n) judgement matrix. ``a`` (n,) weights, optional. If given, returns the
    hand-calculation estimate ``(1/n) sum_i (B a)_i / a_i``, which equals the principal eigenvalue
    exactly when ``a`` is the principal eigenvector.
    Returns float"""
    B = _check(B)
    if a is None:
        return float(np.max(np.real(np.linalg.eigvals(B))))
    a = np.asarray(a, dtype=float)
    return float(np.mean(B @ a / a))


def consistency_index(lam: float, n: int) -> float:
    """``CI = (lambda_max - n) / (n - 1)``; 0 for ``n <= 2`` (always consistent)."""
    return 0.0 if n <= 2 else (lam - n) / (n - 1)


def consistency_ratio(B: np.ndarray) -> float:
    """``CR = CI / RI(n)`` with Saaty's random index; 0 for ``n <= 2``.

    Parameters: ``B`` (n, n) judgement matrix, ``3 <= n <= 10`` for a non-trivial ratio."""
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

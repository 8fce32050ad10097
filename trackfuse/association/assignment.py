"""Measurement-to-measurement assignment for two passive sensors: weights and exact solvers.

Each candidate pair is triangulated and scored by ``chi2_ij`` of its four angle residuals;
weights (:data:`COSTS`: ``paper``, ``printed``, ``pattipati``) give pair gains
``w_ij = a_ij - a_i0 - a_0j`` and ``J = sum w_ij``. Solvers: ``lsa_clip``, ``lsa_augmented``,
``enumerate`` (tests). Equations and W002-1/W002-4: ``docs/papers/passive_assoc.md``,
"Weights", "Departure from eq. 17 as printed" and "Exact optimum".

References: Pattipati K. R. et al., IEEE Trans. Automatic Control 37(2), 1992; Deb S. et al.,
IEEE Trans. AES 33(2), 1997; Crouse D. F., IEEE Trans. AES 52(4), 2016."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from trackfuse.association.triangulation import angle_residuals, triangulate

COSTS = ("paper", "printed", "pattipati")
"""Pair-weight forms of :func:`pair_weights`."""
EXACT = ("lsa_clip", "lsa_augmented")
"""Exact solvers a config may choose; ``"enumerate"`` (brute force) is a test reference."""
BRUTE_FORCE = "enumerate"


@dataclass(frozen=True)
class PairWeights:
    """Weights of one scan: ``a`` (m1, m2) log-likelihood of each pair, ``a_i0`` (m1,) and ``a_0j``
    (m2,) of leaving one unpaired, ``chi2`` (m1, m2) at the triangulated point."""

    a: np.ndarray
    a_i0: np.ndarray
    a_0j: np.ndarray
    chi2: np.ndarray

    @cached_property
    def gain(self) -> np.ndarray:
        """(m1, m2) pair gains ``w_ij = a_ij - a_i0 - a_0j`` (computed once, read-only)."""
        gain = self.a - self.a_i0[:, None] - self.a_0j[None, :]
        gain.flags.writeable = False  # shared by every solver of the scan
        return gain


@dataclass(frozen=True)
class Assignment:
    """Pairs: ``partner1`` (m1,), ``partner2`` (m2,) (-1: unpaired); ``objective`` summed gains."""

    partner1: np.ndarray
    partner2: np.ndarray
    objective: float


def pair_chi2(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
              sigma_a: float, sigma_b: float, tri: str = "unit_normal") -> np.ndarray:
    """Chi-square (m1, m2) of every pair at its triangulated point; z (m, 2) rad, s (3,) m."""
    m1, m2 = len(z1), len(z2)
    if m1 == 0 or m2 == 0:
        return np.zeros((m1, m2))
    Z1 = np.repeat(z1, m2, axis=0)
    Z2 = np.tile(z2, (m1, 1))
    p = triangulate(Z1, Z2, s1, s2, method=tri, sigma=(sigma_a, sigma_b))
    r = angle_residuals(p, Z1, Z2, s1, s2) / np.array([sigma_a, sigma_b, sigma_a, sigma_b])
    return np.einsum("ki,ki->k", r, r).reshape(m1, m2)


def pair_weights(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
                 sigma_a: float, sigma_b: float, p_d: float, p_f: float,
                 cost: str = "paper", tri: str = "unit_normal",
                 psi: tuple[float, float] | np.ndarray = (1.0, 1.0)) -> PairWeights:
    """:class:`PairWeights` of a scan: ``z1`` (m1, 2), ``z2`` (m2, 2) rad, ``s1``, ``s2`` (3,) m.

    ``cost`` one of :data:`COSTS` (``p_f`` for ``paper``/``printed``, ``psi`` (2,) rad^2 for
    ``pattipati``); ``tri`` the triangulation method."""
    chi2 = pair_chi2(z1, z2, s1, s2, sigma_a, sigma_b, tri)
    m1, m2 = chi2.shape
    log_norm = np.log(2.0 * np.pi * sigma_a * sigma_b)
    if cost in ("paper", "printed"):
        norm = log_norm if cost == "paper" else 0.0
        a = 2.0 * (np.log(p_d) - norm) - 0.5 * chi2
        dummy = np.log(p_f)
    elif cost == "pattipati":
        a = np.sum(np.log(p_d * np.asarray(psi, dtype=float)) - log_norm) - 0.5 * chi2
        dummy = 0.0
    else:
        raise ValueError(f"unknown cost {cost!r}")
    return PairWeights(a=a, a_i0=np.full(m1, dummy), a_0j=np.full(m2, dummy), chi2=chi2)


def objective(gain: np.ndarray, partner1: np.ndarray) -> float:
    """Sum of the pair gains ``w_ij`` of an assignment (partner1 (m1,), -1 = unpaired)."""
    rows = np.flatnonzero(partner1 >= 0)
    return float(gain[rows, partner1[rows]].sum())


def from_pairs(rows: np.ndarray, cols: np.ndarray, gain: np.ndarray) -> Assignment:
    """Build an :class:`Assignment` from paired indices ``rows[k] <-> cols[k]``."""
    m1, m2 = gain.shape
    p1 = np.full(m1, -1)
    p2 = np.full(m2, -1)
    p1[rows] = cols
    p2[cols] = rows
    return Assignment(partner1=p1, partner2=p2, objective=objective(gain, p1))


def linear_sum_assignment(cost: np.ndarray, maximize: bool = False):
    """``scipy.optimize.linear_sum_assignment``, imported on first use (about 0.5 s at load)."""
    from scipy.optimize import linear_sum_assignment as solve

    return solve(cost, maximize=maximize)


def _lsa_clip(gain: np.ndarray) -> Assignment:
    rows, cols = linear_sum_assignment(np.maximum(gain, 0.0), maximize=True)
    keep = gain[rows, cols] > 0.0
    return from_pairs(rows[keep], cols[keep], gain)


def _lsa_augmented(gain: np.ndarray) -> Assignment:
    # The gain form is the weight form with a_i0 = a_0j = 0, so the dummy diagonals are 0.
    m1, m2 = gain.shape
    C = np.full((m1 + m2, m2 + m1), np.inf)
    C[:m1, :m2] = -gain
    C[np.arange(m1), m2 + np.arange(m1)] = 0.0
    C[m1 + np.arange(m2), np.arange(m2)] = 0.0
    C[m1:, m2:] = 0.0
    rows, cols = linear_sum_assignment(C)
    real = (rows < m1) & (cols < m2)
    return from_pairs(rows[real], cols[real], gain)


def _enumerate(gain: np.ndarray) -> Assignment:
    m1, m2 = gain.shape
    g = gain.tolist()
    best_value = 0.0
    best: list[int] = [-1] * m1
    current = [-1] * m1
    used = [False] * m2

    def visit(i: int, value: float) -> None:
        nonlocal best_value, best
        if i == m1:
            if value > best_value:
                best_value, best = value, current.copy()
            return
        visit(i + 1, value)
        for j in range(m2):
            if not used[j]:
                used[j] = True
                current[i] = j
                visit(i + 1, value + g[i][j])
                current[i] = -1
                used[j] = False

    visit(0, 0.0)
    p1 = np.array(best, dtype=int)
    rows = np.flatnonzero(p1 >= 0)
    return from_pairs(rows, p1[rows], gain)


def solve_exact(gain: np.ndarray, method: str = "lsa_clip") -> Assignment:
    """Maximise the summed pair gains ``gain`` (m1, m2) over all partial matchings by ``method``."""
    gain = np.asarray(gain, dtype=float)
    if method == "lsa_clip":
        return _lsa_clip(gain)
    if method == "lsa_augmented":
        return _lsa_augmented(gain)
    if method == BRUTE_FORCE:
        return _enumerate(gain)
    raise ValueError(f"unknown exact method {method!r}")

"""Measurement-to-measurement assignment for two passive sensors: weights and exact solvers.

Weights (``docs/papers/passive_assoc.md``, "Weights"). For a candidate pair (measurement
``i`` of sensor 1, ``j`` of sensor 2)
triangulate ``p_hat`` (see :mod:`trackfuse.association.triangulation`), predict the four
angles and form ``chi2_ij``, the sum of the four squared noise-normalised residuals. Three
weight models are offered; all are *gains* to be maximised:

``"paper"`` (paper 002, eq. 12-18, sign of the quadratic corrected)
    ``a_ij = sum_s [ln P_D - ln(2 pi sigma_a sigma_b)] - chi2_ij / 2`` and
    ``a_i0 = a_0j = ln p_f``. A pair beats two unpaired measurements iff
    ``chi2 < 2 sum_s ln(P_D / (2 pi sigma_a sigma_b p_f))``, a threshold that depends on the
    angle unit because a density is compared with a probability (weakness W002-4).
``"printed"`` (paper 002's eq. 17 as printed, sign of the quadratic corrected)
    ``a_ij = sum_s ln P_D - chi2_ij / 2`` and ``a_i0 = a_0j = ln p_f``: the printed weight
    has no Gaussian normalising term ``ln(2 pi sigma_a sigma_b)``, so a pair beats two
    unpaired measurements iff ``chi2 < 2 sum_s ln(P_D / p_f)`` (11.8 at P_D = 0.95,
    p_f = 0.05; ``"paper"`` gives 46.8 at sigma = 0.005 rad). Its term ``- n_s ln p_m``
    cannot be read and is left out, as in ``"paper"``.
``"pattipati"`` (Pattipati et al. 1992; Deb et al. 1997)
    ``a_ij = sum_s ln(P_D psi_s / (2 pi sigma_a sigma_b)) - chi2_ij / 2`` and
    ``a_i0 = a_0j = 0``, with ``psi_s`` the area of sensor ``s``'s field of view (rad^2),
    i.e. the likelihood ratio of "pair from one target" against "two false alarms" with
    false alarms uniform over the FOV.

Objective. With 0/1 variables ``x_ij`` on the dummy-augmented matrix (row 0 and column 0 are
the dummies, each real row and column used exactly once), ``J = sum a_ij x_ij``. Writing the
pair gain ``w_ij = a_ij - a_i0 - a_0j`` gives ``J = const + sum_{pairs} w_ij``; this module
reports ``J = sum_{pairs} w_ij`` (the log-likelihood ratio of the partition against the
all-false partition).

Exact solvers (``docs/papers/passive_assoc.md``, "Exact optimum"): the paper claims the
Hungarian method cannot handle a variable
number of pairs (weakness W002-1); it can, in two equivalent ways:

``"lsa_clip"`` (default)
    ``linear_sum_assignment`` on ``max(W, 0)`` (rectangular, maximised), then drop the
    assigned pairs with ``w_ij <= 0``. Every full assignment's clipped value equals that of
    the matching keeping its positive pairs, and every matching extends to a full
    assignment without lowering the clipped value, so the optima coincide.
``"lsa_augmented"``
    The classical (m1 + m2) square cost matrix with dummy diagonals (e.g. Bar-Shalom & Li,
    *Multitarget-Multisensor Tracking: Principles and Techniques*, 1995; Deb et al. 1997):
    ``[[C, D1], [D2, 0]]`` with ``C = -a``, ``D1 = diag(-a_i0)``, ``D2 = diag(-a_0j)`` and
    ``+inf`` off the diagonals.
``"enumerate"``
    Brute force over every partial matching (for tests; O(sum_k C(m1,k) C(m2,k) k!)).

References
----------
Pattipati K. R., Deb S., Bar-Shalom Y., Washburn R. B., "A new relaxation algorithm and
passive sensor data association", IEEE Trans. Automatic Control 37(2), 1992.
Deb S., Yeddanapudi M., Pattipati K., Bar-Shalom Y., "A generalized S-D assignment algorithm
for multisensor-multitarget state estimation", IEEE Trans. AES 33(2), 1997.
Crouse D. F., "On implementing 2D rectangular assignment algorithms", IEEE Trans. AES 52(4),
2016 (the algorithm behind ``scipy.optimize.linear_sum_assignment``).
"""

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
    """Assignment weights of one two-sensor scan.

    Attributes
    ----------
    a : (m1, m2) pair weights ``a_ij`` (log-likelihood).
    a_i0 : (m1,) weight of leaving sensor-1 measurement ``i`` unpaired.
    a_0j : (m2,) weight of leaving sensor-2 measurement ``j`` unpaired.
    chi2 : (m1, m2) chi-square of the four angle residuals at the triangulated point.
    """

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
    """A feasible partition of two measurement lists into pairs and singletons.

    Attributes
    ----------
    partner1 : (m1,) index of the sensor-2 partner of each sensor-1 measurement, -1 if none.
    partner2 : (m2,) the inverse map, -1 if none.
    objective : sum of the pair gains ``w_ij`` over the pairs.
    """

    partner1: np.ndarray
    partner2: np.ndarray
    objective: float


def pair_chi2(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
              sigma_a: float, sigma_b: float, tri: str = "unit_normal") -> np.ndarray:
    """Chi-square of every candidate pair at its triangulated point.

    z1 : (m1, 2), z2 : (m2, 2) rad; s1, s2 : (3,) m. Returns (m1, m2).
    """
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
    """Assignment weights of a scan (module docstring).

    Parameters
    ----------
    z1 : (m1, 2), z2 : (m2, 2) measured azimuth/elevation, rad.
    s1, s2 : (3,) sensor positions, m.
    sigma_a, sigma_b : angle noise standard deviations, rad (both sensors).
    p_d : detection probability (both sensors).
    p_f : the paper's false-alarm likelihood (``"paper"`` and ``"printed"`` costs).
    cost : one of :data:`COSTS`.
    tri : triangulation method for ``p_hat``.
    psi : (2,) field-of-view areas, rad^2 (``"pattipati"`` cost only).
    """
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
    """``scipy.optimize.linear_sum_assignment``, imported on first use (scipy.optimize costs
    every ``trackfuse list``/``validate`` about half a second at module load)."""
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
    """Maximise the sum of pair gains over all partial matchings.

    Parameters
    ----------
    gain : (m1, m2) pair gains ``w_ij`` (:attr:`PairWeights.gain`).
    method : ``"lsa_clip"``, ``"lsa_augmented"`` or ``"enumerate"`` (module docstring).
    """
    gain = np.asarray(gain, dtype=float)
    if method == "lsa_clip":
        return _lsa_clip(gain)
    if method == "lsa_augmented":
        return _lsa_augmented(gain)
    if method == BRUTE_FORCE:
        return _enumerate(gain)
    raise ValueError(f"unknown exact method {method!r}")

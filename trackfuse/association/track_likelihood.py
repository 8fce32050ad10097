"""Maximum-likelihood track-to-track association: the statistical reference for paper 001.

Under "radar track ``j`` is the ESM target", the factor difference ``d_kj`` (F,) is to first
order zero-mean Gaussian with covariance ``S_kj = P_E(k) + P_Rj(k)``; with white errors and
equal priors the ML decision minimises ``L_j = sum_k [d_kj' S_kj^-1 d_kj + log |S_kj|]``.
The full covariance keeps the TDOA-DF range from counting as independent evidence. See
``docs/papers/esm_radar.md``, "ML reference".

References: Bar-Shalom Y., IEEE Trans. AC 26(2), 1981, 571-572; Bar-Shalom Y., Li X. R.,
*Multitarget-Multisensor Tracking*, 1995, sec. 8.4.
"""

from __future__ import annotations

import numpy as np

from trackfuse.chi2 import chi2_quantile


def gaussian_nll_terms(d: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Squared Mahalanobis distance and log-determinant, batched.

    ``S`` is scaled to a correlation matrix (the factors' units differ by ~20 orders of
    magnitude) and solved by LU, not Cholesky: with the TDOA-DF range and the ``derived`` radar
    model ``S`` can be numerically singular (condition numbers up to 1e17). ``d`` (..., F),
    ``S`` (..., F, F). Returns ``m2`` (...,) ``d' S^-1 d`` and ``logdet`` (...,) ``log |S|``."""
    s = np.sqrt(np.diagonal(S, axis1=-2, axis2=-1))
    Cn = S / (s[..., :, None] * s[..., None, :])
    e = d / s
    m2 = np.einsum("...i,...i->...", e, np.linalg.solve(Cn, e[..., None])[..., 0])
    _, logdet_c = np.linalg.slogdet(Cn)
    return m2, logdet_c + 2.0 * np.log(s).sum(axis=-1)


def ml_track_decision(d: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ML choice of radar track from per-scan factor differences.

    Parameters: ``d`` (..., K, J, F) factor differences (wrapped where angular). ``S`` (..., K, J,
    F, F) difference covariances.
    Returns ``j`` (...,) chosen track index (0-based). ``log_lr`` (...,) log-likelihood ratio of the
    best over the second-best track (>= 0). ``D`` (..., J) chi-square distances ``sum_k d' S^-1 d``.
    """
    m2, logdet = gaussian_nll_terms(d, S)
    D = m2.sum(axis=-2)
    L = D + logdet.sum(axis=-2)
    top2 = np.sort(L, axis=-1)[..., :2]
    return np.argmin(L, axis=-1), 0.5 * (top2[..., 1] - top2[..., 0]), D


def abstaining_decision(j: np.ndarray, log_lr: np.ndarray, D_best: np.ndarray, dof: int,
                        lr_threshold: float, gate_alpha: float) -> np.ndarray:
    """ML decision that may answer "no decision" (W001-6: the paper always forces a choice).

    Gate: ``D_best`` above the ``1 - gate_alpha`` quantile of chi-square with ``dof = K F``
    degrees of freedom means no track fits (``gate_alpha = 0``: no gate). Ambiguity: the best
    track is declared only if ``log_lr >= lr_threshold`` over the runner-up (``log(19)``: 95 %
    posterior between the two). ``j`` (...,) ML choice (0-based); ``log_lr``, ``D_best`` (...,).
    Returns (...,) int: ``j`` where both tests pass, else -1."""
    ok = log_lr >= lr_threshold
    if gate_alpha > 0:
        ok &= D_best <= chi2_quantile(1.0 - gate_alpha, dof)
    return np.where(ok, j, -1)

"""Manoeuvre-dependent factor weights (paper 001 eq. 14-16, corrected; W001-3).

With ``a(1)`` the static AHP weights (F,) (range first) and ``alpha(k)`` the manoeuvre index:
``a'_1(k+1) = a_1(1) exp(-(alpha(k) / alpha_max)^2)``, then every weight is its *static*
value over ``D = a'_1(k+1) + sum_{i>=2} a_i(1)``, so the weights always sum to 1 and the range
weight stays in ``[0.277, 0.51]`` for the paper's weights while ``alpha <= alpha_max``.
``alpha_max``: a given constant (``mode="fixed"``) or the running maximum of alpha
(``"running_max"``). Equations: ``docs/papers/esm_radar.md``, "Improved fuzzy evaluation".
"""

from __future__ import annotations

import numpy as np


def dynamic_weights(a1: np.ndarray, alpha: np.ndarray, alpha_max: float = 10.0,
                    mode: str = "fixed") -> np.ndarray:
    """Per-scan factor weights from the manoeuvre index.

    Parameters: ``a1`` (F,) static weights ``a(1)``, range first, summing to 1. ``alpha`` (..., K)
    manoeuvre index per scan (dimensionless, >= 0). The weights applied at scan ``k`` use
    ``alpha(k-1)``; scan 0 uses ``a(1)``. ``alpha_max`` normalizing constant for ``mode="fixed"`` (>
    0). ``mode`` ``"fixed"`` or ``"running_max"``.
    Returns ``a`` (..., K, F) weights, each row summing to 1."""
    a1 = np.asarray(a1, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    if mode == "fixed":
        ratio = alpha / alpha_max
    elif mode == "running_max":
        peak = np.maximum.accumulate(alpha, axis=-1)
        ratio = np.divide(alpha, peak, out=np.zeros_like(alpha), where=peak > 0)
    else:
        raise ValueError(f"unknown alpha_max mode {mode!r}")
    # Weights at scan k come from alpha(k-1): shift right by one, scan 0 gets ratio 0.
    lagged = np.concatenate([np.zeros_like(ratio[..., :1]), ratio[..., :-1]], axis=-1)
    a1_prime = a1[0] * np.exp(-np.square(lagged))
    D = a1_prime + a1[1:].sum()
    a = np.broadcast_to(a1, lagged.shape + a1.shape) / D[..., None]
    a = a.copy()
    a[..., 0] = a1_prime / D
    return a

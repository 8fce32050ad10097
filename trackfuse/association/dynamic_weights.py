"""Manoeuvre-dependent factor weights (paper 001 eq. 14-16, corrected; W001-3).

``a'_1(k+1) = a_1(1) exp(-(alpha(k) / alpha_max)^2)``; all weights are then renormalised to
sum to 1. See ``docs/papers/esm_radar.md``, "Improved fuzzy evaluation"."""

from __future__ import annotations

import numpy as np


def dynamic_weights(a1: np.ndarray, alpha: np.ndarray, alpha_max: float = 10.0,
                    mode: str = "fixed") -> np.ndarray:
    """Weights ``a`` (..., K, F), rows summing to 1, from ``alpha`` (..., K).

    ``a1`` (F,) static weights, range first. Scan ``k`` uses ``alpha(k-1)`` (scan 0 uses ``a1``);
    the normaliser is ``alpha_max`` (``mode="fixed"``) or the running maximum (``"running_max"``).
    """
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

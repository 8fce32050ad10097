"""Track initialization from a coarse range cue (``docs/papers/twin_sensor.md``,
Initialization); ``P0`` also gives the PCRLB's ``J0 = P0^-1``."""

from __future__ import annotations

import numpy as np

RANGE_CUES = ("absolute", "relative")


def range_cue_sd(cue: str, d: np.ndarray, sigma_range: float, fraction: float) -> float:
    """Range sd (m): ``sigma_range`` (``"absolute"``) or ``fraction * |d|`` (``"relative"``)."""
    if cue == "absolute":
        return float(sigma_range)
    if cue == "relative":
        return float(fraction * np.linalg.norm(d))
    raise ValueError(f"range cue must be one of {RANGE_CUES}, got {cue!r}")


def los_prior_covariance(d: np.ndarray, sigma_range: float, sigma_angle: float,
                         sigma_velocity: float) -> np.ndarray:
    """``P0`` (6, 6) for ``d`` (3,) m: ``sigma_range`` m along the line of sight, ``r sigma_angle``
    across, ``sigma_velocity`` m/s per velocity axis."""
    r = float(np.linalg.norm(d))
    u = d / r
    az = np.arctan2(d[1], d[0])
    el = np.arcsin(u[2])
    e_az = np.array([-np.sin(az), np.cos(az), 0.0])
    e_el = np.array([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)])
    P0 = np.zeros((6, 6))
    P0[:3, :3] = (sigma_range**2 * np.outer(u, u)
                  + (r * sigma_angle) ** 2 * (np.outer(e_az, e_az) + np.outer(e_el, e_el)))
    P0[3:, 3:] = sigma_velocity**2 * np.eye(3)
    return P0

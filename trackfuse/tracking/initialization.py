"""Track initialization from a coarse range cue (``docs/papers/twin_sensor.md``, Defaults).

The prior covariance is built in the line-of-sight frame of the sensor: standard deviation
``sigma_range`` along the line of sight, ``r * sigma_angle`` across it in azimuth and in
elevation, and ``sigma_velocity`` per velocity axis. The same ``P0`` initializes the filters
(``x0 ~ N(x_true(0), P0)``) and the PCRLB (``J0 = P0^-1``), which keeps the bound consistent.

The range cue is given either in metres (``"absolute"``, the paper's scenario: 20 km at
200 km) or as a fraction of the initial range (``"relative"``), so that a scenario whose
target is close does not inherit a cue as wide as the range itself.
"""

from __future__ import annotations

import numpy as np

RANGE_CUES = ("absolute", "relative")


def range_cue_sd(cue: str, d: np.ndarray, sigma_range: float, fraction: float) -> float:
    """Range standard deviation (m) of the radar cue for target-minus-sensor ``d: (3,)`` (m).

    Parameters: ``cue`` ``"absolute"`` (return ``sigma_range``) or ``"relative"`` (return ``fraction
    * |d|``). ``sigma_range`` absolute standard deviation (m). ``fraction`` standard deviation as a
    fraction of the range ``|d|`` (dimensionless)."""
    if cue == "absolute":
        return float(sigma_range)
    if cue == "relative":
        return float(fraction * np.linalg.norm(d))
    raise ValueError(f"range cue must be one of {RANGE_CUES}, got {cue!r}")


def los_prior_covariance(d: np.ndarray, sigma_range: float, sigma_angle: float,
                         sigma_velocity: float) -> np.ndarray:
    """Prior covariance ``P0: (6, 6)`` for target-minus-sensor position ``d: (3,)`` (m).

    Parameters: ``sigma_range`` range standard deviation (m). ``sigma_angle`` cross-range standard
    deviation per axis as an angle (rad). ``sigma_velocity`` velocity standard deviation per axis
    (m/s)."""
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

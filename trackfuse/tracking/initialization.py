"""Track initialization from a coarse range cue (SPEC 1.7, ``s000.init``).

The prior covariance is built in the line-of-sight frame of the sensor: standard deviation
``sigma_range`` along the line of sight, ``r * sigma_angle`` across it in azimuth and in
elevation, and ``sigma_velocity`` per velocity axis. The same ``P0`` initializes the filters
(``x0 ~ N(x_true(0), P0)``) and the PCRLB (``J0 = P0^-1``), which keeps the bound consistent.
"""

from __future__ import annotations

import numpy as np


def los_prior_covariance(d: np.ndarray, sigma_range: float, sigma_angle: float,
                         sigma_velocity: float) -> np.ndarray:
    """Prior covariance ``P0: (6, 6)`` for target-minus-sensor position ``d: (3,)`` (m).

    Parameters
    ----------
    sigma_range : range standard deviation (m).
    sigma_angle : cross-range standard deviation per axis as an angle (rad).
    sigma_velocity : velocity standard deviation per axis (m/s).
    """
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

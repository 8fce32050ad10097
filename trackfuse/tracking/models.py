"""Nearly-constant-velocity target model, state ``[x, y, z, vx, vy, vz]`` (m, m/s), discrete
white-noise acceleration (``docs/papers/twin_sensor.md``, Scenario); ``Q`` has rank 3."""

from __future__ import annotations

import numpy as np


def wrap(a: np.ndarray) -> np.ndarray:
    """Map angles (rad) to [-pi, pi); broadcasts over any shape."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def cv_transition(T: float) -> np.ndarray:
    """State transition ``F: (6, 6)`` of the CV model for period ``T`` (s)."""
    F = np.eye(6)
    F[:3, 3:] = T * np.eye(3)
    return F


def cv_noise_gain(T: float) -> np.ndarray:
    """Noise gain ``G: (6, 3)`` mapping a constant acceleration over one period (m/s^2)."""
    return np.vstack([0.5 * T**2 * np.eye(3), T * np.eye(3)])


def cv_process_noise(T: float, q: float) -> np.ndarray:
    """Process noise covariance ``Q = G q G': (6, 6)`` for acceleration variance ``q`` (m^2/s^4)."""
    G = cv_noise_gain(T)
    return q * G @ G.T

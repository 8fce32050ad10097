"""Sensor platform trajectories, known without error as in paper 000: a climbing orbit,
straight flight, and a formation offset (``docs/papers/twin_sensor.md``, Scenario)."""

from __future__ import annotations

import numpy as np


def orbit_positions(t: np.ndarray, start: np.ndarray, centre_xy: np.ndarray, speed: float,
                    climb: float, direction: int = 1) -> np.ndarray:
    """Positions (K, 3) m on a climbing orbit about ``centre_xy`` at ``t`` (K,) s; ``speed`` and
    ``climb`` m/s, ``direction`` +1 counter-clockwise."""
    t = np.asarray(t, dtype=float)
    rel = np.asarray(start[:2], dtype=float) - np.asarray(centre_xy, dtype=float)
    radius = float(np.hypot(rel[0], rel[1]))
    psi = np.arctan2(rel[1], rel[0]) + direction * speed / radius * t
    return np.stack([centre_xy[0] + radius * np.cos(psi), centre_xy[1] + radius * np.sin(psi),
                     start[2] + climb * t], axis=-1)


def straight_positions(t: np.ndarray, start: np.ndarray, speed: float, heading: float,
                       climb: float) -> np.ndarray:
    """Positions (K, 3) m of constant-velocity flight; ``heading`` rad from +x towards +y."""
    t = np.asarray(t, dtype=float)[:, None]
    v = np.array([speed * np.cos(heading), speed * np.sin(heading), climb])
    return np.asarray(start, dtype=float) + t * v


def baseline_offset(los_azimuth: float, baseline: float, angle: float) -> np.ndarray:
    """Horizontal offset (3,) m of length ``baseline`` at ``angle`` rad from the line-of-sight
    azimuth (``pi/2``: broadside)."""
    a = los_azimuth + angle
    return np.array([baseline * np.cos(a), baseline * np.sin(a), 0.0])

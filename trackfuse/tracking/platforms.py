"""Sensor platform trajectories (positions known without error, as in paper 000).

* :func:`orbit_positions`: a horizontal circle about a centre with a constant climb rate. The
  radius and initial phase follow from the start point, so the paper's scenario (start
  ``(153 209, 0, 2 000)`` m, centre ``(0, 128 558)`` m, 500 m/s, climb 50 m/s) gives
  ``R = 200 km`` and ``psi0 = -40 deg`` (docs/papers/twin_sensor.md, Scenario).
* :func:`straight_positions`: constant-velocity flight.
* :func:`baseline_offset`: the fixed formation offset of a second platform, horizontal, at a
  given angle from the initial line of sight, so two sensors can be co-located (baseline 0,
  the paper) or far apart (triangulation).
"""

from __future__ import annotations

import numpy as np


def orbit_positions(t: np.ndarray, start: np.ndarray, centre_xy: np.ndarray, speed: float,
                    climb: float, direction: int = 1) -> np.ndarray:
    """Positions ``(K, 3)`` (m) on a climbing horizontal orbit at times ``t: (K,)`` (s).

    Parameters: ``start`` (3,) position at ``t = 0`` (m). ``centre_xy`` (2,) horizontal centre of
    the circle (m). ``speed`` horizontal speed along the arc (m/s). ``climb`` vertical rate (m/s).
    ``direction`` +1 counter-clockwise, -1 clockwise (seen from above)."""
    t = np.asarray(t, dtype=float)
    rel = np.asarray(start[:2], dtype=float) - np.asarray(centre_xy, dtype=float)
    radius = float(np.hypot(rel[0], rel[1]))
    psi = np.arctan2(rel[1], rel[0]) + direction * speed / radius * t
    return np.stack([centre_xy[0] + radius * np.cos(psi), centre_xy[1] + radius * np.sin(psi),
                     start[2] + climb * t], axis=-1)


def straight_positions(t: np.ndarray, start: np.ndarray, speed: float, heading: float,
                       climb: float) -> np.ndarray:
    """Positions ``(K, 3)`` (m) of constant-velocity flight.

    ``heading`` (rad) is the horizontal course from +x towards +y, ``speed`` the horizontal
    speed (m/s), ``climb`` the vertical rate (m/s)."""
    t = np.asarray(t, dtype=float)[:, None]
    v = np.array([speed * np.cos(heading), speed * np.sin(heading), climb])
    return np.asarray(start, dtype=float) + t * v


def baseline_offset(los_azimuth: float, baseline: float, angle: float) -> np.ndarray:
    """Horizontal offset ``(3,)`` (m) of a second platform flying in formation.

    The offset has length ``baseline`` (m) and points at ``angle`` (rad) from the line-of-sight
    azimuth ``los_azimuth`` (rad); ``angle = pi/2`` is broadside, the best triangulation
    geometry."""
    a = los_azimuth + angle
    return np.array([baseline * np.cos(a), baseline * np.sin(a), 0.0])

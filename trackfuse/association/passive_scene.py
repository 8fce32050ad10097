"""Scenario of paper 002: two passive (angle-only) sensors observing a set of point targets.

Each sensor detects each target with probability ``P_D`` and reports its azimuth and
elevation (rad) with independent ``N(0, sigma^2)`` errors; false alarms, Poisson with mean
``P_F N`` (or Binomial), are uniform in the field-of-view box around the true angles widened
by ``margin``. Lists are shuffled; target labels (``-1``: false alarm) are kept for scoring.
Scenes: ``paper`` (the first ``n`` of M1-M10) or ``random`` (``n`` uniform in their bounding
box). Geometry and defaults: ``docs/papers/passive_assoc.md``, "Model".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import azel

KM = 1000.0

#: Sensor positions (2, 3) in metres.
SENSORS = np.array([[0.0, 0.0, 0.0], [0.0, 20.0, 7.0]]) * KM

#: Paper targets M1-M10, (10, 3) in metres.
PAPER_TARGETS = np.array([
    [5, 7, 1], [9, 10, 8], [17, 8, 4], [14, 3, 10], [8, 16, 6],
    [11, 13, 5], [7, 19, 4], [7, 12, 20], [10, 4, 9], [13, 15, 14],
], dtype=float) * KM

#: Axis-aligned bounding box of M1-M10, (2, 3) [low; high] in metres.
PAPER_BOX = np.stack([PAPER_TARGETS.min(axis=0), PAPER_TARGETS.max(axis=0)])


def los_angles(p: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Azimuth and elevation of points seen from a sensor.

    Parameters: ``p`` (..., 3) target positions, m. ``s`` (3,) sensor position, m.
    Returns (..., 2) array of ``[azimuth, elevation]`` in rad."""
    return azel(np.asarray(p, dtype=float) - s)


@dataclass(frozen=True)
class PassiveScan:
    """One simultaneous scan of every sensor (two in paper 002, S in the S-D assignment).

    Attributes: ``targets`` (N, 3) true target positions, m. ``sensors`` (S, 3) sensor positions, m.
    ``z`` one (m_s, 2) array of measured ``[azimuth, elevation]`` per sensor, rad, shuffled.
    ``labels`` one (m_s,) int array per sensor: the target index of each measurement, -1 for a false
    alarm (for scoring only). ``fov`` (S, 4) per-sensor box ``[a_low, a_high, b_low, b_high]``, rad.
    """

    targets: np.ndarray
    sensors: np.ndarray
    z: tuple[np.ndarray, ...]
    labels: tuple[np.ndarray, ...]
    fov: np.ndarray

    @property
    def psi(self) -> np.ndarray:
        """(S,) field-of-view areas ``(a_high - a_low)(b_high - b_low)``, rad^2."""
        return (self.fov[:, 1] - self.fov[:, 0]) * (self.fov[:, 3] - self.fov[:, 2])


def scene_targets(n: int, mode: str, rng: np.random.Generator) -> np.ndarray:
    """Target positions (n, 3) in m: the paper's first ``n`` or ``n`` uniform in its box."""
    if mode == "paper":
        if not 1 <= n <= len(PAPER_TARGETS):
            raise ValueError(f"paper scene has 1..{len(PAPER_TARGETS)} targets, got {n}")
        return PAPER_TARGETS[:n].copy()
    if mode == "random":
        return rng.uniform(PAPER_BOX[0], PAPER_BOX[1], size=(n, 3))
    raise ValueError(f"unknown scene mode {mode!r}")


def fov_box(angles: np.ndarray, margin: float) -> np.ndarray:
    """Field-of-view box (4,) ``[a_low, a_high, b_low, b_high]`` around angles (N, 2), rad."""
    lo = angles.min(axis=0) - margin
    hi = angles.max(axis=0) + margin
    return np.array([lo[0], hi[0], lo[1], hi[1]])


def simulate_scan(targets: np.ndarray, sigma_a: float, sigma_b: float, p_d: float,
                  p_f: float, rng_noise: np.random.Generator,
                  rng_clutter: np.random.Generator, rng_shuffle: np.random.Generator,
                  clutter: str = "poisson", margin: float = 0.1,
                  sensors: np.ndarray = SENSORS) -> PassiveScan:
    """Simulate one scan of every sensor (in sensor order, so the first two sensors' data
    do not depend on the sensors after them).

    Parameters: ``targets`` (N, 3) target positions, m. ``sigma_a``, ``sigma_b`` azimuth / elevation
    noise standard deviations, rad. ``p_d`` detection probability of each sensor. ``p_f``
    false-alarm parameter; the count is Poisson(p_f N) or Binomial(N, p_f). ``rng_noise``,
    ``rng_clutter``, ``rng_shuffle`` independent streams for detection and angle noise, false
    alarms, and the shuffling of each sensor's list. ``clutter`` ``"poisson"`` or ``"binomial"``.
    ``margin`` FOV box margin around the true angles, rad. ``sensors`` (S, 3) sensor positions, m.
    """
    n = len(targets)
    zs, labels, boxes = [], [], []
    for s in range(len(sensors)):
        true = los_angles(targets, sensors[s])
        detected = rng_noise.random(n) < p_d
        noise = rng_noise.standard_normal((n, 2)) * (sigma_a, sigma_b)
        box = fov_box(true, margin)
        if clutter == "poisson":
            n_fa = int(rng_clutter.poisson(p_f * n))
        elif clutter == "binomial":
            n_fa = int(rng_clutter.binomial(n, p_f))
        else:
            raise ValueError(f"unknown clutter model {clutter!r}")
        fa = rng_clutter.uniform(box[[0, 2]], box[[1, 3]], size=(n_fa, 2))
        z = np.concatenate([(true + noise)[detected], fa])
        z[:, 0] = wrap(z[:, 0])
        lab = np.concatenate([np.flatnonzero(detected), np.full(n_fa, -1)])
        order = rng_shuffle.permutation(len(z))
        zs.append(z[order])
        labels.append(lab[order])
        boxes.append(box)
    return PassiveScan(targets=targets, sensors=sensors, z=tuple(zs), labels=tuple(labels),
                       fov=np.array(boxes))


def true_partners(labels1: np.ndarray, labels2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ground-truth partner of every measurement, -1 for the dummy.

    The partner of a measurement of target ``t`` is the other sensor's measurement of ``t``
    if that sensor detected it, else the dummy; a false alarm's partner is the dummy.
    Returns ((m1,), (m2,)) int arrays of indices into the other sensor's list, or -1."""
    where2 = {int(t): j for j, t in enumerate(labels2) if t >= 0}
    p1 = np.full(len(labels1), -1)
    p2 = np.full(len(labels2), -1)
    for i, t in enumerate(labels1):
        j = where2.get(int(t), -1) if t >= 0 else -1
        if j >= 0:
            p1[i] = j
            p2[j] = i
    return p1, p2

"""Scenario of paper 002: two (or S) passive angle-only sensors observing point targets.

Detections with ``P_D``, Gaussian az/el errors, Poisson (or Binomial) false alarms uniform
in a widened field-of-view box; lists shuffled, labels kept for scoring. Geometry and
defaults: ``docs/papers/passive_assoc.md``, "Model"."""

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
    """``[azimuth, elevation]`` (..., 2) rad of points ``p`` (..., 3) m seen from ``s`` (3,) m."""
    return azel(np.asarray(p, dtype=float) - s)


@dataclass(frozen=True)
class PassiveScan:
    """One simultaneous scan of every sensor.

    ``targets`` (N, 3) m, ``sensors`` (S, 3) m; per sensor ``z`` (m_s, 2) rad (shuffled) and
    ``labels`` (m_s,) (target index, -1 false alarm); ``fov`` (S, 4) az and el bounds, rad."""

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
    """Simulate one scan of every sensor, in sensor order (the first sensors' data do not depend on
    later ones). ``rng_noise``, ``rng_clutter``, ``rng_shuffle`` are independent streams;
    ``p_f`` gives Poisson(p_f N) or Binomial(N, p_f) false alarms; ``margin`` rad."""
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
    """True partner (index into the other list) of every measurement, -1 for the dummy (a false
    alarm, or a target the other sensor missed): ((m1,), (m2,))."""
    where2 = {int(t): j for j, t in enumerate(labels2) if t >= 0}
    p1 = np.full(len(labels1), -1)
    p2 = np.full(len(labels2), -1)
    for i, t in enumerate(labels1):
        j = where2.get(int(t), -1) if t >= 0 else -1
        if j >= 0:
            p1[i] = j
            p2[j] = i
    return p1, p2

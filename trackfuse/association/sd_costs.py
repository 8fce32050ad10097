"""Costs (nats) of S-tuples of passive az/el measurements, for the S-D assignment.

``c = -[sum_{s real} g_s - chi2 / 2 + (S - k) ln(1 - P_D)]`` at the LS intersection of the
tuple's ``k >= 2`` lines of sight; 0 for at most one real index, ``+inf`` for parallel lines.
With ``volume`` the position is integrated out (Laplace). Equations:
``docs/papers/sd_assignment.md``, "Costs". The loop runs compiled (numba, cached on disk)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
from numba import njit

from trackfuse.association.triangulation import los_rows

JIT = {"cache": True, "nogil": True, "error_model": "numpy"}

COSTS = ("paper", "pattipati")
"""Tuple-cost forms of :func:`tuple_costs` (those of paper 002's pair weights)."""


def sensor_gains(n_sensors: int, sigma_a: float, sigma_b: float, p_d: float, p_f: float,
                 cost: str, psi: Sequence[float] | None) -> np.ndarray:
    """(S,) the per-sensor log-likelihood-ratio term ``g_s`` of a real measurement, nats."""
    log_norm = np.log(2.0 * np.pi * sigma_a * sigma_b)
    if cost == "paper":
        return np.full(n_sensors, np.log(p_d) - log_norm - np.log(p_f))
    if cost == "pattipati":
        if psi is None or len(psi) != n_sensors:
            raise ValueError(f"cost 'pattipati' needs one FOV area per sensor ({n_sensors})")
        return np.log(p_d * np.asarray(psi, dtype=float)) - log_norm
    raise ValueError(f"unknown cost {cost!r}; allowed: {', '.join(COSTS)}")


def subset_fit(z: Sequence[np.ndarray], sensors: np.ndarray, sigma_a: float,
               sigma_b: float) -> tuple[np.ndarray, np.ndarray]:
    """Chi-square at the LS intersection (``+inf`` if undefined) and log-determinant of the
    position information (1/m^2; ``-inf`` if singular), each (m_1, ..., m_S'), of every
    combination. ``z``: S' arrays (m_s, 2) rad; ``sensors`` (S', 3) m. Oracle:
    ``tests/sd_reference.py``."""
    shape = tuple(len(zs) for zs in z)
    if 0 in shape:
        return np.zeros(shape), np.zeros(shape)
    width = max(shape)
    rows = np.zeros((len(z), width, 2, 3))
    rhs = np.zeros((len(z), width, 2))
    angles = np.zeros((len(z), width, 2))
    for s, (zs, pos) in enumerate(zip(z, sensors, strict=True)):
        rows[s, :len(zs)], rhs[s, :len(zs)] = los_rows(np.asarray(zs, dtype=float), pos)
        angles[s, :len(zs)] = zs
    chi2, logdet = _combination_fit(rows, rhs, angles, np.asarray(sensors, dtype=float),
                                    np.array(shape, np.int64), 1.0 / sigma_a, 1.0 / sigma_b)
    return chi2.reshape(shape), logdet.reshape(shape)


@njit(**JIT)
def _combination_fit(rows, rhs, angles, sensors, counts, inv_a, inv_b):
    """Chi-square and information log-determinant of each combination, C order, from rows
    (k, m, 2, 3), rhs (k, m, 2), angles (k, m, 2) rad and sensors (k, 3) m."""
    k = counts.shape[0]
    total = 1
    for s in range(k):
        total *= counts[s]
    chi2_out, logdet_out = np.empty(total), np.empty(total)
    pick = np.empty(k, np.int64)
    for flat in range(total):
        rest = flat
        for s in range(k - 1, -1, -1):
            pick[s] = rest % counts[s]
            rest //= counts[s]
        p = _intersection(rows, rhs, pick)
        chi2, info = 0.0, np.zeros((3, 3))
        for s in range(k):
            dx, dy = p[0] - sensors[s, 0], p[1] - sensors[s, 1]
            dz = p[2] - sensors[s, 2]
            r_a = (angles[s, pick[s], 0] - math.atan2(dy, dx) + math.pi) % (2.0 * math.pi) \
                - math.pi
            r_b = angles[s, pick[s], 1] - math.atan2(dz, math.hypot(dx, dy))
            chi2 += (r_a * inv_a) ** 2 + (r_b * inv_b) ** 2
            _add_information(info, dx, dy, dz, inv_a, inv_b)
        chi2_out[flat] = chi2 if math.isfinite(chi2) else math.inf
        det = _determinant(info)
        logdet_out[flat] = math.log(det) if det > 0.0 else -math.inf
    return chi2_out, logdet_out


@njit(**JIT)
def _add_information(info, dx, dy, dz, inv_a, inv_b):
    """Add ``H' R^-1 H`` at relative position ``(dx, dy, dz)`` m to ``info`` (3, 3)."""
    rh2 = dx * dx + dy * dy
    rh = math.sqrt(rh2)
    r2 = rh2 + dz * dz
    h_a = (-dy / rh2 * inv_a, dx / rh2 * inv_a, 0.0)
    h_b = (-dx * dz / (rh * r2) * inv_b, -dy * dz / (rh * r2) * inv_b, rh / r2 * inv_b)
    for i in range(3):
        for j in range(3):
            info[i, j] += h_a[i] * h_a[j] + h_b[i] * h_b[j]


@njit(**JIT)
def _determinant(m):
    """Determinant of a 3 x 3 matrix."""
    return (m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1])
            - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
            + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]))


@njit(**JIT)
def _intersection(rows, rhs, pick):
    """LS point (3,) of the picked rows (normal equations, adjugate / determinant)."""
    m = np.zeros((3, 3))
    v = np.zeros(3)
    for s in range(pick.shape[0]):
        for r in range(2):
            a = rows[s, pick[s], r]
            for i in range(3):
                v[i] += a[i] * rhs[s, pick[s], r]
                for j in range(3):
                    m[i, j] += a[i] * a[j]
    adj = np.empty((3, 3))
    for i in range(3):
        c1, c2 = m[:, (i + 1) % 3], m[:, (i + 2) % 3]
        adj[i, 0] = c1[1] * c2[2] - c1[2] * c2[1]
        adj[i, 1] = c1[2] * c2[0] - c1[0] * c2[2]
        adj[i, 2] = c1[0] * c2[1] - c1[1] * c2[0]
    det = m[0, 0] * adj[0, 0] + m[1, 0] * adj[0, 1] + m[2, 0] * adj[0, 2]
    return (adj @ v) / det


def tuple_costs(z: Sequence[np.ndarray], sensors: np.ndarray, sigma_a: float,
                sigma_b: float, p_d: float, p_f: float, cost: str = "paper",
                psi: Sequence[float] | None = None, volume: float | None = None
                ) -> np.ndarray:
    """Cost tensor (m_1 + 1, ..., m_S + 1) of a scan, nats.

    ``z``: S arrays (m_s, 2) rad; ``sensors`` (S, 3) m; ``sigma_a``, ``sigma_b`` rad; ``cost``
    ``"paper"`` or ``"pattipati"`` (``psi`` (S,) FOV areas, rad^2); ``volume`` (m^3) for the
    marginal position, None for the fitted one."""
    n_sensors = len(z)
    gains = sensor_gains(n_sensors, sigma_a, sigma_b, p_d, p_f, cost, psi)
    log_miss = np.log1p(-p_d) if p_d < 1.0 else -np.inf
    out = np.zeros(tuple(len(zs) + 1 for zs in z))
    for k in range(2, n_sensors + 1):
        missed = (n_sensors - k) * log_miss if n_sensors > k else 0.0
        for subset in itertools.combinations(range(n_sensors), k):
            chi2, logdet = subset_fit([z[s] for s in subset], sensors[list(subset)],
                                      sigma_a, sigma_b)
            gain = gains[list(subset)].sum() - 0.5 * chi2 + missed
            if volume is not None:  # no position (parallel lines): no target
                with np.errstate(invalid="ignore"):
                    gain = np.where(np.isfinite(logdet) & np.isfinite(chi2),
                                    gain + occam_term(logdet, volume), -np.inf)
            where = tuple(slice(1, None) if s in subset else 0 for s in range(n_sensors))
            out[where] = -gain
    return out


def occam_term(logdet_info: np.ndarray, volume: float) -> np.ndarray:
    """``ln((2 pi)^{3/2} |P|^{1/2} / V)`` nats: position integrated over volume ``V`` (Laplace)."""
    return 1.5 * np.log(2.0 * np.pi) - 0.5 * logdet_info - np.log(volume)

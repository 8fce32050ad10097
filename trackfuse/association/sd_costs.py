"""Costs of S-tuples of passive (azimuth/elevation) measurements, for the S-D assignment.

A tuple ``(i_1, ..., i_S)`` takes measurement ``i_s`` of sensor ``s`` (0: none, the dummy).
For a tuple with ``k >= 2`` real measurements (``docs/papers/sd_assignment.md``, "Costs"):
the target position ``p_hat`` is the least-squares intersection of its ``k`` lines of sight
(:func:`trackfuse.association.triangulation.intersect`), ``chi2`` the sum of the ``2k``
squared noise-normalised angle residuals at ``p_hat``, and the cost is the negative
log-likelihood ratio of "one target, seen by these ``k`` sensors and missed by the other
``S - k``" against "these ``k`` measurements are false alarms":

    c = -[ sum_{s real} g_s - chi2 / 2 + (S - k) ln(1 - P_D) ]

with, as the two-sensor weights of :func:`trackfuse.association.assignment.pair_weights`,

``"paper"``      ``g_s = ln P_D - ln(2 pi sigma_a sigma_b) - ln p_f``
``"pattipati"``  ``g_s = ln(P_D psi_s) - ln(2 pi sigma_a sigma_b)`` (``psi_s``: FOV area, rad^2).

A tuple with at most one real measurement costs 0: a lone line of sight fixes no position,
and it is the reference hypothesis (the measurement is a false alarm). With ``S = 2`` the
costs are minus the pair gains ``w_ij`` of ``pair_weights`` (tested). A tuple whose lines of
sight are parallel (no intersection) costs ``+inf``.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from trackfuse.association.triangulation import intersect, los_residuals

COSTS = ("paper", "pattipati")


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


def subset_chi2(z: Sequence[np.ndarray], sensors: np.ndarray, sigma_a: float,
                sigma_b: float) -> np.ndarray:
    """Chi-square of every combination of one measurement per listed sensor.

    z : S' arrays (m_s, 2) rad; sensors : (S', 3) m. Returns (m_1, ..., m_S') at the
    least-squares intersection (``+inf`` where it is undefined)."""
    shape = tuple(len(zs) for zs in z)
    if 0 in shape:
        return np.zeros(shape)
    grids = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    picked = [zs[g.ravel()] for zs, g in zip(z, grids, strict=True)]
    with np.errstate(divide="ignore", invalid="ignore"):  # parallel lines: inf below
        p = intersect(picked, sensors)
        r = los_residuals(p, picked, sensors) / np.tile([sigma_a, sigma_b], len(z))
        chi2 = np.einsum("ki,ki->k", r, r)
    return np.where(np.isfinite(chi2), chi2, np.inf).reshape(shape)


def tuple_costs(z: Sequence[np.ndarray], sensors: np.ndarray, sigma_a: float,
                sigma_b: float, p_d: float, p_f: float, cost: str = "paper",
                psi: Sequence[float] | None = None) -> np.ndarray:
    """The cost tensor (m_1 + 1, ..., m_S + 1) of a scan, nats (module docstring).

    Parameters
    ----------
    z : S arrays (m_s, 2) of measured azimuth/elevation, rad.
    sensors : (S, 3) sensor positions, m.
    sigma_a, sigma_b : angle noise standard deviations, rad (every sensor).
    p_d : detection probability (every sensor); p_f : the paper's false-alarm likelihood.
    cost : ``"paper"`` or ``"pattipati"``; psi : (S,) FOV areas, rad^2 (``"pattipati"``).
    """
    n_sensors = len(z)
    gains = sensor_gains(n_sensors, sigma_a, sigma_b, p_d, p_f, cost, psi)
    log_miss = np.log1p(-p_d) if p_d < 1.0 else -np.inf
    out = np.zeros(tuple(len(zs) + 1 for zs in z))
    for k in range(2, n_sensors + 1):
        missed = (n_sensors - k) * log_miss if n_sensors > k else 0.0
        for subset in itertools.combinations(range(n_sensors), k):
            chi2 = subset_chi2([z[s] for s in subset], sensors[list(subset)], sigma_a,
                               sigma_b)
            where = tuple(slice(1, None) if s in subset else 0 for s in range(n_sensors))
            out[where] = -(gains[list(subset)].sum() - 0.5 * chi2 + missed)
    return out

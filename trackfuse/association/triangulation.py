"""Triangulation of a 3-D point from one azimuth/elevation line of sight (LOS) per sensor.

Each LOS gives two linear equations ``A_s p = B_s`` in ``p`` (m), solved by least squares
(paper 002 eq. 4-7). Forms (:data:`METHODS`) and equations: ``docs/papers/passive_assoc.md``,
"Triangulation". Vectorised over ``K`` candidates; :func:`intersect` and
:func:`los_residuals` take any ``S' >= 2`` lines of sight (``docs/papers/sd_assignment.md``).

References: Liu H. et al., Control and Decision 23(4), 2008, eq. 4-8; Bar-Shalom, Li,
Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, ch. 3; Hartley,
Zisserman, *Multiple View Geometry*, 2nd ed., 2003, ch. 12."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from trackfuse.association.passive_scene import los_angles
from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import azel_jacobian

METHODS = ("paper", "unit_normal", "wls", "ml")


def los_rows(z: np.ndarray, s: np.ndarray, form: str = "unit_normal"
             ) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (K, 2, 3) and ``B`` (K, 2) m of one LOS: ``z`` (K, 2) rad, sensor ``s`` (3,) m."""
    a, b = z[:, 0], z[:, 1]
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    zero = np.zeros_like(a)
    if form == "paper":
        A = np.stack([np.stack([sa, -ca, zero], -1), np.stack([sb, zero, -ca * cb], -1)], 1)
    elif form == "unit_normal":
        A = np.stack([np.stack([sa, -ca, zero], -1), np.stack([-ca * sb, -sa * sb, cb], -1)], 1)
    else:
        raise ValueError(f"unknown row form {form!r}")
    return A, A @ s


def _solve_normal(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Batched ``(A'A)^-1 A'B``: (K, r, 3), (K, r) -> (K, 3), by Cramer's rule (fast)."""
    M = np.einsum("kri,krj->kij", A, A)
    v = np.einsum("kri,kr->ki", A, B)
    c0, c1, c2 = M[:, :, 0], M[:, :, 1], M[:, :, 2]
    adj = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=1)
    det = np.einsum("ki,ki->k", c0, adj[:, 0])
    return np.einsum("kij,kj->ki", adj, v) / det[:, None]


def _stack(z1, z2, s1, s2, form):
    A1, B1 = los_rows(z1, s1, form)
    A2, B2 = los_rows(z2, s2, form)
    return np.concatenate([A1, A2], 1), np.concatenate([B1, B2], 1)


def least_squares(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
                  form: str = "unit_normal") -> np.ndarray:
    """Unweighted LS of the stacked 4 x 3 system (paper eq. 4-7): (K, 3) m."""
    return _solve_normal(*_stack(np.atleast_2d(z1), np.atleast_2d(z2), s1, s2, form))


def intersect(z: Sequence[np.ndarray], sensors: np.ndarray) -> np.ndarray:
    """LS intersection of ``S' >= 2`` LOS (unit-normal rows), (K, 3) m; z: S' arrays (K, 2) rad."""
    rows = [los_rows(np.atleast_2d(zs), s) for zs, s in zip(z, sensors, strict=True)]
    return _solve_normal(np.concatenate([A for A, _ in rows], 1),
                         np.concatenate([B for _, B in rows], 1))


def los_residuals(p: np.ndarray, z: Sequence[np.ndarray], sensors: np.ndarray) -> np.ndarray:
    """Measured minus predicted angles, azimuths wrapped: (K, 2 S') rad, ``[a_1, b_1, ...]``."""
    r = np.concatenate([zs - los_angles(p, s) for zs, s in zip(z, sensors, strict=True)], 1)
    r[:, 0::2] = wrap(r[:, 0::2])
    return r


def angle_jacobian(p: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Jacobian of ``[az, el]`` with respect to ``p`` (K, 3): (K, 2, 3) rad/m."""
    return azel_jacobian(p - s)[..., :3]


def angle_residuals(p: np.ndarray, z1: np.ndarray, z2: np.ndarray, s1: np.ndarray,
                    s2: np.ndarray) -> np.ndarray:
    """Measured minus predicted angles (paper eq. 8), wrapped: (K, 4) rad."""
    r = np.concatenate([z1 - los_angles(p, s1), z2 - los_angles(p, s2)], axis=1)
    r[:, [0, 2]] = wrap(r[:, [0, 2]])
    return r


def triangulate(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
                method: str = "unit_normal", sigma: tuple[float, float] = (1.0, 1.0),
                iterations: int = 3) -> np.ndarray:
    """Position (K, 3) m of each candidate pair ``z1``, ``z2`` (K, 2) rad; sensors ``s1``, ``s2`` m.

    ``sigma`` = ``(sigma_a, sigma_b)`` rad weights ``wls`` and ``ml``; ``iterations`` are
    Gauss-Newton steps for ``ml``."""
    z1 = np.atleast_2d(np.asarray(z1, dtype=float))
    z2 = np.atleast_2d(np.asarray(z2, dtype=float))
    if method not in METHODS:
        raise ValueError(f"unknown triangulation method {method!r}")
    if method == "paper":
        return least_squares(z1, z2, s1, s2, "paper")
    # unit-normal LS in closed form: it is the common-perpendicular midpoint (tested)
    p = common_perpendicular_midpoint(z1, z2, s1, s2)
    sa, sb = sigma
    if method == "wls":
        A, B = _stack(z1, z2, s1, s2, "unit_normal")
        w = np.empty((len(p), 4))
        for k, s in enumerate((s1, s2)):
            d = p - s
            rho = np.hypot(d[:, 0], d[:, 1])
            w[:, 2 * k] = 1.0 / (rho * sa)
            w[:, 2 * k + 1] = 1.0 / (np.sqrt(rho**2 + d[:, 2] ** 2) * sb)
        return _solve_normal(A * w[..., None], B * w)
    if method == "ml":
        scale = np.array([sa, sb, sa, sb])
        for _ in range(iterations):
            J = np.concatenate([angle_jacobian(p, s1), angle_jacobian(p, s2)], 1)
            r = angle_residuals(p, z1, z2, s1, s2)
            p = p + _solve_normal(J / scale[:, None], r / scale)
        return p
    return p


def common_perpendicular_midpoint(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray,
                                  s2: np.ndarray) -> np.ndarray:
    """Midpoint of the common perpendicular of two LOS, (K, 3) m: the unit-normal LS solution.

    Lines ``s1 + t u``, ``s2 + v w``, ``d = s1 - s2``, ``c = u.w``:
    ``t = (c w.d - u.d) / (1 - c^2)``, ``v = (w.d - c u.d) / (1 - c^2)``."""
    def direction(z):
        a, b = z[:, 0], z[:, 1]
        return np.stack([np.cos(b) * np.cos(a), np.cos(b) * np.sin(a), np.sin(b)], -1)

    u, w = direction(np.atleast_2d(z1)), direction(np.atleast_2d(z2))
    d = s1 - s2
    b = np.sum(u * w, -1)
    du, dw = u @ d, w @ d
    den = np.maximum(1.0 - b**2, 1e-15)  # parallel lines have no unique closest points
    t = (b * dw - du) / den
    v = (dw - b * du) / den
    return 0.5 * ((s1 + t[:, None] * u) + (s2 + v[:, None] * w))

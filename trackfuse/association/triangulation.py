"""Triangulation of a 3-D point from one azimuth/elevation line of sight (LOS) per sensor.

Each LOS (sensor at ``p_s``, azimuth ``a``, elevation ``b``, rad) gives two linear equations
``A_s p = B_s`` in the position ``p`` (m); paper 002 (eq. 4-7) solves the stacked system by
least squares, ``p_hat = (A'A)^-1 A'B``. Forms (:data:`METHODS`): ``paper`` (its elimination
rows, corrected; W002-8), ``unit_normal`` (default: the LOS's unit normals, the midpoint of
the common perpendicular), ``wls`` (unit normals weighted by ``1/(rho_s sigma_a)`` and
``1/(r_s sigma_b)``) and ``ml`` (Gauss-Newton on the four normalised angle residuals).
Equations: ``docs/papers/passive_assoc.md``, "Triangulation". Vectorized over ``K`` candidate
pairs; :func:`intersect` and :func:`los_residuals` take any ``S' >= 2`` lines of sight
(``docs/papers/sd_assignment.md``).

References: Liu H. et al., Control and Decision 23(4), 2008, eq. 4-8; Bar-Shalom, Li,
Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, ch. 3; Hartley,
Zisserman, *Multiple View Geometry*, 2nd ed., 2003, ch. 12.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from trackfuse.association.passive_scene import los_angles
from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import azel_jacobian

METHODS = ("paper", "unit_normal", "wls", "ml")


def los_rows(z: np.ndarray, s: np.ndarray, form: str = "unit_normal"
             ) -> tuple[np.ndarray, np.ndarray]:
    """The two linear equations ``A p = B`` that one LOS puts on the target position.

    Parameters: ``z`` (K, 2) azimuth and elevation, rad. ``s`` (3,) sensor position, m. ``form``
    ``"paper"`` (corrected elimination rows) or ``"unit_normal"``.
    Returns ``A`` (K, 2, 3), B : (K, 2) in m."""
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
    """Batched least squares ``(A'A)^-1 A'B`` for A (K, r, 3), B (K, r) -> (K, 3).

    The 3 x 3 normal equations are solved by Cramer's rule (inverse = adjugate / det, the
    adjugate rows being cross products of the columns), which vectorizes far better than
    ``numpy.linalg.solve`` on many tiny systems."""
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
    """Unweighted LS solution ``(A'A)^-1 A'B`` of the stacked 4 x 3 system (paper eq. 4-7).

    z1, z2 : (K, 2) rad; s1, s2 : (3,) m; form as in :func:`los_rows`. Returns (K, 3) m."""
    return _solve_normal(*_stack(np.atleast_2d(z1), np.atleast_2d(z2), s1, s2, form))


def intersect(z: Sequence[np.ndarray], sensors: np.ndarray) -> np.ndarray:
    """Least-squares intersection of ``S' >= 2`` lines of sight per candidate.

    The unit-normal rows of every LOS are stacked (``2 S'`` x 3) and solved by
    ``(A'A)^-1 A'B``; with two LOS this is :func:`common_perpendicular_midpoint`.
    z : S' arrays (K, 2) of azimuth/elevation, rad; sensors : (S', 3) m. Returns (K, 3) m."""
    rows = [los_rows(np.atleast_2d(zs), s) for zs, s in zip(z, sensors, strict=True)]
    return _solve_normal(np.concatenate([A for A, _ in rows], 1),
                         np.concatenate([B for _, B in rows], 1))


def los_residuals(p: np.ndarray, z: Sequence[np.ndarray], sensors: np.ndarray) -> np.ndarray:
    """Measured minus predicted angles of ``S'`` sensors, azimuths wrapped: (K, 2 S') rad,
    columns ``[a_1, b_1, a_2, b_2, ...]`` for p (K, 3) m and z: S' arrays (K, 2) rad."""
    r = np.concatenate([zs - los_angles(p, s) for zs, s in zip(z, sensors, strict=True)], 1)
    r[:, 0::2] = wrap(r[:, 0::2])
    return r


def angle_jacobian(p: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Jacobian of ``[az, el]`` with respect to ``p``: (K, 2, 3) in rad/m for p (K, 3).

    The position columns of :func:`trackfuse.tracking.sensors.azel_jacobian`."""
    return azel_jacobian(p - s)[..., :3]


def angle_residuals(p: np.ndarray, z1: np.ndarray, z2: np.ndarray, s1: np.ndarray,
                    s2: np.ndarray) -> np.ndarray:
    """Measured minus predicted angles (paper eq. 8), wrapped: (K, 4) rad.

    Columns are ``[a_1, b_1, a_2, b_2]`` residuals for p (K, 3) and z1, z2 (K, 2)."""
    r = np.concatenate([z1 - los_angles(p, s1), z2 - los_angles(p, s2)], axis=1)
    r[:, [0, 2]] = wrap(r[:, [0, 2]])
    return r


def triangulate(z1: np.ndarray, z2: np.ndarray, s1: np.ndarray, s2: np.ndarray,
                method: str = "unit_normal", sigma: tuple[float, float] = (1.0, 1.0),
                iterations: int = 3) -> np.ndarray:
    """Estimate the target position of each candidate pair of lines of sight.

    Parameters: ``z1``, ``z2`` (K, 2) azimuth/elevation measured by sensors 1 and 2, rad. ``s1``,
    ``s2`` (3,) sensor positions, m. ``method`` one of ``"paper"``, ``"unit_normal"``, ``"wls"``,
    ``"ml"`` (module docstring). ``sigma`` ``(sigma_a, sigma_b)`` angle noise standard deviations,
    rad (``wls``, ``ml``). ``iterations`` Gauss-Newton iterations for ``ml``.
    Returns ``p_hat`` (K, 3) positions, m."""
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
    """Midpoint of the common perpendicular of two LOS lines, (K, 3) in m.

    This equals the unit-normal LS solution (the normals of each LOS span the plane
    orthogonal to it, so ``A'A = 2I - u u' - w w'``) and costs no matrix solve.

    For lines ``s1 + t u`` and ``s2 + v w`` with unit directions ``u``, ``w``,
    ``d = s1 - s2``, ``c = u.w``: minimising ``|d + t u - v w|^2`` gives
    ``t = (c w.d - u.d) / (1 - c^2)`` and ``v = (w.d - c u.d) / (1 - c^2)``.
    z1, z2 : (K, 2) rad; s1, s2 : (3,) m."""
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

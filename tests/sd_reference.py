"""Plain references for the S-D assignment (trackfuse/association/sd_assignment.py) and its
tuple costs (trackfuse/association/sd_costs.py).

:func:`brute_force` finds the optimum over every feasible assignment with dummies (small
problems only); :func:`lagrangian` is the Lagrangian relaxation of the module written with
numpy and scipy alone (``numpy.min``/``argmin`` over the tail instead of the compiled
kernel, scipy's ``linear_sum_assignment`` called directly instead of the project's exact
solver), step for step the same algorithm with its sums in the same order (equal
multipliers make exact ties, which must break alike), so the tests pin the two together.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
from scipy.optimize import linear_sum_assignment

from trackfuse.association.triangulation import angle_jacobian, intersect, los_residuals


def brute_force(cost: np.ndarray) -> tuple[float, list[tuple[int, ...]]]:
    """The minimum summed cost over all feasible assignments, and one optimal set of tuples
    (those with two or more real indices).

    Every feasible assignment is reached: the first measurement not yet used (in sensor,
    then index order) goes into each possible tuple in turn. The best completion of a set of
    used measurements is memoised (it does not depend on how they were used)."""
    cost = np.asarray(cost, dtype=float)
    sizes = [n - 1 for n in cost.shape]

    @functools.cache
    def best(used: tuple[int, ...]) -> tuple[float, tuple[tuple[int, ...], ...]]:
        free = [(s, i) for s, n in enumerate(sizes) for i in range(1, n + 1)
                if not used[s] >> i & 1]
        if not free:
            return 0.0, ()
        s0, i0 = free[0]
        options = [[i0] if s == s0 else
                   [0] + [i for i in range(1, n + 1) if not used[s] >> i & 1]
                   for s, n in enumerate(sizes)]
        found = (np.inf, ())
        for t in itertools.product(*options):
            after = tuple(m | (1 << i if i else 0) for m, i in zip(used, t, strict=True))
            rest, chosen = best(after)
            multi = sum(i > 0 for i in t) >= 2
            value = rest + (min(cost[t], 0.0) if multi else 0.0)
            if value < found[0]:
                found = (value, ((t,) if multi else ()) + chosen)
        return found

    value, chosen = best((0,) * len(sizes))
    return value, list(chosen)


def _dummy_matching(low: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact 2-D assignment with dummies: ``low`` (R+1, n+1), last row the dummy row,
    column 0 the dummy column. scipy's ``linear_sum_assignment`` maximises the clipped pair
    gains and the pairs of gain <= 0 are dropped (the clipped form, which breaks the ties
    that equal multipliers make as the project's solver does). Returns the column of each
    real row (0 = dummy) and the real columns left to the dummy row."""
    r, n = low.shape[0] - 1, low.shape[1] - 1
    gain = low[:r, :1] + low[r:, 1:] - low[:r, 1:]
    rows, cols = linear_sum_assignment(np.maximum(gain, 0.0), maximize=True)
    keep = gain[rows, cols] > 0.0
    column = np.zeros(r, np.int64)
    column[rows[keep]] = cols[keep] + 1
    alone = np.setdiff1d(np.arange(1, n + 1), column[column > 0])
    return column, alone


def _tail_sum(u: list[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
    total = np.zeros(shape)
    for k, m in enumerate(u):
        total = total + m.reshape([-1 if j == k else 1 for j in range(len(shape))])
    return total


def lagrangian(cost: np.ndarray, max_gap: float = 0.01, max_iter: int = 100,
               patience: int = 5) -> tuple[float, float, int, np.ndarray]:
    """The module's Lagrangian relaxation in plain numpy/scipy: (primal, dual, iterations,
    tuples with two or more real indices, sorted)."""
    cost = np.minimum(np.asarray(cost, dtype=float), 0.0)
    shape, n_sensors = cost.shape, cost.ndim
    u = [np.zeros(n) for n in shape[2:]]
    best_primal, best_dual, best, theta, stale, it = np.inf, -np.inf, None, 2.0, 0, 0
    while it < max_iter:
        it += 1
        reduced = cost - _tail_sum(u, shape[2:])
        flat = reduced.reshape(shape[0], shape[1], -1)
        low, arg = flat.min(axis=2), flat.argmin(axis=2)
        column, alone = _dummy_matching(np.concatenate([low[1:], low[:1]]))
        heads = [(i + 1, j) for i, j in enumerate(column)] + [(0, j) for j in alone]
        free = [t for t in range(1, flat.shape[2]) if flat[0, 0, t] < 0.0]
        # sums in the module's order: equal multipliers make exact ties, broken alike
        dual = float(np.array([low[h] for h in heads]).sum())
        dual += float(np.array([flat[0, 0, t] for t in free]).sum())
        dual += float(sum(m[1:].sum() for m in u))
        tails = [arg[h] for h in heads] + free
        relaxed = [tuple(h) + np.unravel_index(t, shape[2:]) for h, t in
                   zip(heads + [(0, 0)] * len(free), tails, strict=True)]
        g = [1.0 - np.bincount([t[s] for t in relaxed], minlength=shape[s])[1:]
             for s in range(2, n_sensors)]
        if dual > best_dual:
            best_dual, stale = dual, 0
        else:
            stale += 1
        rows = [h for h in heads if any(h)]
        for k in range(2, n_sensors):
            tail_u = _tail_sum(u[k - 1:], shape[k + 1:])
            ext = rows + [(0,) * k]
            low = np.array([(cost[r] - tail_u).reshape(shape[k], -1).min(axis=1) for r in ext])
            column, alone = _dummy_matching(low)
            rows = [r + (int(c),) for r, c in zip(ext[:-1], column, strict=True)] + \
                [(0,) * k + (int(j),) for j in alone]
            rows = [r for r in rows if any(r)]
        primal = float(np.array([cost[r] for r in rows]).sum())
        if primal < best_primal:
            best_primal, best = primal, rows
        norm2 = sum(float(x @ x) for x in g)
        if norm2 == 0.0 or (best_primal - best_dual) / max(abs(best_primal), 1.0) <= max_gap:
            break
        if stale >= patience:
            theta, stale = theta / 2.0, 0
        step = theta * (best_primal - dual) / norm2
        for m, x in zip(u, g, strict=True):
            m[1:] += step * x
    declared = sorted(r for r in best if sum(i > 0 for i in r) >= 2 and cost[r] < 0.0)
    return float(best_primal), float(min(best_dual, best_primal)), it, np.array(declared)


def subset_fit(z: list[np.ndarray], sensors: np.ndarray, sigma_a: float, sigma_b: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """``sd_costs.subset_fit`` vectorized with numpy: every combination triangulated at once
    (:func:`~trackfuse.association.triangulation.intersect`); the chi-square (``+inf``
    where undefined) and the log-determinant of the position information."""
    shape = tuple(len(zs) for zs in z)
    grids = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    picked = [zs[g.ravel()] for zs, g in zip(z, grids, strict=True)]
    with np.errstate(divide="ignore", invalid="ignore"):
        p = intersect(picked, sensors)
        r = los_residuals(p, picked, sensors) / np.tile([sigma_a, sigma_b], len(z))
        chi2 = np.einsum("ki,ki->k", r, r)
        scale = np.array([1.0 / sigma_a, 1.0 / sigma_b])[:, None]
        info = sum(np.einsum("kri,krj->kij", h, h) for h in
                   (angle_jacobian(p, s) * scale for s in sensors))
        sign, logdet = np.linalg.slogdet(info)
    logdet = np.where(sign > 0, logdet, -np.inf)
    return np.where(np.isfinite(chi2), chi2, np.inf).reshape(shape), logdet.reshape(shape)

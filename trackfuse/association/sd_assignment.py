"""S-dimensional assignment with a dummy index, by Lagrangian relaxation (S >= 2 sensors).

Index 0 of each sensor is the dummy; tuple costs ``c`` (nats) come from
:func:`trackfuse.association.sd_costs.tuple_costs`, clipped to ``min(c, 0)`` (a tuple at 0
is reported as singletons). Sensors 3..S are relaxed with multipliers; the dual is a 2-D
assignment, recovery gives the primal, and Polyak subgradient steps halve ``theta`` after
:data:`PATIENCE` stale iterations. Equations: ``docs/papers/sd_assignment.md``, "Lagrangian
relaxation". The tail minimum runs in numba; ``tests/sd_reference.py`` is its numpy oracle.

References: Deb S. et al., IEEE Trans. AES 33(2), 1997, 523-538; Poore A. B., Rijavec N.,
SIAM J. Optimization 3(3), 1993, 544-563; Held M., Wolfe P., Crowder H. P., Math.
Programming 6, 1974, 62-88."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from trackfuse.association.assignment import solve_exact

JIT = {"cache": True, "nogil": True, "error_model": "numpy"}
#: Iterations without a better dual bound after which the step factor theta is halved.
PATIENCE = 5
#: Initial step factor of the subgradient step.
THETA0 = 2.0
#: Floor (nats) of the scale in the relative duality gap.
GAP_SCALE_FLOOR = 1.0


@dataclass(frozen=True)
class SDResult:
    """A feasible S-D assignment: ``tuples`` (K, S) (0 = dummy), ``primal`` (upper bound, nats),
    ``dual`` (lower bound, nats), ``gap`` ``(primal - dual) / max(|primal|, 1)``, ``iterations``."""

    tuples: np.ndarray
    primal: float
    dual: float
    gap: float
    iterations: int

    @property
    def declared(self) -> np.ndarray:
        """(D, S) the tuples with at least two real indices (the declared targets)."""
        return self.tuples[(self.tuples > 0).sum(axis=1) >= 2]


def checked_costs(cost: np.ndarray) -> np.ndarray:
    """``min(cost, 0)``, C-contiguous; ValueError for S < 2, NaN, or a nonzero cost on a tuple
    with at most one real index."""
    cost = np.asarray(cost, dtype=float)
    if cost.ndim < 2:
        raise ValueError(f"an S-D cost tensor needs S >= 2 dimensions, got {cost.ndim}")
    if np.isnan(cost).any():
        raise ValueError("the cost tensor holds NaN")
    grids = np.indices(cost.shape, sparse=True)
    reals = sum((g > 0).astype(int) for g in grids)
    if np.any(cost[reals <= 1] != 0.0):
        raise ValueError("a tuple with at most one real index must cost 0 (its measurements "
                         "declared false)")
    return np.ascontiguousarray(np.minimum(cost, 0.0))


@njit(**JIT)
def reduce_tail(cost, utail):
    """Min over ``t`` of ``cost[a, b, t] - utail[t]`` (A, B) and its first argmin (A, B)."""
    a, b, t = cost.shape
    low = np.empty((a, b))
    arg = np.empty((a, b), np.int64)
    for i in range(a):
        for j in range(b):
            best, k_best = cost[i, j, 0] - utail[0], 0
            for k in range(1, t):
                value = cost[i, j, k] - utail[k]
                if value < best:
                    best, k_best = value, k
            low[i, j], arg[i, j] = best, k_best
    return low, arg


def tail_sum(multipliers: list[np.ndarray]) -> np.ndarray:
    """(T,) ``sum_s u_s(i_s)`` over the flattened tail ``(i_s)`` (C order); ``[0]`` if none."""
    total = np.zeros(1)
    for u in multipliers:
        total = np.add.outer(total, u).ravel()
    return total


def _dummy_matching(low: np.ndarray) -> tuple[np.ndarray, float]:
    """Exact 2-D assignment on ``low`` (R+1, n+1), dummies last row and column 0: pairs and cost."""
    r = low.shape[0] - 1
    gain = low[:r, :1] + low[r:, 1:] - low[:r, 1:]
    match = solve_exact(gain)
    column = np.where(match.partner1 >= 0, match.partner1 + 1, 0)
    alone = np.flatnonzero(match.partner2 < 0) + 1
    pairs = np.concatenate([np.stack([np.arange(r), column], 1),
                            np.stack([np.full(len(alone), r), alone], 1)]).astype(np.int64)
    value = float(low[pairs[:, 0], pairs[:, 1]].sum())
    return pairs, value


@dataclass(frozen=True)
class Relaxed:
    """Relaxed problem at ``u``: ``dual`` (a lower bound), ``tuples`` (K, S), subgradient ``g``."""

    dual: float
    tuples: np.ndarray
    g: list[np.ndarray]


def relax(cost: np.ndarray, u: list[np.ndarray]) -> Relaxed:
    """Relaxed problem at multipliers ``u`` ((n_s + 1,) per sensor 3..S, ``u[k][0] = 0``)."""
    shape = cost.shape
    utail = tail_sum(u)
    cube = cost.reshape(shape[0], shape[1], -1)
    low, arg = reduce_tail(cube, utail)
    # 2-D: rows i_1 = 1..n_1 then the dummy row; columns i_2 = 0..n_2
    table = np.concatenate([low[1:], low[:1]])
    pairs, value = _dummy_matching(table)
    i1 = np.where(pairs[:, 0] < shape[0] - 1, pairs[:, 0] + 1, 0)
    i2 = pairs[:, 1]
    tails = arg[i1, i2]
    free_cost = cube[0, 0, 1:] - utail[1:]
    free = np.flatnonzero(free_cost < 0.0) + 1
    value += float(free_cost[free - 1].sum())
    heads = np.concatenate([np.stack([i1, i2], 1), np.zeros((len(free), 2), np.int64)])
    tail_index = np.concatenate([tails, free])
    tail_idx = np.stack(np.unravel_index(tail_index, shape[2:]), 1) if len(shape) > 2 \
        else np.zeros((len(tail_index), 0), np.int64)
    tuples = np.concatenate([heads, tail_idx], 1)
    g = [1.0 - np.bincount(tuples[:, s], minlength=shape[s])[1:] for s in range(2, len(shape))]
    dual = value + float(sum(m[1:].sum() for m in u))
    return Relaxed(dual=dual, tuples=tuples, g=g)


def recover(cost: np.ndarray, heads: np.ndarray, u: list[np.ndarray]) -> np.ndarray:
    """Feasible tuples (K, S) from 2-D ``heads`` (R, 2), adding sensors 3..S by 2-D assignment."""
    shape = cost.shape
    rows = heads[(heads > 0).any(axis=1)]
    for k in range(2, len(shape)):
        utail = tail_sum(u[k - 1:])
        ext = np.concatenate([rows, np.zeros((1, k), np.int64)])
        sub = cost[tuple(ext.T)].reshape(len(ext), shape[k], -1)
        low, _ = reduce_tail(np.ascontiguousarray(sub), utail)
        pairs, _ = _dummy_matching(low)
        rows = np.concatenate([ext[pairs[:, 0]], pairs[:, 1:]], 1)
        rows = rows[(rows > 0).any(axis=1)]
    return rows


def split_nonnegative(cost: np.ndarray, tuples: np.ndarray) -> np.ndarray:
    """``tuples`` with multi-index tuples of clipped cost 0 split into singletons."""
    value = cost[tuple(tuples.T)]
    keep = ((tuples > 0).sum(axis=1) < 2) | (value < 0.0)
    singles = [np.eye(tuples.shape[1], dtype=np.int64)[s] * i
               for t in tuples[~keep] for s, i in enumerate(t) if i > 0]
    return np.concatenate([tuples[keep], np.array(singles, np.int64).reshape(-1,
                                                                               tuples.shape[1])])


def relative_gap(primal: float, dual: float) -> float:
    """``(primal - dual) / max(|primal|, 1)``, the relative duality gap."""
    return (primal - dual) / max(abs(primal), GAP_SCALE_FLOOR)


def solve_sd(cost: np.ndarray, max_gap: float = 0.01, max_iter: int = 100) -> SDResult:
    """Minimum-cost feasible S-D assignment of ``cost`` (n_1 + 1, ..., n_S + 1) nats, stopping at
    relative gap ``max_gap``, a feasible relaxed solution, or ``max_iter`` iterations."""
    cost = checked_costs(cost)
    u = [np.zeros(n) for n in cost.shape[2:]]
    best_primal, best_dual, best = np.inf, -np.inf, None
    theta, stale, it = THETA0, 0, 0
    while it < max_iter:
        it += 1
        relaxed = relax(cost, u)
        if relaxed.dual > best_dual:
            best_dual, stale = relaxed.dual, 0
        else:
            stale += 1
        tuples = recover(cost, relaxed.tuples[:, :2], u)
        primal = float(cost[tuple(tuples.T)].sum())
        if primal < best_primal:
            best_primal, best = primal, tuples
        norm2 = float(sum(np.dot(g, g) for g in relaxed.g))
        if norm2 == 0.0 or relative_gap(best_primal, best_dual) <= max_gap:
            break
        if stale >= PATIENCE:
            theta, stale = theta / 2.0, 0
        step = theta * (best_primal - relaxed.dual) / norm2
        for m, g in zip(u, relaxed.g, strict=True):
            m[1:] += step * g
    if best_dual > best_primal:  # a lower bound: above the primal only by rounding
        if best_dual - best_primal > 1e-9 * max(abs(best_primal), GAP_SCALE_FLOOR):
            raise RuntimeError(f"dual bound {best_dual!r} above the primal {best_primal!r}")
        best_dual = best_primal
    return SDResult(tuples=split_nonnegative(cost, best), primal=best_primal,
                    dual=best_dual, gap=relative_gap(best_primal, best_dual), iterations=it)


def solve_sd_exact(cost: np.ndarray) -> SDResult:
    """The exact optimum by integer linear programming (``scipy.optimize.milp``, HiGHS).

    Variables are the tuples of two or more real indices with negative (clipped) cost, each
    real index in at most one of them (the rest are singletons, cost 0). Exponential in the
    worst case; the reference for small and sparse problems. ``dual = primal``, ``gap = 0``."""
    from scipy.optimize import LinearConstraint, milp  # on use: scipy.optimize is slow to load
    from scipy.sparse import csr_array

    cost = checked_costs(cost)
    candidates = np.argwhere(cost < 0.0)
    sizes = np.array(cost.shape) - 1
    chosen = candidates[:0]
    if len(candidates):
        offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]) - 1
        cols = np.repeat(np.arange(len(candidates)), cost.ndim)
        rows = (candidates + offsets).ravel()
        real = candidates.ravel() > 0
        a = csr_array((np.ones(real.sum()), (rows[real], cols[real])),
                      shape=(int(sizes.sum()), len(candidates)))
        found = milp(cost[tuple(candidates.T)], integrality=np.ones(len(candidates)),
                     bounds=(0, 1), constraints=LinearConstraint(a, -np.inf, 1.0))
        if not found.success:
            raise RuntimeError(f"the integer program failed: {found.message}")
        chosen = candidates[found.x > 0.5]
    tuples = _with_singletons(chosen, sizes)
    primal = float(cost[tuple(tuples.T)].sum())
    return SDResult(tuples=tuples, primal=primal, dual=primal, gap=0.0, iterations=0)


def _with_singletons(chosen: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """``chosen`` (D, S) plus a singleton for every real index it does not hold."""
    singles = []
    for s, n in enumerate(sizes):
        used = np.zeros(n + 1, bool)
        used[chosen[:, s]] = True
        for i in np.flatnonzero(~used[1:]) + 1:
            row = np.zeros(len(sizes), np.int64)
            row[s] = i
            singles.append(row)
    return np.concatenate([chosen.astype(np.int64),
                           np.array(singles, np.int64).reshape(-1, len(sizes))])

"""The partheno-genetic algorithm's search (:mod:`trackfuse.association.pga`), compiled.

Setup, draws and collection are :mod:`.pga`'s; the genetic operations run in numba from
checkpoint to checkpoint. The oracle ``tests/pga_reference.py`` does the same floating-point
operations in the same order (pinned exactly by ``tests/test_pga_kernel.py``)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
from numba import njit

from trackfuse.association.assignment import PairWeights
from trackfuse.association.pga import (
    CHECKPOINTS,
    PGAResult,
    collect,
    draw_blocks,
    initial_solution,
    orient,
    schedule,
)

JIT = {"cache": True, "nogil": True, "error_model": "numpy"}
#: Callees run only from compiled code: no Python or C entry point to compile for them.
INNER = {**JIT, "no_cpython_wrapper": True, "no_cfunc_wrapper": True}
# Columns of a row of draws (the fields of pga.Draws, in stream order).
FIRST, SECOND, MUTATE, REPAIR, PICK, PLACE, ACCEPT_CROSSOVER, ACCEPT_MUTATION = range(8)
# Constant arguments as int64 and bool values: a literal in a call would compile one more
# copy of the called function per constant (about a second each, on the first run).
_ZERO, _CROSSOVER_COLUMNS = np.int64(0), np.int64(2)
_EMPTY, _PAIRED = np.bool_(False), np.bool_(True)
# Entries of the float state carried from one compiled segment to the next.
J_CUR, J_BEST, TEMPERATURE = range(3)


def pga(weights: PairWeights, rng: np.random.Generator, ops: int = 1000,
        checkpoints: Sequence[int] = CHECKPOINTS, p_m: float = 0.2, init: str = "random_B",
        roulette: str = "worse", second: str = "roulette", repair_moves: bool = False,
        staged: bool = False, evict: bool = False, accept: str = "monotone", t0: float = 1.0,
        t1: float = 0.01) -> PGAResult:
    """Run the (improved) PGA on one problem with its own stream ``rng``: :class:`PGAResult`.

    ``ops`` operations, best recorded at ``checkpoints`` (``ops`` always added); the other
    options are the variants of ``docs/papers/passive_assoc.md``, "Partheno-genetic algorithm"
    (``t0``, ``t1`` in nats)."""
    start = time.perf_counter()
    w, rank, transpose = orient(weights, roulette)
    marks, anneal, cool = schedule(ops, checkpoints, accept, second, t0, t1)
    m1, m2 = rank.shape[0] - 1, rank.shape[1]
    columns = np.arange(m2)

    def objective(col_row: list[int]) -> float:  # the oracle's sum, of Python floats
        return sum(w[col_row, columns].tolist())

    cur = initial_solution(m1, m2, init, rng)
    J = objective(cur)
    cur = np.array(cur, dtype=np.int64)
    best, q = cur.copy(), rank[cur, columns]
    state = np.array([J, J, t0])
    saved: dict[int, tuple[list[int], float]] = {}  # checkpoint -> (best, elapsed s)
    if 0 in marks:
        saved[0] = (best.tolist(), time.perf_counter() - start)
    done = 0
    for block in draw_blocks(rng, ops):
        lo = 0
        while lo < len(block):
            hi = min(len(block), min(c for c in marks if c > done) - done + lo)
            _search(block[lo:hi], w, rank, cur, best, q, state, float(p_m),
                    second == "roulette", bool(repair_moves), bool(staged), bool(evict), anneal,
                    cool)
            done, lo = done + hi - lo, hi
            if done in marks:
                saved[done] = (best.tolist(), time.perf_counter() - start)
    return collect(saved, objective, transpose, weights.a.shape[0])


@njit(**JIT)
def _search(draws, w, rank, cur, best, q, state, p_m, roulette_second, repair_moves, staged,
            evict, anneal, cool):
    """Run the operations of ``draws`` (n, 8) from ``cur`` (m2,) in place (oracle: ``operate``)."""
    m1, m2 = w.shape[0] - 1, w.shape[1]
    J, J_best, T = state[J_CUR], state[J_BEST], state[TEMPERATURE]
    child, cum, touched = cur.copy(), np.cumsum(q), np.empty(3, np.int64)
    scratch, seen = np.empty(max(m1, m2) + 1, np.int64), np.empty(m1 + 1, np.bool_)
    n_paired = _ZERO
    for j in range(m2):
        n_paired += cur[j] != 0
    stale = False
    for t in range(draws.shape[0]):
        d = draws[t]
        dJ, child_paired, n_touched = 0.0, n_paired, 0
        if m2 >= 2:
            if stale:
                _cumulative_sum(q, cum)
                stale = False
            j1, j2 = _columns(cum, q, d[FIRST], d[SECOND], roulette_second)
            r1, r2 = child[j1], child[j2]
            child[j1], child[j2] = r2, r1
            dJ += w[r2, j1] + w[r1, j2] - w[r1, j1] - w[r2, j2]
            touched[0], touched[1], n_touched = j1, j2, 2
            if staged:
                if _accepted(dJ, d[ACCEPT_CROSSOVER], anneal, T):
                    J, J_best, n_paired, stale = _commit(J + dJ, J_best, child_paired, cur,
                                                         child, best, q, rank, touched,
                                                         _CROSSOVER_COLUMNS)
                else:
                    _revert(cur, child, touched, _CROSSOVER_COLUMNS)
                dJ, child_paired, n_touched = 0.0, n_paired, 0
        if m1 > 0 and d[MUTATE] < p_m:
            gain, c, child_paired = _mutate(child, w, d, child_paired, repair_moves, evict,
                                            scratch, seen)
            if c >= 0:
                dJ += gain
                touched[n_touched] = c
                n_touched += 1
        if n_touched:
            if _accepted(dJ, d[ACCEPT_MUTATION], anneal, T):
                J, J_best, n_paired, stale = _commit(J + dJ, J_best, child_paired, cur, child,
                                                     best, q, rank, touched, n_touched)
            else:
                _revert(cur, child, touched, n_touched)
        T *= cool
    state[J_CUR], state[J_BEST], state[TEMPERATURE] = J, J_best, T


@njit(**INNER)
def _accepted(dJ, u, anneal, T):
    """Monotone acceptance, or Metropolis at temperature ``T``."""
    return dJ >= 0.0 or (anneal and u < math.exp(dJ / T))


@njit(**INNER)
def _commit(J, J_best, child_paired, cur, child, best, q, rank, touched, n_touched):
    """Accept the offspring, keep it as ``best`` if better: ``J``, best ``J``, pairs, stale flag."""
    for k in range(n_touched):
        j = touched[k]
        cur[j] = child[j]
        q[j] = rank[cur[j], j]
    if J_best < J:
        J_best = J
        for j in range(cur.shape[0]):
            best[j] = cur[j]
    return J, J_best, child_paired, True


@njit(**INNER)
def _cumulative_sum(q, out):
    """``out = np.cumsum(q)`` element by element (cheaper to compile)."""
    acc = 0
    for j in range(q.shape[0]):
        acc += q[j]
        out[j] = acc


@njit(**INNER)
def _revert(cur, child, touched, n_touched):
    """Reject the offspring: restore its touched columns from ``cur``."""
    for k in range(n_touched):
        j = touched[k]
        child[j] = cur[j]


@njit(**INNER)
def _bisect_right(cum, x, lo, hi, shift):
    """First ``i`` in ``lo..hi-1`` with ``cum[i] - shift > x``, else ``hi`` (``bisect_right``)."""
    while lo < hi:
        mid = (lo + hi) // 2
        if x < cum[mid] - shift:
            hi = mid
        else:
            lo = mid + 1
    return lo


@njit(**INNER)
def _columns(cum, q, u1, u2, roulette_second):
    """The crossover's two columns (``_Search._crossover`` of the oracle)."""
    m2 = cum.shape[0]
    j1 = min(_bisect_right(cum, u1 * cum[m2 - 1], _ZERO, m2, _ZERO), m2 - 1)
    if roulette_second:
        x, q1 = u2 * (cum[m2 - 1] - q[j1]), q[j1]
        j2 = _bisect_right(cum, x, _ZERO, j1, _ZERO)
        if j2 == j1:
            j2 = _bisect_right(cum, x, j1 + 1, m2, q1)
            if j2 == m2:
                j2 = m2 - 1 if j1 < m2 - 1 else m2 - 2
    else:
        j2 = int(u2 * (m2 - 1))
        j2 += j2 >= j1
    return j1, j2


@njit(**INNER)
def _mutate(child, w, d, child_paired, repair_moves, evict, scratch, seen):
    """Re-pair or unpair in place (oracle's ``_mutate``): gain, touched column (-1: none), pairs."""
    m1, m2 = w.shape[0] - 1, w.shape[1]
    if repair_moves and d[REPAIR] < 0.5 and child_paired < m1:
        seen[:] = False
        for j in range(m2):
            seen[child[j]] = True
        n_free = 0
        for r in range(1, m1 + 1):
            if not seen[r]:
                scratch[n_free] = r
                n_free += 1
        r = scratch[int(d[PICK] * n_free)]
        if evict and d[PLACE] < 0.5:
            c = int(2.0 * d[PLACE] * m2)
            child_paired += child[c] == 0
            old = child[c]
            child[c] = r
            return w[r, c] - w[old, c], c, child_paired
        n_empty = _columns_where(child, _EMPTY, scratch)
        c = scratch[int((2.0 * d[PLACE] - 1.0 if evict else d[PLACE]) * n_empty)]
        child[c] = r
        return w[r, c], c, child_paired + 1
    if child_paired:
        n = _columns_where(child, _PAIRED, scratch)
        c = scratch[int(d[PICK] * n)]
        r = child[c]
        child[c] = 0
        return -w[r, c], c, child_paired - 1
    return 0.0, -1, child_paired


@njit(**INNER)
def _columns_where(child, paired, out):
    """Write the columns holding a real row (``paired``) or none into ``out``; return how many."""
    n = 0
    for j in range(child.shape[0]):
        if (child[j] != 0) == paired:
            out[n] = j
            n += 1
    return n

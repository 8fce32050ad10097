"""Improved partheno-genetic algorithm (PGA) of paper 002 for the two-sensor assignment.

Representation (docs/papers/passive_assoc.md, "Partheno-genetic algorithm"). The solution
is the 0/1 matrix ``X`` of size (m1+1) x (m2+1) with
dummy row and column 0; the smaller measurement set is put on the rows (m1 <= m2, the
problem is transposed if needed and mapped back). It is stored as ``col_row``, a list of
length m2 with ``col_row[j]`` in ``{0 (dummy), 1..m1}``, each real row at most once; a row
absent from ``col_row`` sits in dummy column 0. The objective is the sum of pair gains
``J = sum_j w[col_row[j]][j]`` with ``w[0][j] = 0`` (see
:mod:`trackfuse.association.assignment`), so every move changes ``J`` by the gains of the
two or three columns it touches and is evaluated in O(1).

Operators, one *genetic operation* = crossover, then mutation with probability ``p_m``,
then evaluation:

* crossover (paper eq. 21-23): swap the contents of two distinct real columns. Column ``j``
  is drawn by roulette with weight ``num(j)``, the descending rank (1 = largest) of the
  selected entry ``a_{i*(j), j}`` among the m1+1 entries ``a_0j, ..., a_m1j`` of its column
  (``roulette="worse"``: badly placed columns are swapped more often; the paper's text is
  self-contradictory, ``"better"`` gives weight ``m1 + 2 - num(j)``). The second column is
  drawn by roulette over the remaining columns or uniformly (``second``).
* mutation (paper sec. 3.2, one gene, k = 1): unpair a random paired row ``r`` from its
  column ``c`` (``x_rc = 0``, ``x_r0 = x_0c = 1``).
* re-pair (our improvement, ``repair=True``): with probability 1/2 the mutation instead
  pairs a random unpaired row with a random empty column. Without it no operator maps a
  solution with unpaired rows back towards more pairs, so under monotone acceptance the
  search cannot undo an unpairing and the chain is not irreducible (W002-2 in
  docs/papers/passive_assoc.md).
* evicting re-pair (ours, ``evict=True``): half of the re-pair moves put the unpaired row
  into any column, sending its occupant (if any) to the dummy column (:func:`exchange`).
  This is the single step from "row r' paired with c, row r unpaired" to the reverse, which
  otherwise needs an unpairing followed by a re-pairing and is blocked under monotone
  acceptance whenever the intermediate state is worse (the typical remaining gap).

Staged evaluation (ours, ``staged=True``): the crossover offspring and the mutation
offspring are evaluated and accepted one after the other within the operation. In the
paper-like joint form a useful mutation is vetoed whenever the crossover drawn with it
lowers ``J``; when only one column is empty every swap breaks a pair, so the last missing
pair can then never be made (each evaluation is still O(1), at most two per operation).

Acceptance: ``"monotone"`` (paper-like, reconstruction of the lost flow chart: accept the
offspring iff ``J_new >= J``) or ``"anneal"`` (Metropolis acceptance
``exp(dJ / T_t)`` with geometric cooling from ``t0`` to ``t1``, the best solution kept).

The best solution so far is recorded at each checkpoint of the operation count, which is the
x-axis of the paper's Fig. 2. The budget ``ops`` itself is always a checkpoint, so a run is
scored at the operation count it was given, whatever checkpoint list accompanies it.

References
----------
Liu H., Dou L., Xin B., Dong L., Control and Decision 23(4), 2008, sec. 3.
Li M. J., Tong T. S., "A partheno-genetic algorithm and analysis on its global convergence",
Acta Automatica Sinica 25(1), 1999.
Rudolph G., "Convergence analysis of canonical genetic algorithms", IEEE Trans. Neural
Networks 5(1), 1994 (elitism and irreducibility).
Kirkpatrick S., Gelatt C. D., Vecchi M. P., "Optimization by simulated annealing", Science
220, 1983.
"""

from __future__ import annotations

import math
import time
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import accumulate

import numpy as np

from trackfuse.association.assignment import PairWeights

CHECKPOINTS = (0, 10, 20, 50, 100, 200, 500, 1000)
_BLOCK = 4096  # operations per block of pre-drawn uniforms


@dataclass(frozen=True)
class PGAResult:
    """Best solutions of one PGA run at each checkpoint.

    Attributes
    ----------
    checkpoints : (C,) operation counts.
    partner1 : (C, m1) sensor-2 partner of each sensor-1 measurement, -1 for the dummy.
    objective : (C,) sum of pair gains of the best solution.
    elapsed_s : (C,) wall time from the start of the run, s.
    """

    checkpoints: np.ndarray
    partner1: np.ndarray
    objective: np.ndarray
    elapsed_s: np.ndarray


def is_feasible(col_row: Sequence[int], m1: int) -> bool:
    """True iff every entry is in 0..m1 and no real row appears twice."""
    real = [r for r in col_row if r != 0]
    return all(0 <= r <= m1 for r in col_row) and len(real) == len(set(real))


def swap_columns(col_row: list[int], w: list[list[float]], j1: int, j2: int) -> float:
    """Crossover: swap the contents of columns ``j1`` and ``j2`` in place; return dJ.

    ``w`` is the (m1+1) x m2 gain table with ``w[0][j] = 0``.
    """
    r1, r2 = col_row[j1], col_row[j2]
    col_row[j1], col_row[j2] = r2, r1
    return w[r2][j1] + w[r1][j2] - w[r1][j1] - w[r2][j2]


def unpair(col_row: list[int], w: list[list[float]], c: int) -> float:
    """Mutation: move the row of column ``c`` to the dummy column in place; return dJ."""
    r = col_row[c]
    col_row[c] = 0
    return -w[r][c]


def repair(col_row: list[int], w: list[list[float]], r: int, c: int) -> float:
    """Re-pair: put the unpaired row ``r`` into the empty column ``c`` in place; return dJ."""
    if col_row[c] != 0 or r in col_row:
        raise ValueError("re-pair needs an unpaired row and an empty column")
    col_row[c] = r
    return w[r][c]


def exchange(col_row: list[int], w: list[list[float]], r: int, c: int) -> float:
    """Evicting re-pair: put the unpaired row ``r`` into column ``c`` in place, sending the
    row that held ``c`` (if any) to the dummy column; return dJ."""
    if r in col_row:
        raise ValueError("exchange needs an unpaired row")
    old = col_row[c]
    col_row[c] = r
    return w[r][c] - w[old][c]


def column_ranks(a: np.ndarray, a_0j: np.ndarray) -> np.ndarray:
    """Descending rank (1 = largest) of each entry within its column of ``[a_0j; a]``.

    a : (m1, m2), a_0j : (m2,). Returns (m1+1, m2) ints; ties keep row order.
    """
    full = np.vstack([a_0j[None, :], a])
    order = np.argsort(-full, axis=0, kind="stable")
    ranks = np.empty_like(order)
    np.put_along_axis(ranks, order, np.arange(1, full.shape[0] + 1)[:, None], axis=0)
    return ranks


def pga(weights: PairWeights, rng: np.random.Generator, ops: int = 1000,
        checkpoints: Sequence[int] = CHECKPOINTS, p_m: float = 0.2, init: str = "random_B",
        roulette: str = "worse", second: str = "roulette", repair_moves: bool = False,
        staged: bool = False, evict: bool = False, accept: str = "monotone", t0: float = 1.0,
        t1: float = 0.01) -> PGAResult:
    """Run the (improved) partheno-genetic algorithm on one assignment problem.

    Parameters
    ----------
    weights : the scan's :class:`PairWeights` (m1 x m2, either orientation).
    rng : the algorithm's own random stream.
    ops : number of genetic operations.
    checkpoints : operation counts at which the best solution is recorded; counts above
        ``ops`` are ignored and ``ops`` itself is always added.
    p_m : mutation probability per operation.
    init : ``"random_B"`` (random injection of the rows into distinct columns) or
        ``"standard"`` (row i in column i, paper eq. 31).
    roulette : ``"worse"`` (weight num(j)) or ``"better"`` (weight m1 + 2 - num(j)).
    second : second crossover column by ``"roulette"`` over the rest or ``"uniform"``.
    repair_moves : enable the re-pair move (module docstring).
    evict : half of the re-pair moves pick any column, whose row then goes to the dummy
        column (:func:`exchange`); otherwise re-pair only into empty columns.
    staged : evaluate (and accept or reject) the crossover offspring and the mutation
        offspring separately within one operation, instead of only their combination.
    accept : ``"monotone"`` or ``"anneal"``.
    t0, t1 : initial and final annealing temperatures, in units of J (nats).
    """
    start = time.perf_counter()
    transpose = weights.a.shape[0] > weights.a.shape[1]
    a, a_0j = (weights.a.T, weights.a_i0) if transpose else (weights.a, weights.a_0j)
    gain = weights.gain.T if transpose else weights.gain
    m1, m2 = a.shape
    w = [[0.0] * m2] + gain.tolist()
    rank = column_ranks(a, a_0j).tolist()
    if roulette == "better":
        rank = [[m1 + 2 - v for v in row] for row in rank]
    elif roulette != "worse":
        raise ValueError(f"unknown roulette direction {roulette!r}")
    if accept not in ("monotone", "anneal"):
        raise ValueError(f"unknown acceptance {accept!r}")
    anneal = accept == "anneal"

    cur = [0] * m2
    if init == "random_B":
        for r, j in enumerate(rng.permutation(m2)[:m1].tolist(), start=1):
            cur[j] = r
    elif init == "standard":
        cur[:m1] = range(1, m1 + 1)
    else:
        raise ValueError(f"unknown init {init!r}")
    J = sum(w[r][j] for j, r in enumerate(cur))
    n_paired = m1
    q = [rank[r][j] for j, r in enumerate(cur)]  # roulette weight of each column
    best, J_best = cur.copy(), J

    marks = sorted({int(c) for c in checkpoints if 0 <= c <= ops} | {ops})
    mark_set = set(marks)
    saved: dict[int, tuple[list[int], float]] = {}  # checkpoint -> (best, elapsed s)
    if 0 in mark_set:
        saved[0] = (best.copy(), time.perf_counter() - start)
    cool = (t1 / t0) ** (1.0 / max(ops, 1)) if anneal else 1.0
    T = t0
    roulette_second = second == "roulette"
    if second not in ("roulette", "uniform"):
        raise ValueError(f"unknown second-column rule {second!r}")

    # ``child`` is the offspring under construction and equals ``cur`` outside an operation;
    # moves touch only the columns in ``touched``, so accepting or rejecting an offspring
    # copies those columns one way or the other instead of the whole list.
    child, dJ, child_paired, touched = cur.copy(), 0.0, n_paired, []
    cum = list(accumulate(q))  # cumulative roulette weights, rebuilt after q changes
    stale = False
    for t in range(1, ops + 1):
        if (t - 1) % _BLOCK == 0:  # uniforms in blocks: bounded memory, same stream
            U = rng.random((min(_BLOCK, ops - t + 1), 8)).tolist()
        u = U[(t - 1) % _BLOCK]
        for stage in (0, 1):
            if stage == 0 and m2 >= 2:
                # crossover: roulette column pair, then swap
                if stale:
                    cum, stale = list(accumulate(q)), False
                j1 = min(bisect_right(cum, u[0] * cum[-1]), m2 - 1)
                if roulette_second:
                    # roulette over the columns other than j1 (their running sum skips q[j1])
                    x, q1 = u[1] * (cum[-1] - q[j1]), q[j1]
                    j2 = bisect_right(cum, x, 0, j1)
                    if j2 == j1:
                        j2 = bisect_right(cum, x, j1 + 1, m2, key=lambda c: c - q1)
                        if j2 == m2:
                            j2 = m2 - 1 if j1 < m2 - 1 else m2 - 2
                else:
                    j2 = int(u[1] * (m2 - 1))
                    j2 += j2 >= j1
                dJ += swap_columns(child, w, j1, j2)
                touched += [j1, j2]
            elif stage == 1 and m1 and u[2] < p_m:
                if repair_moves and u[3] < 0.5 and child_paired < m1:
                    free = sorted(set(range(1, m1 + 1)).difference(child))
                    r = free[int(u[4] * len(free))]
                    if evict and u[5] < 0.5:
                        c = int(2.0 * u[5] * m2)
                        child_paired += child[c] == 0
                        dJ += exchange(child, w, r, c)
                    else:
                        empty = [j for j, row in enumerate(child) if row == 0]
                        c = empty[int((2.0 * u[5] - 1.0 if evict else u[5]) * len(empty))]
                        dJ += repair(child, w, r, c)
                        child_paired += 1
                    touched.append(c)
                elif child_paired:
                    paired = [j for j, row in enumerate(child) if row]
                    c = paired[int(u[4] * len(paired))]
                    dJ += unpair(child, w, c)
                    child_paired -= 1
                    touched.append(c)
            if not (staged or stage == 1) or not touched:
                continue
            # evaluation and acceptance of the offspring
            if dJ >= 0.0 or (anneal and u[6 + stage] < math.exp(dJ / T)):
                J, n_paired = J + dJ, child_paired
                for j in touched:
                    cur[j] = child[j]
                    q[j] = rank[cur[j]][j]
                stale = True
                if J_best < J:
                    best, J_best = cur.copy(), J
            else:
                for j in touched:
                    child[j] = cur[j]
            dJ, child_paired, touched = 0.0, n_paired, []
        T *= cool
        if t in mark_set:
            saved[t] = (best.copy(), time.perf_counter() - start)

    partner = np.full((len(marks), weights.a.shape[0]), -1)
    objective = np.empty(len(marks))
    elapsed = np.empty(len(marks))
    for k, c in enumerate(marks):
        sol, elapsed[k] = saved[c]
        objective[k] = sum(w[r][j] for j, r in enumerate(sol))
        for j, r in enumerate(sol):
            if r:
                if transpose:
                    partner[k, j] = r - 1
                else:
                    partner[k, r - 1] = j
    return PGAResult(checkpoints=np.array(marks), partner1=partner, objective=objective,
                     elapsed_s=elapsed)

"""The plain-Python oracle of the compiled PGA (:mod:`trackfuse.association.pga_search`).

The partheno-genetic algorithm of :mod:`trackfuse.association.pga` on lists, one genetic
operation at a time (:class:`_Search`), with the move operators as functions. The compiled
search repeats it step by step; ``tests/test_pga_kernel.py`` pins the two bit for bit.
"""

from __future__ import annotations

import math
import time
from bisect import bisect_right
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from itertools import accumulate

import numpy as np

from trackfuse.association.assignment import PairWeights
from trackfuse.association.pga import (
    CHECKPOINTS,
    Draws,
    PGAResult,
    collect,
    draw_blocks,
    initial_solution,
    orient,
    schedule,
)


def is_feasible(col_row: Sequence[int], m1: int) -> bool:
    """True iff every entry is in 0..m1 and no real row appears twice.

    The operators keep a chromosome feasible by construction (tests/test_pga.py)."""
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


@dataclass(frozen=True)
class _Problem:
    """One assignment problem in PGA form: the smaller set on the rows (``m1 <= m2``).

    ``w[r][j]`` is the gain of row ``r`` (0 = dummy, gain 0) in column ``j``; ``rank[r][j]``
    the roulette weight of column ``j`` when it holds row ``r``.
    """

    w: list[list[float]]
    rank: list[list[int]]
    m1: int
    m2: int
    transpose: bool

    def objective(self, col_row: Sequence[int]) -> float:
        """Sum of pair gains ``J`` of a solution."""
        return sum(self.w[r][j] for j, r in enumerate(col_row))


def _problem(weights: PairWeights, roulette: str) -> _Problem:
    """Setup of the reference search: :func:`orient` as nested lists."""
    w, rank, transpose = orient(weights, roulette)
    return _Problem(w.tolist(), rank.tolist(), rank.shape[0] - 1, rank.shape[1], transpose)


class _Search:
    """The state of one PGA run and its genetic operation (:meth:`operate`).

    ``child`` is the offspring under construction and equals ``cur`` outside an operation;
    moves touch only the columns in ``touched``, so accepting or rejecting an offspring
    copies those columns one way or the other instead of the whole list.
    """

    def __init__(self, problem: _Problem, cur: list[int], p_m: float, second: str,
                 repair_moves: bool, staged: bool, evict: bool, anneal: bool) -> None:
        self.problem, self.p_m, self.staged, self.anneal = problem, p_m, staged, anneal
        self.roulette_second, self.repair_moves, self.evict = second == "roulette", \
            repair_moves, evict
        self.cur, self.J, self.n_paired = cur, problem.objective(cur), problem.m1
        self.q = [problem.rank[r][j] for j, r in enumerate(cur)]  # roulette weights
        self.cum, self.stale = list(accumulate(self.q)), False  # cumulative roulette weights
        self.best, self.J_best = cur.copy(), self.J
        self.child, self.dJ, self.child_paired = cur.copy(), 0.0, self.n_paired
        self.touched: list[int] = []
        self.T = 1.0  # annealing temperature, set by the caller

    def operate(self, d: Draws) -> None:
        """One genetic operation: crossover, mutation, evaluation (staged or joint)."""
        m1, m2 = self.problem.m1, self.problem.m2
        if m2 >= 2:
            self._crossover(d.first_column, d.second_column)
            if self.staged:
                self._evaluate(d.accept_crossover)
        if m1 and d.mutate < self.p_m:
            self._mutate(d)
        self._evaluate(d.accept_mutation)

    def _crossover(self, u1: float, u2: float) -> None:
        """Roulette column pair (second by roulette over the rest, or uniform), then swap."""
        q, m2 = self.q, self.problem.m2
        if self.stale:
            self.cum, self.stale = list(accumulate(q)), False
        cum = self.cum
        j1 = min(bisect_right(cum, u1 * cum[-1]), m2 - 1)
        if self.roulette_second:
            # roulette over the columns other than j1 (their running sum skips q[j1])
            x, q1 = u2 * (cum[-1] - q[j1]), q[j1]
            j2 = bisect_right(cum, x, 0, j1)
            if j2 == j1:
                j2 = bisect_right(cum, x, j1 + 1, m2, key=lambda c: c - q1)
                if j2 == m2:
                    j2 = m2 - 1 if j1 < m2 - 1 else m2 - 2
        else:
            j2 = int(u2 * (m2 - 1))
            j2 += j2 >= j1
        self.dJ += swap_columns(self.child, self.problem.w, j1, j2)
        self.touched += [j1, j2]

    def _mutate(self, d: Draws) -> None:
        """Re-pair (plain or evicting) with probability 1/2 when enabled, else unpair."""
        child, w, m1, m2 = self.child, self.problem.w, self.problem.m1, self.problem.m2
        if self.repair_moves and d.repair < 0.5 and self.child_paired < m1:
            free = sorted(set(range(1, m1 + 1)).difference(child))
            r = free[int(d.pick * len(free))]
            if self.evict and d.place < 0.5:
                c = int(2.0 * d.place * m2)
                self.child_paired += child[c] == 0
                self.dJ += exchange(child, w, r, c)
            else:
                empty = [j for j, row in enumerate(child) if row == 0]
                c = empty[int((2.0 * d.place - 1.0 if self.evict else d.place) * len(empty))]
                self.dJ += repair(child, w, r, c)
                self.child_paired += 1
            self.touched.append(c)
        elif self.child_paired:
            paired = [j for j, row in enumerate(child) if row]
            c = paired[int(d.pick * len(paired))]
            self.dJ += unpair(child, w, c)
            self.child_paired -= 1
            self.touched.append(c)

    def _evaluate(self, u_accept: float) -> None:
        """Accept (monotone, or Metropolis at temperature ``T``) or reject the offspring."""
        if not self.touched:
            return
        dJ, cur, child = self.dJ, self.cur, self.child
        if dJ >= 0.0 or (self.anneal and u_accept < math.exp(dJ / self.T)):
            self.J, self.n_paired = self.J + dJ, self.child_paired
            rank, q = self.problem.rank, self.q
            for j in self.touched:
                cur[j] = child[j]
                q[j] = rank[cur[j]][j]
            self.stale = True
            if self.J_best < self.J:
                self.best, self.J_best = cur.copy(), self.J
        else:
            for j in self.touched:
                child[j] = cur[j]
        self.dJ, self.child_paired, self.touched = 0.0, self.n_paired, []


def _draws(rng: np.random.Generator, ops: int) -> Iterator[Draws]:
    """The :class:`Draws` of operations ``1..ops`` (:func:`draw_blocks`)."""
    for block in draw_blocks(rng, ops):
        yield from map(Draws._make, block.tolist())


def pga(weights: PairWeights, rng: np.random.Generator, ops: int = 1000,
        checkpoints: Sequence[int] = CHECKPOINTS, p_m: float = 0.2, init: str = "random_B",
        roulette: str = "worse", second: str = "roulette", repair_moves: bool = False,
        staged: bool = False, evict: bool = False, accept: str = "monotone", t0: float = 1.0,
        t1: float = 0.01) -> PGAResult:
    """The (improved) partheno-genetic algorithm on one assignment problem in plain Python:
    the oracle of :func:`trackfuse.association.pga_search.pga`, whose docstring gives the
    parameters (the same here)."""
    start = time.perf_counter()
    problem = _problem(weights, roulette)
    marks, anneal, cool = schedule(ops, checkpoints, accept, second, t0, t1)
    search = _Search(problem, initial_solution(problem.m1, problem.m2, init, rng), p_m,
                     second, repair_moves, staged, evict, anneal)
    saved: dict[int, tuple[list[int], float]] = {}  # checkpoint -> (best, elapsed s)
    if 0 in marks:
        saved[0] = (search.best.copy(), time.perf_counter() - start)
    search.T = t0
    for t, draws in enumerate(_draws(rng, ops), start=1):
        search.operate(draws)
        search.T *= cool
        if t in marks:
            saved[t] = (search.best.copy(), time.perf_counter() - start)
    return collect(saved, problem.objective, problem.transpose, weights.a.shape[0])

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
* re-pair (our improvement, ``repair_moves=True``): with probability 1/2 the mutation instead
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

Random numbers: each operation draws eight uniforms in one row (:class:`Draws`, drawn in
blocks of rows so memory stays bounded and the stream does not depend on the block size),
each with one job. ``place`` serves two decisions under ``evict``: ``place < 1/2`` picks the
evicting re-pair and the position within the chosen column list is ``2 place`` (or
``2 place - 1``), which is again uniform on [0, 1) given that choice and independent of it,
so one uniform is split into a fair coin and a position without bias.

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
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from itertools import accumulate
from typing import NamedTuple

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
    """True iff every entry is in 0..m1 and no real row appears twice.

    The tests' reference (tests/test_pga.py): the operators keep a chromosome feasible by
    construction, so the package itself never calls it."""
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


class Draws(NamedTuple):
    """The eight uniforms on [0, 1) of one genetic operation, in stream order."""

    first_column: float  # roulette position of the first crossover column
    second_column: float  # roulette (or uniform) position of the second crossover column
    mutate: float  # the operation mutates iff mutate < p_m
    repair: float  # re-pair (if enabled and a row is unpaired) iff repair < 1/2, else unpair
    pick: float  # which unpaired row is re-paired, or which paired column is unpaired
    place: float  # the column of a re-pair (with evict: < 1/2 evicting, see module doc)
    accept_crossover: float  # Metropolis draw for the crossover offspring (staged)
    accept_mutation: float  # Metropolis draw for the (mutation or joint) offspring


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


def column_ranks(a: np.ndarray, a_0j: np.ndarray) -> np.ndarray:
    """Descending rank (1 = largest) of each entry within its column of ``[a_0j; a]``.

    a : (m1, m2), a_0j : (m2,). Returns (m1+1, m2) ints; ties keep row order.
    """
    full = np.vstack([a_0j[None, :], a])
    order = np.argsort(-full, axis=0, kind="stable")
    ranks = np.empty_like(order)
    np.put_along_axis(ranks, order, np.arange(1, full.shape[0] + 1)[:, None], axis=0)
    return ranks


class Oriented(NamedTuple):
    """One assignment problem in PGA form as arrays, the smaller set on the rows."""

    w: np.ndarray  # (m1+1, m2) float gains, row 0 (the dummy) zero
    rank: np.ndarray  # (m1+1, m2) int roulette weight of column j when it holds row r
    transpose: bool  # rows are the caller's sensor-2 measurements


def orient(weights: PairWeights, roulette: str) -> Oriented:
    """Setup: orient the problem (rows = the smaller set), gains and roulette weights."""
    transpose = weights.a.shape[0] > weights.a.shape[1]
    a, a_0j = (weights.a.T, weights.a_i0) if transpose else (weights.a, weights.a_0j)
    gain = weights.gain.T if transpose else weights.gain
    m1, m2 = a.shape
    rank = column_ranks(a, a_0j)
    if roulette == "better":
        rank = m1 + 2 - rank
    elif roulette != "worse":
        raise ValueError(f"unknown roulette direction {roulette!r}")
    w = np.ascontiguousarray(np.vstack([np.zeros((1, m2)), gain]), dtype=np.float64)
    return Oriented(w, rank.astype(np.int64, copy=False), transpose)


def _problem(weights: PairWeights, roulette: str) -> _Problem:
    """Setup of the reference search: :func:`orient` as nested lists."""
    w, rank, transpose = orient(weights, roulette)
    return _Problem(w.tolist(), rank.tolist(), rank.shape[0] - 1, rank.shape[1], transpose)


def initial_solution(m1: int, m2: int, init: str, rng: np.random.Generator) -> list[int]:
    """Setup: the initial solution ``col_row`` (module docstring)."""
    cur = [0] * m2
    if init == "random_B":
        for r, j in enumerate(rng.permutation(m2)[:m1].tolist(), start=1):
            cur[j] = r
    elif init == "standard":
        cur[:m1] = range(1, m1 + 1)
    else:
        raise ValueError(f"unknown init {init!r}")
    return cur


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


class Schedule(NamedTuple):
    """When a run records its best solution and how it accepts: ``marks`` the operation
    counts of the checkpoints (``ops`` always one), ``anneal`` Metropolis acceptance,
    ``cool`` the temperature factor per operation (1 without annealing)."""

    marks: set[int]
    anneal: bool
    cool: float


def schedule(ops: int, checkpoints: Sequence[int], accept: str, second: str, t0: float,
             t1: float) -> Schedule:
    """The :class:`Schedule` of a run of ``ops`` operations; ``ValueError`` for an unknown
    ``accept`` or ``second`` option (see :func:`pga`)."""
    if accept not in ("monotone", "anneal"):
        raise ValueError(f"unknown acceptance {accept!r}")
    if second not in ("roulette", "uniform"):
        raise ValueError(f"unknown second-column rule {second!r}")
    anneal = accept == "anneal"
    return Schedule({int(c) for c in checkpoints if 0 <= c <= ops} | {ops}, anneal,
                    (t1 / t0) ** (1.0 / max(ops, 1)) if anneal else 1.0)


def draw_blocks(rng: np.random.Generator, ops: int) -> Iterator[np.ndarray]:
    """The uniforms of operations ``1..ops`` in blocks of at most ``_BLOCK`` rows, each
    ``(rows, 8)`` with the columns of :class:`Draws`."""
    for first in range(0, ops, _BLOCK):
        yield rng.random((min(_BLOCK, ops - first), 8))


def _draws(rng: np.random.Generator, ops: int) -> Iterator[Draws]:
    """The :class:`Draws` of operations ``1..ops`` (:func:`draw_blocks`)."""
    for block in draw_blocks(rng, ops):
        yield from map(Draws._make, block.tolist())


def collect(saved: dict[int, tuple[list[int], float]], objective: Callable[[list[int]], float],
            transpose: bool, rows: int) -> PGAResult:
    """Collection: checkpointed solutions (checkpoint -> (``col_row``, elapsed s)), scored
    by ``objective``, back in the caller's orientation (``rows`` = sensor-1 count)."""
    marks = sorted(saved)
    partner = np.full((len(marks), rows), -1)
    objective_at = np.empty(len(marks))
    elapsed = np.empty(len(marks))
    for k, c in enumerate(marks):
        sol, elapsed[k] = saved[c]
        objective_at[k] = objective(sol)
        for j, r in enumerate(sol):
            if r:
                if transpose:
                    partner[k, j] = r - 1
                else:
                    partner[k, r - 1] = j
    return PGAResult(checkpoints=np.array(marks), partner1=partner, objective=objective_at,
                     elapsed_s=elapsed)


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

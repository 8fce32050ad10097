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

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
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

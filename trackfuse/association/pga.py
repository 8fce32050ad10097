"""Improved partheno-genetic algorithm (PGA) of paper 002 for the two-sensor assignment.

The solution is the 0/1 matrix ``X`` of size (m1+1) x (m2+1) with dummy row and column 0,
the smaller measurement set on the rows, stored as ``col_row`` (length m2, ``col_row[j]`` in
``{0 (dummy), 1..m1}``). Its objective ``J = sum_j w[col_row[j]][j]`` (``w[0][j] = 0``,
:mod:`trackfuse.association.assignment`) changes by the gains of the two or three columns a
move touches, so each move is evaluated in O(1). One genetic operation = crossover, then
mutation with probability ``p_m``, then evaluation; the operators (crossover, unpairing
mutation, re-pair, evicting re-pair), staged evaluation and the acceptance rules
(``monotone``, ``anneal``) are in ``docs/papers/passive_assoc.md``, "Partheno-genetic
algorithm" and W002-2. The best solution is recorded at each checkpoint of the operation
count (Fig. 2's x-axis); the budget ``ops`` is always a checkpoint.

References: Liu H., Dou L., Xin B., Dong L., Control and Decision 23(4), 2008, sec. 3; Li M. J.,
Tong T. S., Acta Automatica Sinica 25(1), 1999; Rudolph G., IEEE Trans. Neural Networks 5(1),
1994; Kirkpatrick S. et al., Science 220, 1983.
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

    Attributes: ``checkpoints`` (C,) operation counts. ``partner1`` (C, m1) sensor-2 partner of each
    sensor-1 measurement, -1 for the dummy. ``objective`` (C,) sum of pair gains of the best
    solution. ``elapsed_s`` (C,) wall time from the start of the run, s."""

    checkpoints: np.ndarray
    partner1: np.ndarray
    objective: np.ndarray
    elapsed_s: np.ndarray


class Draws(NamedTuple):
    """The eight uniforms on [0, 1) of one genetic operation, in stream order (drawn in
    blocks of rows: memory stays bounded and the stream does not depend on the block size).
    Under ``evict``, ``place < 1/2`` picks the evicting re-pair and ``2 place`` (or
    ``2 place - 1``), again uniform and independent of that choice, the position."""

    first_column: float  # roulette position of the first crossover column
    second_column: float  # roulette (or uniform) position of the second crossover column
    mutate: float  # the operation mutates iff mutate < p_m
    repair: float  # re-pair (if enabled and a row is unpaired) iff repair < 1/2, else unpair
    pick: float  # which unpaired row is re-paired, or which paired column is unpaired
    place: float  # the column of a re-pair (with evict: < 1/2 evicting, see above)
    accept_crossover: float  # Metropolis draw for the crossover offspring (staged)
    accept_mutation: float  # Metropolis draw for the (mutation or joint) offspring


def column_ranks(a: np.ndarray, a_0j: np.ndarray) -> np.ndarray:
    """Descending rank (1 = largest) of each entry within its column of ``[a_0j; a]``.

    a : (m1, m2), a_0j : (m2,). Returns (m1+1, m2) ints; ties keep row order."""
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

"""Improved partheno-genetic algorithm (PGA) of paper 002 for the two-sensor assignment.

A solution is ``col_row`` (m2,), ``col_row[j]`` in ``{0 (dummy), 1..m1}``, the smaller set on
the rows; ``J = sum_j w[col_row[j]][j]`` changes only in the columns a move touches, so each
move costs O(1). Operators, evaluation and acceptance rules: ``docs/papers/passive_assoc.md``,
"Partheno-genetic algorithm" and W002-2. The search itself is :mod:`.pga_search`.

References: Liu H., Dou L., Xin B., Dong L., Control and Decision 23(4), 2008, sec. 3; Li M. J.,
Tong T. S., Acta Automatica Sinica 25(1), 1999; Rudolph G., IEEE Trans. Neural Networks 5(1),
1994; Kirkpatrick S. et al., Science 220, 1983."""

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
    """Best solutions at each checkpoint: ``checkpoints`` (C,) operation counts, ``partner1``
    (C, m1) (-1: dummy), ``objective`` (C,) summed pair gains, ``elapsed_s`` (C,) wall seconds."""

    checkpoints: np.ndarray
    partner1: np.ndarray
    objective: np.ndarray
    elapsed_s: np.ndarray


class Draws(NamedTuple):
    """The eight uniforms on [0, 1) of one operation, in stream order (drawn in blocks; the stream
    does not depend on the block size). Under ``evict``, ``place < 1/2`` picks the evicting
    re-pair and ``2 place`` (mod 1) the position."""

    first_column: float  # roulette position of the first crossover column
    second_column: float  # roulette (or uniform) position of the second crossover column
    mutate: float  # the operation mutates iff mutate < p_m
    repair: float  # re-pair (if enabled and a row is unpaired) iff repair < 1/2, else unpair
    pick: float  # which unpaired row is re-paired, or which paired column is unpaired
    place: float  # the column of a re-pair (with evict: < 1/2 evicting, see above)
    accept_crossover: float  # Metropolis draw for the crossover offspring (staged)
    accept_mutation: float  # Metropolis draw for the (mutation or joint) offspring


def column_ranks(a: np.ndarray, a_0j: np.ndarray) -> np.ndarray:
    """Descending rank (1 = largest) in each column of ``[a_0j; a]``: (m1+1, m2), ties by row."""
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
    """Setup: the initial ``col_row``, ``random_B`` or ``standard`` (paper 002 eq. 31)."""
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
    """Checkpoint ``marks`` (``ops`` always one), Metropolis ``anneal``, and ``cool``, the
    temperature factor per operation (1 without annealing)."""

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
    """Uniforms of operations ``1..ops`` in blocks (rows, 8), columns as :class:`Draws`."""
    for first in range(0, ops, _BLOCK):
        yield rng.random((min(_BLOCK, ops - first), 8))


def collect(saved: dict[int, tuple[list[int], float]], objective: Callable[[list[int]], float],
            transpose: bool, rows: int) -> PGAResult:
    """Checkpointed ``col_row`` scored by ``objective``, back in the caller's orientation."""
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

"""Clutter nested across clutter levels: a lower level's false returns are a subset of a
higher level's in the same trial, and every level keeps its exact Poisson law.

Each clutter cell (one sensor at one scan) carries a unit-rate Poisson process on the axis
of the mean number of false returns ``lambda``: arrival ``j`` of a cell sits at
``E_1 + ... + E_j`` with ``E_i ~ Exp(1)`` independent, and brings its own position
uniforms. Level ``lambda`` keeps the arrivals below ``lambda``: their number is
``Poisson(lambda)`` and, given the number, their positions are independent uniforms, so each
level is the clutter of its own Poisson law; a higher level only adds arrivals. Sweep points
that differ in ``clutter.mean`` therefore share most of their returns, and a level's
returns depend only on the trial's stream and that level, not on the sweep's other points
(no largest level needs to be known, and drawing costs what the level itself needs).

The stream is read in rounds: round ``r`` draws ``(cells, 3)`` uniforms, for every cell
the gap to its next arrival (``-log u``) and that arrival's two position uniforms. Rounds
are drawn in blocks until every cell's last arrival lies above ``lambda``; a block of ``b``
rounds reads the same numbers as ``b`` single rounds, so round ``r``'s draws do not depend
on the block size or on ``lambda``.
"""

from __future__ import annotations

import numpy as np


def nested_poisson(rng: np.random.Generator, mean: float,
                   cells: int) -> tuple[np.ndarray, np.ndarray]:
    """False-return counts ``(cells,)`` int, each ``Poisson(mean)``, and the two position
    uniforms on ``[0, 1)`` of every return, ``(2, total)``, cell-major then in arrival order
    (see the module docstring). ``mean`` is the mean number of returns per cell (>= 0).

    Arrival ``j`` lies below ``mean`` when the product of the first ``j`` gap
    uniforms is above ``exp(-mean)`` (the gaps ``-log u`` are ``Exp(1)``)."""
    if mean <= 0.0:  # no arrival and nothing drawn (so read the clutter last from a stream)
        return np.zeros(cells, dtype=np.int64), np.empty((2, 0))
    floor = np.exp(-mean)
    block = int(mean + 4.0 * np.sqrt(mean)) + 2  # one block suffices almost always
    rounds = rng.random((block, cells, 3))
    kept = np.cumprod(rounds[..., 0], axis=0) > floor  # (rounds, cells): a prefix per cell
    while kept[-1].any():
        rounds = np.concatenate([rounds, rng.random((block, cells, 3))])
        kept = np.cumprod(rounds[..., 0], axis=0) > floor
    where = np.nonzero(kept.T)  # (cell, round) of every return, cell-major
    return np.bincount(where[0], minlength=cells), rounds[where[1], where[0], 1:].T

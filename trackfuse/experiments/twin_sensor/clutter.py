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

Each trial's stream is read in rounds: round ``r`` draws ``(cells, 3)`` uniforms, for every
cell the gap to its next arrival (``-log u``) and that arrival's two position uniforms.
Rounds are drawn in blocks until every cell's last arrival lies above ``lambda``; a block of
``b`` rounds reads the same numbers as ``b`` single rounds, so round ``r``'s draws do not
depend on the block size, on ``lambda`` or on the other trials of the batch.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def nested_poisson(rngs: Sequence[np.random.Generator], mean: float, cells: int,
                   wanted: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """False-return counts ``(N, cells)`` int, each ``Poisson(mean)``, and the two position
    uniforms on ``[0, 1)`` of every return, ``(2, total)``, trial-, cell-major then in
    arrival order, for ``N`` trials each drawing from its own generator of ``rngs`` (see
    the module docstring). ``mean`` is the mean number of returns per cell (>= 0); nothing
    is drawn at 0, so read the clutter last from a stream. ``wanted: (cells,)`` bool, if
    given: the cells whose returns are kept (the others are drawn alike, and count 0).

    Arrival ``j`` lies below ``mean`` when the product of the first ``j`` gap uniforms is
    above ``exp(-mean)`` (the gaps ``-log u`` are ``Exp(1)``)."""
    if mean <= 0.0:
        return np.zeros((len(rngs), cells), dtype=np.int64), np.empty((2, 0))
    block = int(mean + 4.0 * np.sqrt(mean)) + 2  # one block suffices almost always
    rounds = np.empty((len(rngs), block, cells, 3))
    for n, rng in enumerate(rngs):
        rng.random(out=rounds[n])
    counts, uniforms = _arrivals(rounds, mean, wanted)
    longer = {}
    for n in np.flatnonzero(counts.max(axis=1) >= block):  # a cell may have more arrivals
        drawn = rounds[n]
        while (np.cumprod(drawn[..., 0], axis=0)[-1] > np.exp(-mean)).any():
            drawn = np.concatenate([drawn, rngs[n].random((block, cells, 3))])
        longer[n] = _arrivals(drawn[None], mean, wanted)
    if longer:  # replace those trials' returns, in trial order
        pieces = np.split(uniforms, np.cumsum(counts.sum(axis=1))[:-1], axis=1)
        for n, (trial_counts, trial_uniforms) in longer.items():
            counts[n], pieces[n] = trial_counts[0], trial_uniforms
        uniforms = np.concatenate(pieces, axis=1)
    return counts, uniforms


def _arrivals(rounds: np.ndarray, mean: float,
              wanted: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Counts ``(N, cells)`` and uniforms ``(2, total)`` (trial-, cell-major, in arrival
    order) of the arrivals below ``mean`` in ``rounds: (N, R, cells, 3)``, in the
    ``wanted`` cells (every cell if ``None``): those whose product of gap uniforms, from
    the first round on, is above ``exp(-mean)``."""
    N, R, cells, _ = rounds.shape
    product = rounds[..., 0].copy()  # (N, R, cells); a loop over rounds beats cumprod here
    for r in range(1, R):
        product[:, r] *= product[:, r - 1]
    kept = product > np.exp(-mean)  # a prefix of the rounds in each cell
    if wanted is not None:
        kept &= wanted
    trial, cell, arrival = np.nonzero(kept.transpose(0, 2, 1))
    rows = (trial * R + arrival) * cells + cell  # of rounds as (N * R * cells, 3)
    return kept.sum(axis=1), np.take(rounds.reshape(-1, 3), rows, axis=0)[:, 1:].T

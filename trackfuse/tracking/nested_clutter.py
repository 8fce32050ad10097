"""Clutter nested across clutter levels: a lower level's false returns are a subset of a higher
level's in the same trial, each level exactly ``Poisson(lambda)`` with uniform positions
(``docs/papers/twin_sensor.md``, "Clutter nested across levels").

Each cell (one sensor at one scan) is a unit-rate Poisson process along ``lambda``; round
``r`` of a trial's stream draws ``(cells, 3)`` uniforms: the gap ``-log u`` to each cell's
next arrival and its two position uniforms. Rounds are drawn in blocks until every cell's
last arrival passes ``lambda``; round ``r``'s draws depend neither on the block size nor on
``lambda``."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit

from trackfuse.spawned_streams import Stream, drawing
from trackfuse.tracking.pda import JIT


def nested_poisson(rngs: Sequence[Stream], mean: float, cells: int,
                   wanted: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Counts ``(N, cells)`` int, each ``Poisson(mean)``, and position uniforms ``(2, total)`` on
    ``[0, 1)`` (trial-, cell-major, then arrival order), each trial from its generator in
    ``rngs``; arrival ``j`` is kept when the product of its ``j`` gap uniforms is above
    ``exp(-mean)``. Nothing is drawn at ``mean`` 0, so draw the clutter last from a stream.
    ``wanted`` (cells,) bool keeps the returns of those cells only (the others count 0)."""
    if mean <= 0.0:
        return np.zeros((len(rngs), cells), dtype=np.int64), np.empty((2, 0))
    block = int(mean + 4.0 * np.sqrt(mean)) + 2  # one block suffices almost always
    rounds = np.empty((len(rngs), block, cells, 3))
    for n, stream in enumerate(rngs):
        with drawing(stream) as rng:
            rng.random(out=rounds[n])
    counts, uniforms = _arrivals(rounds, mean, wanted)
    longer = {}
    for n in np.flatnonzero(counts.max(axis=1) >= block):  # a cell may have more arrivals
        drawn = rounds[n]
        while (np.cumprod(drawn[..., 0], axis=0)[-1] > np.exp(-mean)).any():
            with drawing(rngs[n]) as rng:
                drawn = np.concatenate([drawn, rng.random((block, cells, 3))])
        longer[n] = _arrivals(drawn[None], mean, wanted)
    if longer:  # replace those trials' returns, in trial order
        pieces = np.split(uniforms, np.cumsum(counts.sum(axis=1))[:-1], axis=1)
        for n, (trial_counts, trial_uniforms) in longer.items():
            counts[n], pieces[n] = trial_counts[0], trial_uniforms
        uniforms = np.concatenate(pieces, axis=1)
    return counts, uniforms


def _arrivals(rounds: np.ndarray, mean: float,
              wanted: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Counts ``(N, cells)`` and uniforms ``(2, total)`` of the arrivals below ``mean`` in
    ``rounds`` (N, R, cells, 3), in the ``wanted`` cells (all if ``None``)."""
    cells = rounds.shape[2]
    wanted = np.ones(cells, dtype=np.bool_) if wanted is None else wanted
    return kept_arrivals(rounds, float(np.exp(-mean)), wanted)


@njit(**JIT)
def kept_arrivals(rounds: np.ndarray, threshold: float,
                  wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Counts ``(N, cells)`` and position uniforms ``(2, total)`` (trial-, cell-major, then
    arrival order) of the arrivals of ``rounds`` (N, R, cells, 3) whose product of gap
    uniforms, taken in round order, is above ``threshold``, in the ``wanted`` (cells,) cells."""
    N, R, cells, _ = rounds.shape
    counts = np.zeros((N, cells), dtype=np.int64)
    for n in range(N):
        for c in range(cells):
            if wanted[c]:
                product, r = rounds[n, 0, c, 0], 0
                while r < R and product > threshold:
                    r += 1
                    if r < R:
                        product = rounds[n, r, c, 0] * product
                counts[n, c] = r
    uniforms = np.empty((2, counts.sum()))
    i = 0
    for n in range(N):
        for c in range(cells):
            for r in range(counts[n, c]):
                uniforms[0, i], uniforms[1, i] = rounds[n, r, c, 1], rounds[n, r, c, 2]
                i += 1
    return counts, uniforms

"""Clutter nested across clutter levels: a lower level's false returns are a subset of a higher
level's in the same trial, each level exactly ``Poisson(lambda)`` with uniform positions
(``docs/papers/twin_sensor.md``, "Clutter nested across levels").

Each cell (one sensor at one scan) is a unit-rate Poisson process along ``lambda``; round
``r`` of a trial's stream draws ``(cells, 3)`` uniforms: the gap ``-log u`` to each cell's
next arrival and its two position uniforms. Rounds are drawn in blocks until every cell's
last arrival passes ``lambda``; round ``r``'s draws depend neither on the block size nor on
``lambda``."""

from __future__ import annotations

import numpy as np
from numba import njit

from trackfuse.tracking.pda import JIT

TWO_PI = 2.0 * np.pi


def first_rounds(mean: float) -> int:
    """Rounds drawn at once for clutter level ``mean``: enough for every cell almost always
    (0 at ``mean`` 0, which draws nothing)."""
    return int(mean + 4.0 * np.sqrt(mean)) + 2 if mean > 0.0 else 0


class NestedClutter:
    """The nested clutter of ``trials`` trials of ``cells`` cells at level ``mean``, drawn
    trial by trial (:meth:`draw`) through one reused block of rounds: ``counts`` ``(trials,
    cells)`` int, each ``Poisson(mean)``, and :meth:`uniforms`, the kept arrivals' position
    uniforms. Arrival ``j`` is kept when the product of its ``j`` gap uniforms is above
    ``exp(-mean)``; ``wanted`` (cells,) bool keeps the returns of those cells only (the others
    count 0)."""

    def __init__(self, mean: float, trials: int, cells: int, wanted: np.ndarray | None = None):
        self.counts = np.zeros((trials, cells), dtype=np.int64)
        self._threshold = float(np.exp(-mean))
        self._block = np.empty((first_rounds(mean), cells, 3))
        self._wanted = np.ones(cells, dtype=np.bool_) if wanted is None else wanted
        self._uniforms: list[np.ndarray] = []

    def draw(self, trial: int, rng: np.random.Generator) -> None:
        """Draw ``trial``'s clutter from ``rng``, its stream (nothing at ``mean`` 0, so draw the
        clutter last from a stream)."""
        if not self._block.size:
            return
        drawn = rng.random(out=self._block)
        uniforms, complete = kept_arrivals(drawn, self._threshold, self._wanted,
                                           self.counts[trial])
        while not complete:  # a cell may have more arrivals: draw on (rare)
            drawn = np.concatenate([drawn, rng.random(self._block.shape)])
            uniforms, complete = kept_arrivals(drawn, self._threshold, self._wanted,
                                               self.counts[trial])
        self._uniforms.append(uniforms)

    def uniforms(self) -> np.ndarray:
        """Position uniforms ``(2, total)`` on ``[0, 1)`` of the kept arrivals (trial-,
        cell-major, then arrival order)."""
        return np.concatenate(self._uniforms, axis=1) if self._uniforms else np.empty((2, 0))


@njit(**JIT)
def kept_arrivals(rounds: np.ndarray, threshold: float, wanted: np.ndarray,
                  counts: np.ndarray) -> tuple[np.ndarray, bool]:
    """Position uniforms ``(2, total)`` (cell-major, then arrival order) of the arrivals of
    ``rounds`` (R, cells, 3) whose product of gap uniforms, taken in round order, is above
    ``threshold``, in the ``wanted`` (cells,) cells; their number per cell goes to
    ``counts`` (cells,). False if a cell's arrivals may go on past round R."""
    R, cells, _ = rounds.shape
    complete = True
    for c in range(cells):
        r = 0
        if wanted[c]:
            product = rounds[0, c, 0]
            while r < R and product > threshold:
                r += 1
                if r < R:
                    product = rounds[r, c, 0] * product
        counts[c] = r
        complete = complete and r < R
    uniforms = np.empty((2, counts.sum()))
    i = 0
    for c in range(cells):
        for r in range(counts[c]):
            uniforms[0, i], uniforms[1, i] = rounds[r, c, 1], rounds[r, c, 2]
            i += 1
    return uniforms, complete


def padded_disk_points(counts: np.ndarray, uniforms: np.ndarray,
                       slots: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit-disk points ``(N, K, S, slots, 2)`` and their validity ``(N, K, S, slots)`` of
    cells with ``counts`` (N, K, S) returns from the uniforms ``(2, total)`` behind them
    (trial-, scan-, sensor-major, as :class:`NestedClutter` gives them): radius
    ``sqrt(u0)``, angle ``2 pi u1`` (numpy's ``disk_points`` in ``tests/pda_reference.py``,
    the same arithmetic); zero where not valid. Allocated by numpy, whose large arrays get
    huge pages where the system allows (far fewer page faults than compiled code's)."""
    points = np.zeros(counts.shape + (slots, 2))
    valid = np.zeros(counts.shape + (slots,), dtype=np.bool_)
    place_disk_points(counts, uniforms, points, valid)
    return points, valid


@njit(**JIT)
def place_disk_points(counts: np.ndarray, uniforms: np.ndarray, points: np.ndarray,
                      valid: np.ndarray) -> None:
    """Fill :func:`padded_disk_points`'s zeroed ``points`` and ``valid``."""
    N, K, S = counts.shape
    i = 0
    for n in range(N):
        for k in range(K):
            for s in range(S):
                for j in range(counts[n, k, s]):
                    radius, angle = np.sqrt(uniforms[0, i]), TWO_PI * uniforms[1, i]
                    points[n, k, s, j, 0] = radius * np.cos(angle)
                    points[n, k, s, j, 1] = radius * np.sin(angle)
                    valid[n, k, s, j] = True
                    i += 1

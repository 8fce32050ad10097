"""The one seeding rule: which random numbers a Monte Carlo trial sees.

Each trial gets two PCG64 generators, told apart by the ``spawn_key`` of a
:class:`numpy.random.SeedSequence` (domain 0 or 1), so no stream can equal another:

* ``common``, of (root seed, trial): the same at every sweep point (common random numbers),
  for truth, initial estimate, measurement noise and algorithm randomness;
* ``point``, of (root seed, trial, draw point): what a swept parameter changes, such as the
  clutter. Points that differ only in ``Param(draws=False)`` keys share a draw point.

Nothing else (worker, executor, batch, order) enters, so every schedule writes the same
numbers. Domain 2 seeds numpy's global generator before each trial
(:func:`seed_numpy_global`). See ``docs/runner.md`` (seeding).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # only for annotations: workers load no sweep parsing
    from trackfuse.sweep import SweepPoint

_COMMON, _POINT, _GLOBAL = 0, 1, 2


@dataclass(frozen=True)
class TrialStreams:
    """The random streams of one trial (see the module docstring)."""

    common: np.random.Generator
    point: np.random.Generator


def draw_points(points: Sequence[SweepPoint], drawing: Collection[str]) -> list[int]:
    """The draw point of every sweep point, in point order: the index of the first point
    whose values of the swept keys in ``drawing`` (the parameters that change what is
    simulated) equal its own. With every swept key drawing, each point is its own."""
    first: dict[tuple[Any, ...], int] = {}
    return [first.setdefault(_hashable([v for k, v in p.values.items() if k in drawing]),
                             p.index) for p in points]


def _hashable(value: Any) -> Any:
    """``value`` with every list made a tuple (a swept value may be a list)."""
    return tuple(map(_hashable, value)) if isinstance(value, (list, tuple)) else value


def trial_streams(seed: int, point: int, trial: int) -> TrialStreams:
    """Streams of trial ``trial`` whose point stream is keyed by sweep point ``point`` (the
    runner passes the point's draw point, :func:`draw_points`) under root seed ``seed``."""
    common = np.random.SeedSequence(seed, spawn_key=(_COMMON, trial))
    specific = np.random.SeedSequence(seed, spawn_key=(_POINT, trial, point))
    return TrialStreams(np.random.default_rng(common), np.random.default_rng(specific))


def seed_numpy_global(seed: int, point: int, trial: int) -> None:
    """Seed numpy's global generator (``np.random.normal`` and the like, which a plugin
    must not use) for trial ``trial`` of draw point ``point``: from a third domain of the
    same seed sequence, so a plugin that uses it anyway draws the same numbers on every
    executor and worker, and neither trial stream is touched."""
    state = np.random.SeedSequence(seed, spawn_key=(_GLOBAL, trial, point)).generate_state(1)
    np.random.seed(int(state[0]))


def batch_streams(seed: int, point: int, trials: range) -> list[TrialStreams]:
    """:func:`trial_streams` for every trial index in ``trials``."""
    return [trial_streams(seed, point, t) for t in trials]

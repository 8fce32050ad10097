"""The one seeding rule (``docs/runner.md``, "Seeding"): each trial gets two PCG64 generators
told apart by ``SeedSequence`` spawn keys, ``common`` of (root seed, trial) and ``point`` of
(root seed, trial, draw point); nothing else (worker, executor, batch, order) enters."""

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
    """The draw point of each sweep point: the first point equal to it in the ``drawing`` keys."""
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
    """Seed numpy's global generator for trial ``trial`` of draw point ``point`` from a third
    domain, so a plugin that uses it draws the same numbers on every executor."""
    state = np.random.SeedSequence(seed, spawn_key=(_GLOBAL, trial, point)).generate_state(1)
    np.random.seed(int(state[0]))


def batch_streams(seed: int, point: int, trials: range) -> list[TrialStreams]:
    """:func:`trial_streams` for every trial index in ``trials``."""
    return [trial_streams(seed, point, t) for t in trials]

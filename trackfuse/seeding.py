"""The one seeding rule (``docs/runner.md``, "Seeding"): each trial gets two PCG64 generators
told apart by ``SeedSequence`` spawn keys, ``common`` of (root seed, trial) and ``point`` of
(root seed, trial, draw point); nothing else (worker, executor, batch, order) enters."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # only for annotations: workers load no sweep parsing
    from trackfuse.sweep import SweepPoint

COMMON_DOMAIN, POINT_DOMAIN, GLOBAL_DOMAIN = 0, 1, 2
"""First spawn-key word of the common, point and numpy-global streams."""


@dataclass(frozen=True)
class TrialStreams:
    """The random streams of trial ``trial`` at draw point ``draw_point`` under root seed
    ``seed`` (see the module docstring); each generator is made when first used."""

    seed: int
    draw_point: int
    trial: int

    @cached_property
    def common(self) -> np.random.Generator:
        """The stream shared by every sweep point of the trial."""
        return np.random.default_rng(np.random.SeedSequence(
            self.seed, spawn_key=(COMMON_DOMAIN, self.trial)))

    @cached_property
    def point(self) -> np.random.Generator:
        """The stream of the trial at its draw point."""
        return np.random.default_rng(np.random.SeedSequence(
            self.seed, spawn_key=(POINT_DOMAIN, self.trial, self.draw_point)))


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
    return TrialStreams(seed, point, trial)


def seed_numpy_global(seed: int, point: int, trial: int) -> None:
    """Seed numpy's global generator for trial ``trial`` of draw point ``point`` from a third
    domain, so a plugin that uses it draws the same numbers on every executor."""
    state = np.random.SeedSequence(seed, spawn_key=(GLOBAL_DOMAIN, trial, point)).generate_state(1)
    np.random.seed(int(state[0]))


def batch_streams(seed: int, point: int, trials: range) -> list[TrialStreams]:
    """:func:`trial_streams` for every trial index in ``trials``."""
    return [trial_streams(seed, point, t) for t in trials]

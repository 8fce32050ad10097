"""The one seeding rule: which random numbers a Monte Carlo trial sees.

Every trial gets two independent generators (``numpy.random.Generator``, PCG64):

* ``common``: a function of (root seed, trial) only. It is the *same* for every point of a
  sweep, so points compare on the same targets and the same measurement noise (common
  random numbers). Experiments draw from it everything the swept parameters do not change
  the distribution of: truth, initial estimate, measurement noise as standard normals to be
  scaled, algorithm randomness.
* ``point``: a function of (root seed, trial, sweep point). Experiments draw from it what a
  swept parameter changes, such as the number and positions of clutter returns.

Neither depends on the worker, the executor, the batch or the order of completion, so any
schedule writes the same numbers. The two are separated by the ``spawn_key`` of a
:class:`numpy.random.SeedSequence` (domain 0 for common, 1 for point), so no (trial, point)
can collide with another trial's common stream. See ``docs/runner.md`` (seeding).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_COMMON, _POINT = 0, 1


@dataclass(frozen=True)
class TrialStreams:
    """The random streams of one trial (see the module docstring)."""

    common: np.random.Generator
    point: np.random.Generator


def trial_streams(seed: int, point: int, trial: int) -> TrialStreams:
    """Streams of trial ``trial`` at sweep point ``point`` under root seed ``seed``."""
    common = np.random.SeedSequence(seed, spawn_key=(_COMMON, trial))
    specific = np.random.SeedSequence(seed, spawn_key=(_POINT, trial, point))
    return TrialStreams(np.random.default_rng(common), np.random.default_rng(specific))


def batch_streams(seed: int, point: int, trials: range) -> list[TrialStreams]:
    """:func:`trial_streams` for every trial index in ``trials``."""
    return [trial_streams(seed, point, t) for t in trials]

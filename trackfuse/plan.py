"""A run's plan, computed from its config alone (nothing is read or written): the run id, the
sweep points, the draw point of each, the batches of each point and the task of each batch.

Trials are cut into batches of ``batch_size`` by trial index alone, and trial ``t`` of point
``p`` draws only from the streams of :func:`trackfuse.seeding.trial_streams` keyed by the
root seed, ``draw_points[p]`` and ``t``; so the numbers depend on neither the executor nor
the order in which batches finish. The batch size is part of the run id: an experiment's
vectorized ``run_batch`` may round the last bits differently for other batch compositions.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import trackfuse
from trackfuse.batch import BatchTask
from trackfuse.config import Config
from trackfuse.results import BatchSpan, run_id
from trackfuse.seeding import draw_points
from trackfuse.sweep import SweepPoint, expand


@dataclass(frozen=True)
class RunPlan:
    """What a config asks to compute, and under which run id."""

    config: Config
    run_id: str
    points: list[SweepPoint]
    draw_points: list[int]  # per sweep point: the point whose streams its trials draw

    @classmethod
    def of(cls, config: Config, code_digest: str, libraries: Mapping[str, Any]) -> RunPlan:
        """The plan of ``config`` run by code ``code_digest`` with ``libraries``' versions."""
        points = expand(config.sweep, config.sweep_mode)
        return cls(config, run_id(config.to_dict(), trackfuse.__version__, code_digest,
                                  dict(libraries)),
                   points, draw_points(points, config.experiment.drawing))

    @property
    def batches_per_point(self) -> int:
        """Batches of a point that runs the most trials the config allows."""
        return math.ceil(self.config.trials / self.config.batch_size)

    def span(self, point: int, batch: int) -> BatchSpan | None:
        """Batch ``batch`` of sweep point ``point``, or ``None`` if the plan has no such batch."""
        if not (0 <= point < len(self.points) and 0 <= batch < self.batches_per_point):
            return None
        size = self.config.batch_size
        first = batch * size
        return BatchSpan(point, batch, first, min(first + size, self.config.trials))

    def spans(self, counts: list[int]) -> Iterator[BatchSpan]:
        """Every batch of ``counts[p]`` trials of each point ``p``, lazily, in output order."""
        for point, count in enumerate(counts):
            for batch in range(math.ceil(count / self.config.batch_size)):
                yield self.span(point, batch)

    def tasks(self, spans: Iterable[BatchSpan]) -> Iterator[BatchTask]:
        """What a worker needs to run each batch of ``spans``."""
        cfg = self.config
        for span in spans:
            swept = self.points[span.point].values
            yield BatchTask(cfg.experiment, {**cfg.params, **swept}, swept, cfg.seed, span,
                            self.draw_points[span.point], cfg.trial_timeout)

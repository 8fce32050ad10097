"""Sequential trial counts (``docs/runner.md``, "Sequential trial counts"): add trials to a
point, at looks fixed in advance, until the 95 % interval of ``metric`` has half-width at
most ``half_width`` in every cell, or ``max`` is reached. Reads only trials ``0 .. n - 1``,
so the result is the same for any executor and resume."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # validating a config loads no pandas
    import pandas as pd


@dataclass(frozen=True)
class SequentialRule:
    """``trials: {min, max, until: {metric, half_width}}`` of a config (validated)."""

    min: int
    max: int
    metric: str
    half_width: float

    def looks(self, batch_size: int) -> list[int]:
        """Counts at which the rule is read: ``min``, doubling in whole batches, to ``max``."""
        def whole(n: int) -> int:
            return min(math.ceil(n / batch_size) * batch_size, self.max)

        found = [whole(self.min)]
        while found[-1] < self.max:
            found.append(whole(2 * found[-1]))
        return found

    def as_config(self) -> dict[str, Any]:
        """The rule as a config spells it (what a run's ``config.yaml`` records)."""
        return {"min": self.min, "max": self.max,
                "until": {"metric": self.metric, "half_width": self.half_width}}

    def words(self) -> str:
        """``until the 95 % interval of correct is within +-0.01 (100 to 20000 trials)``."""
        return (f"until the 95 % interval of {self.metric} is within +-{self.half_width:g} "
                f"in every cell ({self.min} to {self.max} trials per point)")


def widest_half_width(summary: pd.DataFrame, rule: SequentialRule) -> float:
    """The largest ``(ci_high - ci_low) / 2`` of ``rule.metric`` over the cells, or inf."""
    mine = summary[summary["metric"] == rule.metric]
    if mine.empty:
        return math.inf
    widths = (mine["ci_high"].astype(float) - mine["ci_low"].astype(float)) / 2
    return math.inf if widths.isna().any() else float(widths.max())


@dataclass
class SequentialCounts:
    """Where a sequential run stands: the trials planned per point (``counts``) and, for
    each point the rule has stopped, its final count and its widest half-width."""

    rule: SequentialRule
    looks: list[int]
    counts: list[int]
    stopped: dict[int, float]

    @classmethod
    def start(cls, rule: SequentialRule, points: int, batch_size: int) -> SequentialCounts:
        """Every one of ``points`` points at the first look."""
        looks = rule.looks(batch_size)
        return cls(rule, looks, [looks[0]] * points, {})

    @classmethod
    def recorded(cls, rule: SequentialRule, batch_size: int,
                 counts: list[int]) -> SequentialCounts:
        """A finished run's counts as its manifest recorded them (every point stopped)."""
        looks = rule.looks(batch_size)
        return cls(rule, looks, [int(n) for n in counts], dict.fromkeys(range(len(counts)),
                                                                          0.0))

    def open_points(self) -> list[int]:
        """The points the rule has not stopped yet, in order."""
        return [p for p in range(len(self.counts)) if p not in self.stopped]

    @property
    def done(self) -> bool:
        return len(self.stopped) == len(self.counts)

    def decide(self, point: int, width: float) -> None:
        """Stop ``point`` when ``width`` (its widest half-width at its current count) meets
        the rule or the count is ``max``; otherwise plan it for the next look."""
        n = self.counts[point]
        if width <= self.rule.half_width or n >= self.rule.max:
            self.stopped[point] = width
        else:
            self.counts[point] = self.looks[self.looks.index(n) + 1]

    def at_max(self) -> list[int]:
        """The stopped points whose interval is still wider than the rule asks."""
        return [p for p, width in sorted(self.stopped.items())
                if not width <= self.rule.half_width]

    def stopping(self, point: int) -> str:
        """What ``summary.csv``'s ``stopping`` column says of ``point``'s rows."""
        rule = f"sequential: {self.rule.metric} +-{self.rule.half_width:g}"
        if point in self.at_max():
            return f"{rule}, stopped at max {self.rule.max}"
        return f"{rule}, met at {self.counts[point]}"

    def manifest_entry(self) -> dict[str, Any]:
        """The manifest's ``sequential`` record."""
        return {"rule": self.rule.as_config(), "looks": list(self.looks),
                "trials": list(self.counts), "stopped_at_max": self.at_max(),
                "half_width": [_finite_or_none(self.stopped.get(p))
                               for p in range(len(self.counts))]}


def _finite_or_none(value: float | None) -> float | None:
    return round(value, 12) if value is not None and math.isfinite(value) else None

"""Progress of a run: a rich bar on a terminal, plain periodic lines otherwise (CI logs)."""

from __future__ import annotations

import sys
import time

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

PLAIN_EVERY_S = 10.0


class RunProgress:
    """Trials done / total with rate and ETA. Use as a context manager."""

    def __init__(self, total: int, done: int, label: str, enabled: bool = True):
        self.total, self.done, self.label = total, done, label
        self.start_done, self.t0 = done, time.monotonic()
        self._last_print, self._printed = self.t0, -1
        console = Console(stderr=True)
        self._rich = enabled and console.is_terminal
        self._plain = enabled and not self._rich
        if self._rich:
            self._bar = Progress(TextColumn("{task.description}"), BarColumn(),
                                 MofNCompleteColumn(), TaskProgressColumn(),
                                 TextColumn("{task.fields[rate]}"), TimeElapsedColumn(),
                                 TextColumn("ETA"), TimeRemainingColumn(), console=console)
            self._task = self._bar.add_task(escape(label), total=total, completed=done, rate="")

    def __enter__(self) -> RunProgress:
        if self._rich:
            self._bar.start()
        elif self._plain:
            self._line()
        return self

    def __exit__(self, *exc) -> None:
        if self._rich:
            self._bar.stop()
        elif self._plain and self.done != self._printed:
            self._line()

    def rate(self) -> float:
        """Trials per second in this session."""
        return (self.done - self.start_done) / max(time.monotonic() - self.t0, 1e-9)

    def advance(self, trials: int) -> None:
        self.done += trials
        if self._rich:
            self._bar.update(self._task, completed=self.done, rate=f"{self.rate():,.0f} trials/s")
        elif self._plain and time.monotonic() - self._last_print >= PLAIN_EVERY_S:
            self._line()

    def _line(self) -> None:
        self._last_print = time.monotonic()
        self._printed = self.done
        rate = self.rate()
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        pct = 100.0 * self.done / max(self.total, 1)
        print(f"{self.label}: {self.done}/{self.total} trials ({pct:.0f}%), "
              f"{rate:,.0f} trials/s, ETA {eta:,.0f} s", file=sys.stderr, flush=True)
